//! The synthetic dataset generator: every generated sequence is a valid G1 motion (joints
//! inside their limits with margin, stance feet flat, on the ground and not sliding, feet
//! apart, hands outside the torso), its forces stay in the calibrated per-task ranges and
//! its sensor calibration is not the identity (all for generator version 1; version 2:
//! `tests/synthetic_v2.rs`); generation is deterministic per seed and per sequence; the
//! committed `data/sample` (version 2) regenerates bit for bit and loads, and version 1
//! still makes the sample it made, to its hash.

use nalgebra::{Isometry3, Point3, Quaternion, Translation3, UnitQuaternion, Vector3};
use std::path::Path;
use std::sync::OnceLock;
use thorarena::sim::motion::synth::{
    synthesize, write_synthetic, SynthOptions, GENERATOR_VERSION, TASKS,
};
use thorarena::sim::motion::{Dataset, Sequence, MANIFEST};
use thorarena::sim::robot::{forward_kinematics, frame_pose, Geometry, RobotModel};

mod common;
use common::g1;

fn options(per_task: usize, seed: u64, tasks: &[&str]) -> SynthOptions {
    SynthOptions {
        per_task,
        seed,
        fps: 50.0,
        tasks: tasks.iter().map(|t| t.to_string()).collect(),
        version: 1,
    }
}

/// Sequences per task of the validity tests: 2, or `THORARENA_SYNTH_PER_TASK` for a
/// thorough run (60 checks the full-size dataset in about two minutes).
fn per_task() -> usize {
    std::env::var("THORARENA_SYNTH_PER_TASK")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(2)
}

/// The sequences of the validity tests, generated once.
fn generated() -> &'static (RobotModel, Vec<Sequence>) {
    static CELL: OnceLock<(RobotModel, Vec<Sequence>)> = OnceLock::new();
    CELL.get_or_init(|| {
        let robot = g1();
        let seqs = synthesize(&robot, &options(per_task(), 7, &[]), |_, _| {}).unwrap();
        (robot, seqs)
    })
}

fn root(seq: &Sequence, k: usize) -> Isometry3<f64> {
    let q = seq.root_quat_wxyz[k];
    Isometry3::from_parts(
        Translation3::from(Vector3::from(seq.root_pos[k])),
        UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3])),
    )
}

