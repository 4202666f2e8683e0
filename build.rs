//! Compiles the bundled data (`data/`: robots, dynamics profiles, the sample dataset) into
//! the binary, so that an installed `thorarena` works without the checkout it was built
//! from. Writes `$OUT_DIR/embedded_data.rs`: a sorted list of (path relative to `data/`,
//! bytes) that `src/files/embedded_data.rs` extracts on first use.

use std::fmt::Write;
use std::path::{Path, PathBuf};

fn main() {
    mujoco_rpath();
    let root = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").expect("set by cargo"));
    let data = root.join("data");
    println!("cargo:rerun-if-changed=data");
    let mut files = Vec::new();
    collect(&data, &mut files);
    files.sort();
    let mut out = String::from("/// Bundled data files: (path relative to `data/`, contents).\n");
    out += "pub(crate) const FILES: &[(&str, &[u8])] = &[\n";
    for path in &files {
        let rel = path
            .strip_prefix(&data)
            .expect("under data/")
            .to_str()
            .expect("data file names are UTF-8");
        println!("cargo:rerun-if-changed={}", path.display());
        writeln!(
            out,
            "    ({rel:?}, include_bytes!({:?})),",
            path.display().to_string()
        )
        .expect("writing to a String");
    }
    out += "];\n";
    let dest = PathBuf::from(std::env::var_os("OUT_DIR").expect("set by cargo"));
    std::fs::write(dest.join("embedded_data.rs"), out).expect("writing embedded_data.rs");
}

/// Every file under `dir`, recursively (directories are watched by cargo as a whole).
fn collect(dir: &Path, files: &mut Vec<PathBuf>) {
    let entries =
        std::fs::read_dir(dir).unwrap_or_else(|e| panic!("reading {}: {e}", dir.display()));
    for entry in entries {
        let path = entry.expect("directory entry").path();
        if path.is_dir() {
            collect(&path, files);
        } else {
            files.push(path);
        }
    }
}

/// With the `mujoco` feature, the binaries find `libmujoco.so` at run time where they were
/// linked against it (`MUJOCO_DYNAMIC_LINK_DIR`, which `mujoco-rs` requires and which must
/// then also hold `libmujoco.so.3.17.0`, its soname): an rpath, so tests and `cargo run`
/// need no `LD_LIBRARY_PATH`. A missing variable is `mujoco-rs`'s error, which says what to
/// set; ours adds how (README, "MuJoCo backend").
fn mujoco_rpath() {
    // Only a build with the feature depends on the variable: toggling it must not rebuild
    // the plain one.
    if std::env::var_os("CARGO_FEATURE_MUJOCO").is_none() {
        return;
    }
    println!("cargo:rerun-if-env-changed=MUJOCO_DYNAMIC_LINK_DIR");
    match std::env::var("MUJOCO_DYNAMIC_LINK_DIR") {
        Ok(dir) => println!("cargo:rustc-link-arg=-Wl,-rpath,{dir}"),
        Err(_) => println!(
            "cargo:warning=the `mujoco` feature needs MUJOCO_DYNAMIC_LINK_DIR (.cargo/config.toml sets it to target/mujoco-3.17.0/lib): run tools/mujoco-lib.sh once to put the library there"
        ),
    }
}
