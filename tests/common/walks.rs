//! The three walks TWIST2 publishes (`$THORARENA_REFERENCE/twist2/motions/`), imported as
//! TWIST2's harness prepares them, and MuJoCo's keypoint errors on them — shared by the
//! tests that run TWIST2 on them (included with `#[path]`).
#![allow(dead_code)]

use std::path::Path;
use std::process::Command;

/// MuJoCo's mean TWIST9 keypoint error per walk in TWIST2's harness, mm (SOURCES.md, TWIST2 in MuJoCo).
pub const MUJOCO_TWIST9_MM: [(&str, f64); 3] = [
    ("0807_yanjie_walk_001", 28.0),
    ("0807_yanjie_walk_002", 31.1),
    ("0807_yanjie_walk_003", 33.5),
];

/// Imports the three walks from `twist2_dir` (the reference's `twist2/`) into the dataset
/// `out`, task `walk`, feet put onto the ground as TWIST2's harness does.
pub fn import_walks(twist2_dir: &Path, out: &Path) {
    let files: Vec<String> = MUJOCO_TWIST9_MM
        .iter()
        .map(|(w, _)| {
            twist2_dir
                .join(format!("motions/{w}.pkl"))
                .display()
                .to_string()
        })
        .collect();
    let o = Command::new(env!("CARGO_BIN_EXE_thorarena"))
        .args(["data", "import", "--format", "twist-pkl"])
        .args(&files)
        .args(["--task", "walk", "--ground-correct", "--out"])
        .arg(out)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "importing the walks: {}",
        String::from_utf8_lossy(&o.stderr)
    );
}
