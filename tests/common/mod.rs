//! Builders shared by the integration tests.
#![allow(dead_code)]

use serde_json::json;
use thorarena::sim::motion::Sequence;
use thorarena::sim::robot::{self, RobotModel};

/// The numbers of a fixture file, one per line (`tests/fixtures/DIR/FILE`: golden vectors
/// a script computed independently of this crate).
pub fn fixture_numbers(dir: &str, file: &str) -> Vec<f64> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(dir)
        .join(file);
    std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .lines()
        .map(|l| l.trim().parse().unwrap())
        .collect()
}

/// The bundled G1.
pub fn g1() -> RobotModel {
    robot::load_bundled("g1_29dof").unwrap()
}

/// 40 frames at 30 fps: the root moves +x at 0.3 m/s and yaws at 0.3 rad/s, every joint
/// ramps at 0.03 rad/s from the default pose, forces are simple ramps.
pub fn sample_sequence(robot: &RobotModel, id: &str) -> Sequence {
    let t = 40;
    let q0 = robot.default_pose();
    let yaw = |k: usize| 0.01 * k as f64;
    Sequence {
        task: "clean_table".into(),
        sequence_id: id.into(),
        fps: 30.0,
        joint_names: robot.joints.iter().map(|j| j.name.clone()).collect(),
        root_pos: (0..t).map(|k| [0.01 * k as f64, 0.0, 0.78]).collect(),
        root_quat_wxyz: (0..t)
            .map(|k| [(yaw(k) / 2.0).cos(), 0.0, 0.0, (yaw(k) / 2.0).sin()])
            .collect(),
        joint_pos: (0..t)
            .map(|k| q0.iter().map(|q| q + 0.001 * k as f64).collect())
            .collect(),
        joint_vel: None,
        force_sensor: [
            (0..t).map(|k| [k as f64, 0.0, -5.0]).collect(),
            vec![[0.0, 1.0, 2.0]; t],
        ],
        hand_from_sensor_wxyz: [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]],
        force_point_hand: [[0.0; 3], [0.01, 0.0, 0.0]],
        forces_recorded: true,
        force_frame: Default::default(),
        provenance: json!({"format": "test"}),
    }
}

/// A checked evaluation built in memory for the runner's own tests (their sequences are
/// made, not read from a dataset): `settings` by name, the default keypoints,
/// termination and policy I/O rules, rapier, no traces.
#[allow(dead_code)]
pub fn runner_spec(
    robot: &RobotModel,
    profile: &thorarena::sim::profile::Profile,
    sequences: &[Sequence],
    settings: &[&str],
    (workers, envs, pipeline_depth): (usize, usize, usize),
) -> thorarena::eval::EvalSpec {
    thorarena::eval::EvalSpec {
        policy: None,
        robot: robot.clone(),
        profile: profile.clone(),
        profile_mismatch: false,
        process_profile: thorarena::policy::declared_profile::ProcessProfile::Named {
            mismatch_ok: false,
        },
        physics_dt_asked_s: None,
        declared_profile: None,
        unchecked: false,
        engine: Default::default(),
        dataset: "in-memory".into(),
        dataset_sha256: String::new(),
        sequences: sequences.to_vec(),
        subset: None,
        settings: settings
            .iter()
            .map(|s| thorarena::eval::Setting::parse(s).unwrap())
            .collect(),
        keypoints: "default".into(),
        termination: Default::default(),
        io: Default::default(),
        shard: None,
        trace: Vec::new(),
        workers,
        envs,
        pipeline_depth,
        advice: Vec::new(),
    }
}

/// This build's `thorarena` run in `cwd` with `args`, to its end.
#[allow(dead_code)]
pub fn run_bin(cwd: &std::path::Path, args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_thorarena"))
        .current_dir(cwd)
        .args(args)
        .output()
        .expect("thorarena runs")
}

/// The error text of a command that must have failed plainly: it did fail, and not by a
/// panic.
#[allow(dead_code)]
pub fn failure(o: &std::process::Output) -> String {
    assert!(
        !o.status.success(),
        "expected an error; stdout: {}",
        String::from_utf8_lossy(&o.stdout)
    );
    let e = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(!e.contains("panicked"), "a panic: {e}");
    e
}
