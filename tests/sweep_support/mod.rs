//! What the hostile-sweep tests share: `thorarena` run in a directory, specs and plans
//! written there, small datasets, and directories copied or listed.
#![allow(dead_code)] // each test file uses part of it

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

pub const BIN: &str = env!("CARGO_BIN_EXE_thorarena");
pub const SAMPLE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/sample");

pub fn thorarena(args: &[&str]) -> Output {
    Command::new(BIN)
        .args(args)
        .output()
        .expect("thorarena runs")
}

pub fn ok(o: Output) -> Output {
    assert!(
        o.status.success(),
        "stdout:\n{}\nstderr:\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

/// The error output of a command that must fail cleanly (an error, not a panic).
pub fn err(o: &Output) -> String {
    let e = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(
        !o.status.success(),
        "expected a failure; stdout:\n{}",
        out(o)
    );
    assert_ne!(o.status.code(), Some(101), "a panic, not an error:\n{e}");
    assert!(!e.contains("panicked"), "a panic, not an error:\n{e}");
    e
}

pub fn out(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

pub fn spec(dir: &Path, body: &str) -> PathBuf {
    let p = dir.join("spec.toml");
    std::fs::write(&p, body).unwrap();
    p
}

pub fn plan(spec: &Path, out: &Path) {
    ok(thorarena(&[
        "sweep",
        "plan",
        spec.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]));
}

pub fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// One in-process policy, two settings, two shards: four quick tasks.
pub fn four_tasks(tmp: &Path) -> PathBuf {
    spec(
        tmp,
        &format!(
            "datasets = [\"{SAMPLE}\"]\nsettings = [\"no-force\", \"force\"]\nshards = 2\n[[policy]]\npolicy = \"hold\"\n"
        ),
    )
}

pub fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let p = e.unwrap().path();
        let dest = to.join(p.file_name().unwrap());
        if p.is_dir() {
            copy_dir(&p, &dest);
        } else {
            std::fs::copy(&p, &dest).unwrap();
        }
    }
}

/// A copy of the sample holding only its first `n` sequences.
pub fn small_dataset(tmp: &Path, n: usize) -> PathBuf {
    let ds = tmp.join(format!("sample-{n}"));
    copy_dir(Path::new(SAMPLE), &ds);
    let manifest = ds.join("manifest.json");
    let mut m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&manifest).unwrap()).unwrap();
    m["sequences"].as_array_mut().unwrap().truncate(n);
    std::fs::write(&manifest, serde_json::to_string(&m).unwrap()).unwrap();
    ds
}

/// Files directly in `dir`.
pub fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}
