//! A rollout becomes data (`eval --trace`, then `data import --format rollout`): the
//! sequence holds the simulated root pose and joints, its forces replayed on its own motion
//! give back the world forces that acted, and `data check` finds a motion the simulator
//! produced balanced — the check's floor.

use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3};
use std::path::Path;
use std::process::Command;
use thorarena::eval::results::RunDir;
use thorarena::sim::motion::check::{check_sequence, CheckOptions};
use thorarena::sim::motion::{Dataset, Reference};
use thorarena::sim::replay::ForceReplay;
use thorarena::sim::robot::{forward_kinematics, load_bundled};

const BIN: &str = env!("CARGO_BIN_EXE_thorarena");
const SAMPLE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/sample");

fn thorarena(args: &[&str]) -> std::process::Output {
    let out = Command::new(BIN).args(args).output().unwrap();
    assert!(
        out.status.success(),
        "thorarena {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

#[test]
fn a_rollout_written_as_data_replays_its_own_forces_and_passes_the_check() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("run");
    thorarena(&[
        "eval",
        "--dataset",
        SAMPLE,
        "--policy",
        "balance",
        "--settings",
        "force",
        "--sequences",
        "clean_table/clean_table_000",
        "--trace",
        "clean_table/clean_table_000",
        "--out",
        run.to_str().unwrap(),
    ]);
    let trace_file = run.join("traces/clean_table-clean_table_000-force.json");
    let ds_dir = tmp.path().join("rollouts");
    thorarena(&[
        "data",
        "import",
        "--format",
        "rollout",
        trace_file.to_str().unwrap(),
        "--out",
        ds_dir.to_str().unwrap(),
        "--task",
        "rollout",
    ]);
    let robot = load_bundled("g1_29dof").unwrap();
    let ds = Dataset::open(&ds_dir, &robot).unwrap();
    let seq = ds.load(0).unwrap();
    let steps = RunDir::read_trace(&trace_file).unwrap();
    assert_eq!(seq.n_frames(), steps.len());
    assert_eq!(seq.task, "rollout");
    assert!(seq.forces_recorded);
    let dt = steps[1].time_s - steps[0].time_s;
    assert!((seq.fps - 1.0 / dt).abs() < 1e-6, "fps {}", seq.fps);

    // The sequence's forces, replayed on its own motion, are the forces that acted.
    let replay = ForceReplay::new(&robot, &seq, 1.0);
    let reference = Reference::new(&seq);
    let mut poses = Vec::new();
    let mut loaded = 0;
    for (k, step) in steps.iter().enumerate() {
        // The canonical format stores float32.
        let close = |a: &[f64], b: &[f64]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-5);
        assert!(close(&seq.root_pos[k], &step.root_pos), "step {k} root");
        assert!(close(&seq.joint_pos[k], &step.q), "step {k} joints");
        let q = step.root_quat_wxyz;
        let root = Isometry3::from_parts(
            Translation3::from(Vector3::from(step.root_pos)),
            UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3])),
        );
        forward_kinematics(&robot, &root, &step.q, &mut poses);
        let replayed = replay.forces_at(&reference, k as f64 / seq.fps, &poses);
        for (side, replayed) in replayed.iter().enumerate() {
            let acted = Vector3::from(step.hand_force_w[side]);
            assert!(
                (replayed - acted).norm() < 1e-4 * (1.0 + acted.norm()),
                "step {k} side {side}: replayed {replayed:?}, acted {acted:?}"
            );
            loaded += usize::from(acted.norm() > 2.0);
        }
    }
    assert!(
        loaded > 100,
        "clean_table's forces acted on {loaded} hand-steps"
    );

    // Standing at a table under its forces, as the simulator made it: inside the support.
    let check = check_sequence(&seq, &robot, &CheckOptions::default()).unwrap();
    assert!(check.with_force.stance_frames > 0);
    assert!(check.with_force.outside_share < 0.02, "{check:?}");
    assert!(check.without_force.outside_share < 0.02, "{check:?}");
}

#[test]
fn a_file_that_is_no_trace_is_refused_naming_it() {
    let tmp = tempfile::tempdir().unwrap();
    let manifest = Path::new(SAMPLE).join("manifest.json");
    let out = Command::new(BIN)
        .args([
            "data",
            "import",
            "--format",
            "rollout",
            manifest.to_str().unwrap(),
        ])
        .args([
            "--out",
            tmp.path().join("ds").to_str().unwrap(),
            "--task",
            "x",
        ])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("manifest.json") && err.contains("eval --trace"),
        "{err}"
    );
    assert!(!tmp.path().join("ds/manifest.json").exists());
}
