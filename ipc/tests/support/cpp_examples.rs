//! Builds the C++ example policies of `adapters/cpp` with `make`, against the
//! `libthorarena_ipc.a` cargo built for the running test binary. Shared by the ipc crate's
//! C++ tests and the workspace's end-to-end policy-server tests (`#[path]` include).

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

/// The repository root: the first ancestor of the including crate's manifest directory
/// that holds `adapters/cpp`.
fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .ancestors()
        .find(|d| d.join("adapters/cpp/Makefile").is_file())
        .expect("adapters/cpp above the manifest directory")
        .to_path_buf()
}

fn tool_works(tool: &str) -> bool {
    Command::new(tool)
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success())
}

/// Builds the C++ examples once per test process; `None` when the tools are missing, after
/// recording `test` as skipped (a failure in CI).
pub fn examples(test: &str) -> Option<&'static Path> {
    static BUILT: OnceLock<Result<PathBuf, String>> = OnceLock::new();
    match BUILT.get_or_init(build_examples) {
        Ok(dir) => Some(dir.as_path()),
        Err(reason) => {
            crate::prereq::skip(test, reason);
            None
        }
    }
}

fn build_examples() -> Result<PathBuf, String> {
    let cxx = std::env::var("CXX").unwrap_or_else(|_| "g++".into());
    for tool in ["make", cxx.as_str()] {
        if !tool_works(tool) {
            return Err(format!(
                "`{tool}` is not on this machine, the C++ examples cannot be built \
                 (apt-get install g++ make, or run ./test.sh as root)"
            ));
        }
    }
    // This binary is <target>/<profile>/deps/cpp_client-<hash>; cargo built the library's
    // staticlib next to it (a test build does not copy it up to <target>/<profile>).
    let exe = std::env::current_exe().unwrap();
    let deps = exe.parent().unwrap();
    let profile_dir = deps.parent().unwrap();
    let lib = deps.join("libthorarena_ipc.a");
    assert!(
        lib.exists(),
        "{} is missing: is `staticlib` still in ipc/Cargo.toml's crate-type?",
        lib.display()
    );
    let build_dir = profile_dir.join("cpp-examples");
    let out = Command::new("make")
        .arg("-C")
        .arg(repo_root().join("adapters/cpp"))
        .arg(format!(
            "TARGET_DIR={}",
            profile_dir.parent().unwrap().display()
        ))
        .arg(format!(
            "PROFILE={}",
            profile_dir.file_name().unwrap().to_string_lossy()
        ))
        .arg(format!("LIB_DIR={}", deps.display()))
        .arg(format!("BUILD_DIR={}", build_dir.display()))
        .arg(format!("CXX={cxx}"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "make -C adapters/cpp failed:\n{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    Ok(build_dir)
}