/// Lowest sole point of one foot body, world z.
fn sole_z(robot: &RobotModel, poses: &[Isometry3<f64>], body: usize) -> f64 {
    robot.bodies[body]
        .shapes
        .iter()
        .filter(|s| s.is_sole)
        .map(|s| {
            let r = match s.geometry {
                Geometry::Sphere { radius } => radius,
                _ => 0.0,
            };
            (poses[body] * s.body_from_shape).translation.z - r
        })
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn every_sequence_keeps_joints_inside_their_limits_with_margin() {
    let (robot, seqs) = generated();
    assert_eq!(seqs.len(), per_task() * TASKS.len());
    for s in seqs {
        for (k, row) in s.joint_pos.iter().enumerate() {
            for (j, q) in row.iter().enumerate() {
                let joint = &robot.joints[j];
                let margin = (q - joint.lower_rad).min(joint.upper_rad - q);
                assert!(
                    margin >= 0.02,
                    "{} frame {k} {}: margin {margin}",
                    s.sequence_id,
                    joint.name
                );
            }
        }
    }
}

#[test]
fn stance_feet_are_flat_on_the_ground_apart_and_do_not_slide() {
    let (robot, seqs) = generated();
    let feet =
        ["left_ankle_roll_link", "right_ankle_roll_link"].map(|n| robot.body_index(n).unwrap());
    let mut poses = Vec::new();
    for s in seqs {
        let mut anchor: [Option<Vector3<f64>>; 2] = [None, None];
        for k in 0..s.n_frames() {
            let pelvis = root(s, k);
            forward_kinematics(robot, &pelvis, &s.joint_pos[k], &mut poses);
            let z = feet.map(|b| sole_z(robot, &poses, b));
            let lowest = z[0].min(z[1]);
            assert!(
                lowest.abs() <= 0.005,
                "{} frame {k}: lowest sole at {lowest} m",
                s.sequence_id
            );
            for side in 0..2 {
                let foot = poses[feet[side]];
                if z[side] > 0.002 {
                    anchor[side] = None;
                    continue;
                }
                let tilt = (foot.rotation * Vector3::z()).angle(&Vector3::z());
                assert!(
                    tilt < 3f64.to_radians(),
                    "{} frame {k}: stance foot tilted {tilt} rad",
                    s.sequence_id
                );
                let p = foot.translation.vector;
                let a = *anchor[side].get_or_insert(p);
                let slide = (p - a).xy().norm();
                assert!(
                    slide <= 0.002,
                    "{} frame {k}: stance foot slid {slide} m",
                    s.sequence_id
                );
            }
            let rel = pelvis.rotation.inverse()
                * (poses[feet[0]].translation.vector - poses[feet[1]].translation.vector);
            assert!(
                rel.y >= 0.12,
                "{} frame {k}: feet {} m apart laterally",
                s.sequence_id,
                rel.y
            );
        }
    }
}

#[test]
fn hands_stay_outside_the_torso() {
    let (robot, seqs) = generated();
    let torso = robot.body_index("torso_link").unwrap();
    let boxes: Vec<_> = robot.bodies[torso]
        .shapes
        .iter()
        .filter_map(|s| match s.geometry {
            Geometry::Box { half_extents } => Some((s.body_from_shape, half_extents)),
            _ => None,
        })
        .collect();
    let mut poses = Vec::new();
    for s in seqs {
        for k in (0..s.n_frames()).step_by(5) {
            forward_kinematics(robot, &root(s, k), &s.joint_pos[k], &mut poses);
            for hand in &robot.hands {
                let p = frame_pose(robot, &poses, hand.frame) * Point3::origin();
                for (pose, h) in &boxes {
                    let local = (poses[torso] * pose).inverse() * p;
                    let inside = (0..3).all(|a| local[a].abs() < h[a]);
                    assert!(
                        !inside,
                        "{} frame {k}: a hand is inside the torso",
                        s.sequence_id
                    );
                }
            }
        }
    }
}

/// Per-hand force range per task (N): (largest allowed, smallest required maximum).
fn force_bounds(task: &str) -> (f64, f64) {
    match task {
        "clean_table" => (25.0, 5.0),
        "liftdown_water" | "liftup_water" => (35.0, 12.0),
        "pull_chair" | "push_chair" => (65.0, 25.0),
        _ => (25.0, 5.0),
    }
}

#[test]
fn forces_stay_in_the_calibrated_ranges_and_vary_over_time() {
    let (robot, seqs) = generated();
    for s in seqs {
        assert!(s.forces_recorded);
        let (hi, lo) = force_bounds(&s.task);
        let mut total: Vec<f64> = Vec::new();
        for side in 0..2 {
            let mags: Vec<f64> = s.force_sensor[side]
                .iter()
                .map(|f| Vector3::from(*f).norm())
                .collect();
            let max = mags.iter().copied().fold(0.0, f64::max);
            assert!(
                max <= hi,
                "{}: hand {side} peaks at {max} N (> {hi})",
                s.sequence_id
            );
            total.extend(mags);
            assert_eq!(
                s.force_point_hand[side],
                <[f64; 3]>::from(robot.hands[side].point_hand.coords)
            );
        }
        let max = total.iter().copied().fold(0.0, f64::max);
        assert!(
            max >= lo,
            "{}: forces never exceed {max} N (< {lo})",
            s.sequence_id
        );
        // Not all the time at one level: the quietest tenth is well below the peak.
        total.sort_by(f64::total_cmp);
        let p10 = total[total.len() / 10];
        assert!(p10 < 0.6 * max, "{}: p10 {p10} vs max {max}", s.sequence_id);
    }
}

#[test]
fn sensor_calibrations_are_rotations_far_from_identity_and_differ_per_side() {
    let (_, seqs) = generated();
    for s in seqs {
        let q = s
            .hand_from_sensor_wxyz
            .map(|q| UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3])));
        for c in &q {
            assert!(
                c.angle() > 1.0,
                "{}: calibration angle {}",
                s.sequence_id,
                c.angle()
            );
        }
        assert!(
            q[0].angle_to(&q[1]) > 2.0,
            "{}: both sides share a calibration",
            s.sequence_id
        );
    }
}

