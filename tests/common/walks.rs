//! The three walks TWIST2 publishes (`$THORARENA_REFERENCE/twist2/motions/`), imported as
//! TWIST2's harness prepares them, and MuJoCo's keypoint errors on them — shared by the
//! tests that run TWIST2 on them (included with `#[path]`).
#![allow(dead_code)]

use std::path::Path;
use thorarena::sim::motion::import::{import_batch, ImportBatch, SourceFormat};

/// MuJoCo's mean TWIST9 keypoint error per walk in TWIST2's harness, mm (SOURCES.md, TWIST2 in MuJoCo).
pub const MUJOCO_TWIST9_MM: [(&str, f64); 3] = [
    ("0807_yanjie_walk_001", 28.0),
    ("0807_yanjie_walk_002", 31.1),
    ("0807_yanjie_walk_003", 33.5),
];

/// Imports the three walks from `twist2_dir` (the reference's `twist2/`) into the dataset
/// `out`, task `walk`, feet put onto the ground as TWIST2's harness does.
pub fn import_walks(twist2_dir: &Path, out: &Path) {
    // What `data import --format twist-pkl FILES --task walk --ground-correct` does.
    let batch = ImportBatch {
        inputs: MUJOCO_TWIST9_MM
            .iter()
            .map(|(w, _)| twist2_dir.join(format!("motions/{w}.pkl")))
            .collect(),
        format: SourceFormat::TwistPkl,
        task: "walk".into(),
        force_logs: None,
        force_offset_s: 0.0,
        force_sign: 1.0,
        renormalize_quaternions: false,
        trim_glitches: false,
        ground_correct: true,
    };
    let robot = thorarena::sim::robot::load_bundled("g1_29dof").unwrap();
    if let Err(e) = import_batch(out, &robot, &batch, &mut ()) {
        panic!("importing the walks: {e}");
    }
}
