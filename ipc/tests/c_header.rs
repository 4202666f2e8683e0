//! The C header `ipc/include/thorarena.h` is what cbindgen makes of `src/ffi.rs` now (no
//! drift), and a C compiler sees the same wire layout as `ipc/layout.json`: a small C
//! program built against the header prints every struct's size, alignment and field
//! offsets, every constant and every status code, and they must equal the layout file's
//! and the Rust ones. The field lookup of the C ABI gives the layout file's example
//! offsets. After a deliberate change of the ABI regenerate the header with
//! `THORARENA_BLESS=1 cargo test -p thorarena-ipc --test c_header`.

use serde_json::Value;
use std::ffi::{c_char, CString};
use std::path::{Path, PathBuf};
use std::process::Command;
use thorarena_ipc::ffi::{thorarena_layout_env_field, ThorarenaStatus};

#[path = "../../tests/prereq/mod.rs"]
mod prereq;

fn crate_dir() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn header_path() -> PathBuf {
    crate_dir().join("include").join("thorarena.h")
}

fn layout_json() -> Value {
    let text = std::fs::read_to_string(crate_dir().join("layout.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

/// The header as cbindgen generates it from this crate's sources now.
fn generated_header() -> String {
    let config = cbindgen::Config::from_file(crate_dir().join("cbindgen.toml")).unwrap();
    let bindings = cbindgen::Builder::new()
        .with_config(config)
        .with_src(crate_dir().join("src").join("lib.rs"))
        .generate()
        .expect("cbindgen parses the crate");
    let mut bytes = Vec::new();
    bindings.write(&mut bytes);
    String::from_utf8(bytes).unwrap()
}

#[test]
fn committed_header_is_what_cbindgen_generates_now() {
    let now = generated_header();
    let path = header_path();
    if std::env::var_os("THORARENA_BLESS").is_some() {
        std::fs::write(&path, &now).unwrap();
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        committed == now,
        "{} is stale: rerun with THORARENA_BLESS=1 after a deliberate change of the C ABI",
        path.display()
    );
}

/// The structs of the layout file that the header mirrors, with their C names.
const MIRRORED: [(&str, &str); 3] = [
    ("BatchHeader", "ThorarenaBatchHeader"),
    ("EnvHeader", "ThorarenaEnvHeader"),
    ("ActionHeader", "ThorarenaActionHeader"),
];

/// A C program printing what the compiler makes of the header, one fact per line.
fn probe_source(layout: &Value) -> String {
    let mut c = String::from(
        "#include <stdalign.h>\n#include <stddef.h>\n#include <stdio.h>\n\
         #include \"thorarena.h\"\n\nint main(void) {\n",
    );
    for (name, c_name) in MIRRORED {
        c += &format!(
            "  printf(\"struct {name} %zu %zu\\n\", sizeof({c_name}), alignof({c_name}));\n"
        );
        for field in layout["structs"][name]["fields"].as_array().unwrap() {
            let f = field["name"].as_str().unwrap();
            c += &format!(
                "  printf(\"field {name}.{f} %zu %zu\\n\", offsetof({c_name}, {f}), \
                 sizeof((({c_name} *)0)->{f}));\n"
            );
        }
    }
    for (name, _) in layout["constants"].as_object().unwrap() {
        if name != "WORD_BYTES" {
            c += &format!(
                "  printf(\"const {name} %llu\\n\", (unsigned long long)THORARENA_{name});\n"
            );
        }
    }
    c += "  printf(\"const PROTOCOL_VERSION %llu\\n\", \
          (unsigned long long)THORARENA_PROTOCOL_VERSION);\n";
    for s in ThorarenaStatus::ALL {
        let n = s.name().to_str().unwrap();
        c += &format!("  printf(\"status {n} %d\\n\", (int){n});\n");
    }
    c += "  return 0;\n}\n";
    c
}

/// What the layout file and the Rust types say the probe must print.
fn expected_probe_output(layout: &Value) -> Vec<String> {
    let mut want = Vec::new();
    for (name, _) in MIRRORED {
        let s = &layout["structs"][name];
        want.push(format!("struct {name} {} {}", s["size"], s["align"]));
        for field in s["fields"].as_array().unwrap() {
            let f = field["name"].as_str().unwrap();
            want.push(format!(
                "field {name}.{f} {} {}",
                field["offset"], field["size"]
            ));
        }
    }
    for (name, value) in layout["constants"].as_object().unwrap() {
        if name != "WORD_BYTES" {
            want.push(format!("const {name} {value}"));
        }
    }
    want.push(format!(
        "const PROTOCOL_VERSION {}",
        layout["protocol_version"]
    ));
    for s in ThorarenaStatus::ALL {
        want.push(format!(
            "status {} {}",
            s.name().to_str().unwrap(),
            s as i32
        ));
    }
    want
}

fn tool_works(tool: &str) -> bool {
    Command::new(tool)
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success())
}

#[test]
fn header_agrees_with_layout_json_under_a_c_compiler() {
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    if !tool_works(&cc) {
        let reason = format!("no C compiler ({cc}) on this machine (apt-get install gcc)");
        return prereq::skip(
            "c_header::header_agrees_with_layout_json_under_a_c_compiler",
            &reason,
        );
    }
    let layout = layout_json();
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("c_header");
    std::fs::create_dir_all(&dir).unwrap();
    let src = dir.join("probe.c");
    let exe = dir.join("probe");
    std::fs::write(&src, probe_source(&layout)).unwrap();
    let include = crate_dir().join("include");
    let out = Command::new(&cc)
        .args([
            "-std=c11",
            "-Wall",
            "-Wextra",
            "-Wpedantic",
            "-Werror",
            "-I",
        ])
        .arg(&include)
        .arg(&src)
        .arg("-o")
        .arg(&exe)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "the header does not compile as C11:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let run = Command::new(&exe).output().unwrap();
    assert!(run.status.success());
    let got: Vec<String> = String::from_utf8(run.stdout)
        .unwrap()
        .lines()
        .map(String::from)
        .collect();
    assert_eq!(got, expected_probe_output(&layout));

    // The same header compiles as C++ (it is used from C++ through extern "C").
    let cxx = std::env::var("CXX").unwrap_or_else(|_| "c++".into());
    if tool_works(&cxx) {
        let out = Command::new(&cxx)
            .args(["-std=c++17", "-Wall", "-Wextra", "-Werror", "-fsyntax-only"])
            .args(["-x", "c++", "-I"])
            .arg(&include)
            .arg(&src)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "the header does not compile as C++17:\n{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

#[test]
fn field_lookup_gives_the_offsets_of_the_layout_example() {
    let layout = layout_json();
    let example = &layout["example"];
    let n_joints = example["n_joints"].as_u64().unwrap() as usize;
    let n_refs = example["n_refs"].as_u64().unwrap() as usize;
    for field in example["env_fields"].as_array().unwrap() {
        let name = CString::new(field["name"].as_str().unwrap()).unwrap();
        let (mut offset, mut len) = (0usize, 0usize);
        // SAFETY: a NUL-terminated name and two writable outputs.
        let status = unsafe {
            thorarena_layout_env_field(n_joints, n_refs, name.as_ptr(), &mut offset, &mut len)
        };
        assert_eq!(status, ThorarenaStatus::Ok, "{name:?}");
        assert_eq!(offset as u64, field["offset"].as_u64().unwrap(), "{name:?}");
        assert_eq!(len as u64, field["len"].as_u64().unwrap(), "{name:?}");
    }
    let unknown: *const c_char = c"reference[2].joint_pos".as_ptr();
    let (mut offset, mut len) = (0usize, 0usize);
    // SAFETY: as above.
    let status =
        unsafe { thorarena_layout_env_field(n_joints, n_refs, unknown, &mut offset, &mut len) };
    assert_eq!(status, ThorarenaStatus::InvalidArgument);
}