#[test]
fn durations_are_between_10_and_30_seconds_and_ids_follow_the_pattern() {
    let (_, seqs) = generated();
    for s in seqs {
        assert!(
            (10.0..=30.0).contains(&s.duration_s()),
            "{}: {} s",
            s.sequence_id,
            s.duration_s()
        );
        assert!(s.sequence_id.starts_with(&s.task) && s.sequence_id.len() == s.task.len() + 4);
        s.validate(Path::new(&s.sequence_id)).unwrap();
    }
}

#[test]
fn the_same_seed_gives_identical_sequences_and_a_subset_regenerates_the_same() {
    let (robot, all) = generated();
    let subset = synthesize(
        robot,
        &options(2, 7, &["push_chair", "clean_table"]),
        |_, _| {},
    )
    .unwrap();
    for s in &subset {
        let same = all.iter().find(|a| a.sequence_id == s.sequence_id).unwrap();
        assert_eq!(s, same);
    }
    let other = synthesize(robot, &options(1, 8, &["push_chair"]), |_, _| {}).unwrap();
    let same_id = all
        .iter()
        .find(|a| a.sequence_id == other[0].sequence_id)
        .unwrap();
    assert_ne!(
        &other[0], same_id,
        "a different seed gave the same sequence"
    );
}

#[test]
fn unknown_tasks_are_rejected() {
    let robot = &generated().0;
    let err = synthesize(robot, &options(1, 0, &["juggle"]), |_, _| {}).unwrap_err();
    assert!(err.to_string().contains("juggle"), "{err}");
}

#[test]
fn the_committed_sample_regenerates_bit_identically_and_loads() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/sample");
    let dir = tempfile::tempdir().unwrap();
    // What `data synth --per-task 2 --seed 0` writes (generator version 2, the default).
    let sample = SynthOptions {
        version: GENERATOR_VERSION,
        ..options(2, 0, &[])
    };
    assert_eq!(GENERATOR_VERSION, 2);
    write_synthetic(dir.path(), &g1(), &sample, false, |_, _| {}).unwrap();
    let manifest = std::fs::read(root.join(MANIFEST)).unwrap();
    assert_eq!(
        manifest,
        std::fs::read(dir.path().join(MANIFEST)).unwrap(),
        "manifest.json differs"
    );
    let robot = &generated().0;
    let ds = Dataset::open(&root, robot).unwrap();
    assert_eq!(ds.len(), 2 * TASKS.len());
    for e in &ds.manifest.sequences {
        let a = std::fs::read(root.join(&e.file)).unwrap();
        let b = std::fs::read(dir.path().join(&e.file)).unwrap();
        assert!(a == b, "{} differs from its regeneration", e.file);
    }
    let seqs = ds.load_all().unwrap();
    assert!(seqs.iter().all(|s| s.forces_recorded && s.fps == 50.0));
}

/// Version 1 stays reproducible, so runs made on it keep verifying against their dataset
/// hash: `data synth --per-task 2 --seed 0 --generator 1` gives the sample committed
/// before version 2 became the default, to its content hash.
#[test]
fn version_1_regenerates_the_sample_it_made_to_its_hash() {
    const V1_SAMPLE_SHA256: &str =
        "e8f2a4d2cd27e373327f3f6d370192e5f9b04da608ccbc98e55ef2d7c382374d";
    let dir = tempfile::tempdir().unwrap();
    let (ds, _) =
        write_synthetic(dir.path(), &g1(), &options(2, 0, &[]), false, |_, _| {}).unwrap();
    assert_eq!(ds.content_hash(), V1_SAMPLE_SHA256);
}

#[test]
fn an_existing_dataset_is_kept_unless_forced() {
    let dir = tempfile::tempdir().unwrap();
    // `data synth --per-task 1 --tasks clean_table`, then again, then with `--force`.
    let run = |force: bool| {
        write_synthetic(
            dir.path(),
            &g1(),
            &options(1, 0, &["clean_table"]),
            force,
            |_, _| {},
        )
    };
    assert!(run(false).is_ok());
    let again = run(false).unwrap_err();
    assert!(
        again.to_string().contains("replaced only when asked to"),
        "{again}"
    );
    assert!(run(true).is_ok());
}
