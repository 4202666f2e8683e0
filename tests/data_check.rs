//! `thorarena data check`: its inverse dynamics against MuJoCo's `mj_inverse`, its balance
//! check on motions whose answer is known (standing still; standing under a hand force no
//! one could lean against), its tables and gate on the bundled sample, and its run on the
//! published motions (TWIST2's walks, SoftMimic's clips); `--rollout`, a tracker's run without
//! force read back per sequence. The MuJoCo test counts as skipped
//! in a build without the `mujoco` feature, the published motions' without
//! `../shared/reference` (never in CI).

use nalgebra::Isometry3;
use std::path::Path;
use std::process::Command;
use thorarena::sim::motion::check::{check_dataset, check_sequence, CheckOptions};
use thorarena::sim::motion::{Dataset, Sequence};
use thorarena::sim::robot::{forward_kinematics, load_bundled, lowest_sole_point_z, RobotModel};

mod prereq;
#[path = "common/walks.rs"]
mod walks;

const BIN: &str = env!("CARGO_BIN_EXE_thorarena");
const SAMPLE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/sample");

fn g1() -> RobotModel {
    load_bundled("g1_29dof").unwrap()
}

/// The root height at which the default pose stands with its soles on z = 0.
fn standing_height(robot: &RobotModel) -> f64 {
    let mut poses = Vec::new();
    forward_kinematics(
        robot,
        &Isometry3::identity(),
        &robot.default_pose(),
        &mut poses,
    );
    -lowest_sole_point_z(robot, &poses).unwrap()
}

/// Two seconds at 50 fps of the default pose standing still, facing +x, with a constant
/// force on both hands; each hand's calibration makes its sensor frame the world's, so
/// `hand_force_w` is the world-frame force.
fn standing(robot: &RobotModel, hand_force_w: [f64; 3]) -> Sequence {
    let n = 100;
    let z = standing_height(robot);
    let mut poses = Vec::new();
    let root = Isometry3::translation(0.0, 0.0, z);
    forward_kinematics(robot, &root, &robot.default_pose(), &mut poses);
    let sensor_in_hand = |side: usize| {
        let frame = &robot.frames[robot.hands[side].frame];
        let q = (poses[frame.body] * frame.body_from_frame)
            .rotation
            .inverse();
        [q.w, q.i, q.j, q.k]
    };
    Sequence {
        task: "stand".into(),
        sequence_id: "still".into(),
        fps: 50.0,
        joint_names: robot.joints.iter().map(|j| j.name.clone()).collect(),
        root_pos: vec![[0.0, 0.0, z]; n],
        root_quat_wxyz: vec![[1.0, 0.0, 0.0, 0.0]; n],
        joint_pos: vec![robot.default_pose(); n],
        joint_vel: None,
        force_sensor: [vec![hand_force_w; n], vec![hand_force_w; n]],
        hand_from_sensor_wxyz: [sensor_in_hand(0), sensor_in_hand(1)],
        force_point_hand: [[0.0; 3]; 2],
        forces_recorded: true,
        force_frame: Default::default(),
        provenance: serde_json::json!({}),
    }
}

#[test]
fn standing_still_keeps_the_cop_inside_and_a_hand_force_no_lean_can_carry_pushes_it_out() {
    let robot = g1();
    let opts = CheckOptions::default();
    let still = check_sequence(&standing(&robot, [0.0; 3]), &robot, &opts).unwrap();
    assert_eq!(still.with_force.stance_frames, 98, "{still:?}");
    assert_eq!(still.with_force.outside_share, 0.0, "{still:?}");
    assert_eq!(still.without_force.outside_share, 0.0, "{still:?}");
    assert!(still.with_force.friction_ratio_p95 < 1e-6, "{still:?}");
    assert_eq!(still.kinematics.contact_share, 1.0);
    assert!(still.kinematics.penetration_max_mm < 1e-6);

    // 150 N forward on each hand with the body upright: the ground's CoP would have to sit
    // far ahead of the toes, and friction carries 300 N against 340 N of weight only at
    // μ ≈ 0.9.
    let pushed = check_sequence(&standing(&robot, [150.0, 0.0, 0.0]), &robot, &opts).unwrap();
    assert_eq!(pushed.with_force.outside_share, 1.0, "{pushed:?}");
    assert!(pushed.with_force.outside_p95_mm > 100.0, "{pushed:?}");
    assert_eq!(pushed.without_force.outside_share, 0.0, "{pushed:?}");
    assert!(pushed.with_force.friction_ratio_p95 > 0.8, "{pushed:?}");
    assert!((pushed.forces.loaded_mean_n - 150.0).abs() < 1e-9);
    assert_eq!(pushed.forces.loaded_share, 1.0);
}

#[test]
fn the_check_refuses_a_cutoff_that_is_no_frequency() {
    let robot = g1();
    let opts = CheckOptions {
        cutoff_hz: 0.0,
        ..CheckOptions::default()
    };
    let e = check_sequence(&standing(&robot, [0.0; 3]), &robot, &opts).unwrap_err();
    assert!(e.to_string().contains("cutoff_hz"), "{e}");
}

#[test]
fn data_check_prints_per_task_tables_writes_json_and_gates_on_max_outside() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("check");
    let ok = Command::new(BIN)
        .args(["data", "check", SAMPLE, "--out", out.to_str().unwrap()])
        .args(["--max-outside", "1"])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&ok.stdout);
    assert!(
        ok.status.success(),
        "{}",
        String::from_utf8_lossy(&ok.stderr)
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("check.json")).unwrap()).unwrap();
    let robot = g1();
    let ds = Dataset::open(Path::new(SAMPLE), &robot).unwrap();
    let tasks = json["tasks"].as_array().unwrap();
    assert_eq!(json["sequences"].as_array().unwrap().len(), ds.len());
    assert_eq!(json["dataset_sha256"], ds.content_hash());
    for t in tasks {
        let task = t["task"].as_str().unwrap();
        assert!(
            stdout.contains(&format!("| {task} |")),
            "{task} not printed"
        );
        assert!(
            t["with_force"]["stance_frames"].as_u64().unwrap() > 0,
            "{t}"
        );
    }
    // The library's numbers, not the file's: the same check in process.
    let inproc = check_dataset(
        &ds,
        &ds.load_all().unwrap(),
        &robot,
        &CheckOptions::default(),
        |_, _| {},
    )
    .unwrap();
    assert_eq!(tasks.len(), inproc.tasks.len());
    let worst = inproc
        .tasks
        .iter()
        .map(|t| t.worst_outside_share())
        .fold(0.0, f64::max);
    let md = std::fs::read_to_string(out.join("check.md")).unwrap();
    assert!(md.contains("by sequence"), "{md}");

    // A gate just below the worst task's share fails, naming it; at it, passes.
    let gate = |max: f64| {
        Command::new(BIN)
            .args(["data", "check", SAMPLE, "--max-outside", &format!("{max}")])
            .output()
            .unwrap()
    };
    if worst > 0.0 {
        let failed = gate(worst - 1e-6);
        assert_eq!(failed.status.code(), Some(1));
        let err = String::from_utf8_lossy(&failed.stderr);
        assert!(err.contains("--max-outside"), "{err}");
    }
    assert!(gate(worst + 1e-9).status.success());
    let bad = gate(1.5);
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("share from 0 to 1"));
}

/// `data check --rollout POLICY --out DIR`: the tracker's run of every sequence without
/// force, read back per sequence into check.json and check.md.
fn check_with_rollout(out: &Path, policy: &str) -> (serde_json::Value, String, String) {
    let run = Command::new(BIN)
        .args(["data", "check", SAMPLE, "--out", out.to_str().unwrap()])
        .args(["--rollout", policy])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr).to_string();
    assert!(run.status.success(), "{stderr}");
    let json = serde_json::from_str(&std::fs::read_to_string(out.join("check.json")).unwrap());
    let md = std::fs::read_to_string(out.join("check.md")).unwrap();
    (json.unwrap(), md, stderr)
}

#[test]
fn data_check_rolls_a_tracker_out_without_force_and_lists_what_it_cannot_hold() {
    let refused = Command::new(BIN)
        .args(["data", "check", SAMPLE, "--rollout", "replay"])
        .output()
        .unwrap();
    assert!(!refused.status.success());
    assert!(String::from_utf8_lossy(&refused.stderr).contains("--out"));

    // Open-loop replay of the reference's joints falls: every sequence it drops is listed
    // with why and when, and each figure is the one its run recorded.
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("check");
    let (json, md, _) = check_with_rollout(&out, "replay");
    let tracker = &json["tracker"];
    let held = tracker["sequences"].as_array().unwrap();
    let ds = Dataset::open(Path::new(SAMPLE), &g1()).unwrap();
    assert_eq!(held.len(), ds.len());
    let run = thorarena::eval::results::RunDir::new(out.join("rollout-replay"));
    let log = run.read_log(&run.read_header().unwrap()).unwrap();
    assert_eq!(log.records.len(), ds.len());
    for (h, entry) in held.iter().zip(&ds.manifest.sequences) {
        assert_eq!(h["sequence_id"], entry.sequence_id.as_str());
        let record = log
            .records
            .iter()
            .find(|r| r.sequence_id == entry.sequence_id && r.setting == "no-force")
            .unwrap();
        assert_eq!(h["survival"].as_f64().unwrap(), record.series.survival());
        let dropped = record.series.survival() < 1.0;
        assert_eq!(h["ended_by"].is_null(), !dropped, "{h}");
        let line = format!("- {}/{}: ", entry.task, entry.sequence_id);
        assert_eq!(md.contains(&line), dropped, "{line} in\n{md}");
    }
    assert!(md.contains("Not held"), "replay held every sequence:\n{md}");

    // Run again: the tracker's run resumes with nothing left to run, the same figures.
    let (again, _, stderr) = check_with_rollout(&out, "replay");
    assert!(stderr.contains("0 episodes to run"), "{stderr}");
    assert_eq!(again["tracker"], json["tracker"]);
}

/// The floor docs/data-check.md measures rests on TWIST2 holding every sample sequence
/// without force.
#[test]
fn twist2_holds_every_sample_sequence_without_force() {
    const TEST: &str = "twist2_holds_every_sample_sequence_without_force";
    let Some(onnx) = prereq::reference(TEST, "twist2/twist2_1017_25k.onnx") else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let policy = format!("twist2:{}", onnx.display());
    let (json, md, _) = check_with_rollout(&tmp.path().join("check"), &policy);
    for h in json["tracker"]["sequences"].as_array().unwrap() {
        assert_eq!(h["survival"].as_f64(), Some(1.0), "{h}");
    }
    assert!(md.contains("Every sequence held to its end."), "{md}");
}

#[test]
fn data_check_runs_on_twist2s_walks_and_softmimics_clips() {
    const TEST: &str = "data_check_runs_on_twist2s_walks_and_softmimics_clips";
    let Some(twist2) = prereq::reference(TEST, "twist2") else {
        return;
    };
    let Some(softmimic) = prereq::reference(TEST, "softmimic/motions") else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let walks = tmp.path().join("walks");
    walks::import_walks(&twist2, &walks);
    let clips = tmp.path().join("softmimic");
    let mut files: Vec<String> = std::fs::read_dir(&softmimic)
        .unwrap()
        .map(|e| e.unwrap().path().to_str().unwrap().to_string())
        .filter(|p| p.ends_with(".csv"))
        .collect();
    files.sort();
    let mut import = Command::new(BIN);
    // SoftMimic's walk.csv starts with a quaternion 2 % off unit norm.
    import.args([
        "data",
        "import",
        "--format",
        "softmimic-csv",
        "--ground-correct",
    ]);
    import.arg("--renormalize-quaternions");
    let imported = import
        .args(&files)
        .args(["--out", clips.to_str().unwrap(), "--task", "softmimic"])
        .output()
        .unwrap();
    assert!(
        imported.status.success(),
        "{}",
        String::from_utf8_lossy(&imported.stderr)
    );
    let robot = g1();
    for dir in [&walks, &clips] {
        let ds = Dataset::open(dir, &robot).unwrap();
        let check = check_dataset(
            &ds,
            &ds.load_all().unwrap(),
            &robot,
            &CheckOptions::default(),
            |_, _| {},
        )
        .unwrap();
        for t in &check.tasks {
            // People walking and standing are on the ground most of the time.
            assert!(t.kinematics.contact_share > 0.7, "{}: {t:?}", dir.display());
            assert!(t.with_force.stance_frames > 0);
            assert!(t.with_force.outside_share.is_finite());
            assert!(t.with_force.outside_p95_mm.is_finite());
        }
        println!("{}", check.markdown(false));
    }
}

/// Our recursive Newton–Euler against MuJoCo's `mj_inverse` (contacts and every other
/// constraint off) on the generated MJCF, at random states and accelerations: the root's
/// generalized force (world force; moment in the root frame) and every joint torque.
#[test]
fn inverse_dynamics_agrees_with_mujocos_mj_inverse() {
    #[cfg(not(feature = "mujoco"))]
    prereq::skip(
        "inverse_dynamics_agrees_with_mujocos_mj_inverse",
        "built without the `mujoco` feature (./test.sh builds it)",
    );
    #[cfg(feature = "mujoco")]
    mj_inverse_agrees();
}

#[cfg(feature = "mujoco")]
fn mj_inverse_agrees() {
    use mujoco_rs::prelude::*;
    use nalgebra::{UnitQuaternion, Vector3};
    use rand::{RngExt, SeedableRng};
    use thorarena::sim::robot::{inverse_dynamics, MotionState};
    let robot = g1();
    let settings = thorarena::sim::physics::PhysicsSettings::default();
    let mut mj =
        MjModel::from_xml_string(&thorarena::sim::physics::mjcf_of(&robot, &settings)).unwrap();
    mj.opt_mut().disableflags |= MjtDisableBit::mjDSBL_CONSTRAINT as i32;
    mj.opt_mut().gravity = settings.gravity;
    let joint = |name: &str| {
        let id = mj.name_to_id(MjtObjBase::mjOBJ_JOINT, name).unwrap();
        (mj.jnt_qposadr()[id] as usize, mj.jnt_dofadr()[id] as usize)
    };
    let joints: Vec<(usize, usize)> = robot.joints.iter().map(|j| joint(&j.name)).collect();
    let root = mj
        .name_to_id(MjtObjBase::mjOBJ_BODY, &robot.bodies[0].name)
        .unwrap();
    let free = mj.body_jntadr()[root] as usize;
    let (free_q, free_v) = (
        mj.jnt_qposadr()[free] as usize,
        mj.jnt_dofadr()[free] as usize,
    );
    let mut data = MjData::new(Box::new(mj));
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let mut r = |scale: f64| scale * rng.random_range(-1.0..1.0);
    let mut poses = Vec::new();
    for trial in 0..5 {
        let n = robot.n_joints();
        let q: Vec<f64> = robot
            .joints
            .iter()
            .map(|j| j.default_rad + 0.3 * r(1.0))
            .collect();
        let qd: Vec<f64> = (0..n).map(|_| r(2.0)).collect();
        let qdd: Vec<f64> = (0..n).map(|_| r(20.0)).collect();
        let rot = UnitQuaternion::from_euler_angles(r(0.3), r(0.3), r(3.0));
        let pos = Vector3::new(r(1.0), r(1.0), 0.8 + r(0.1));
        let (v, w_local) = (
            Vector3::new(r(1.0), r(1.0), r(1.0)),
            Vector3::new(r(1.0), r(1.0), r(1.0)),
        );
        let (a, alpha_local) = (
            Vector3::new(r(5.0), r(5.0), r(5.0)),
            Vector3::new(r(5.0), r(5.0), r(5.0)),
        );
        {
            let qpos = data.qpos_mut();
            qpos[free_q..free_q + 3].copy_from_slice(pos.as_slice());
            let c = rot.quaternion().coords; // (x, y, z, w)
            qpos[free_q + 3..free_q + 7].copy_from_slice(&[c.w, c.x, c.y, c.z]);
            for (j, &(a, _)) in joints.iter().enumerate() {
                qpos[a] = q[j];
            }
        }
        {
            let qvel = data.qvel_mut();
            qvel[free_v..free_v + 3].copy_from_slice(v.as_slice());
            qvel[free_v + 3..free_v + 6].copy_from_slice(w_local.as_slice());
            for (j, &(_, d)) in joints.iter().enumerate() {
                qvel[d] = qd[j];
            }
        }
        {
            let qacc = data.qacc_mut();
            qacc[free_v..free_v + 3].copy_from_slice(a.as_slice());
            qacc[free_v + 3..free_v + 6].copy_from_slice(alpha_local.as_slice());
            for (j, &(_, d)) in joints.iter().enumerate() {
                qacc[d] = qdd[j];
            }
        }
        data.inverse();
        let theirs = data.qfrc_inverse().to_vec();
        let state = MotionState {
            world_from_root: Isometry3::from_parts(pos.into(), rot),
            root_lin_vel_w: v,
            root_ang_vel_w: rot * w_local,
            root_lin_acc_w: a,
            // With ω_w = R·ω_b, dω_w/dt = R·dω_b/dt (the ω × ω term vanishes).
            root_ang_acc_w: rot * alpha_local,
            q: &q,
            qd: &qd,
            qdd: &qdd,
        };
        let gravity = Vector3::from(settings.gravity);
        let ours = inverse_dynamics(&robot, &state, &gravity, &[], &mut poses);
        let force = Vector3::new(theirs[free_v], theirs[free_v + 1], theirs[free_v + 2]);
        let moment_b = Vector3::new(theirs[free_v + 3], theirs[free_v + 4], theirs[free_v + 5]);
        let our_moment_b = rot.inverse() * ours.root_moment_w;
        assert!(
            (force - ours.root_force_w).norm() < 1e-6 * (1.0 + force.norm()),
            "trial {trial}: root force {force:?} (MuJoCo) vs {:?}",
            ours.root_force_w
        );
        assert!(
            (moment_b - our_moment_b).norm() < 1e-6 * (1.0 + moment_b.norm()),
            "trial {trial}: root moment {moment_b:?} (MuJoCo) vs {our_moment_b:?}"
        );
        for (j, &(_, d)) in joints.iter().enumerate() {
            assert!(
                (theirs[d] - ours.joint_torque_nm[j]).abs() < 1e-6 * (1.0 + theirs[d].abs()),
                "trial {trial}: {} torque {} (MuJoCo) vs {}",
                robot.joints[j].name,
                theirs[d],
                ours.joint_torque_nm[j]
            );
        }
    }
}

/// `file` rewritten with `force_left_sensor`'s element `index` set to `value` (written with
/// safetensors directly: the writer refuses such a force), and the manifest's checksum
/// updated, so only the force bound can refuse it.
fn plant_force(dataset: &Path, file: &str, index: usize, value: f32) {
    let path = dataset.join(file);
    let bytes = std::fs::read(&path).unwrap();
    let st = safetensors::SafeTensors::deserialize(&bytes).unwrap();
    let (_, header) = safetensors::SafeTensors::read_metadata(&bytes).unwrap();
    let mut owned: Vec<(String, Vec<usize>, Vec<u8>)> = st
        .tensors()
        .into_iter()
        .map(|(n, v)| (n, v.shape().to_vec(), v.data().to_vec()))
        .collect();
    let (_, _, data) = owned
        .iter_mut()
        .find(|(n, _, _)| n == "force_left_sensor")
        .unwrap();
    data[4 * index..4 * index + 4].copy_from_slice(&value.to_le_bytes());
    let views: Vec<(String, safetensors::tensor::TensorView)> = owned
        .iter()
        .map(|(n, s, b)| {
            let v = safetensors::tensor::TensorView::new(safetensors::Dtype::F32, s.clone(), b);
            (n.clone(), v.unwrap())
        })
        .collect();
    let planted = safetensors::serialize(views, header.metadata().clone()).unwrap();
    std::fs::write(&path, &planted).unwrap();
    let manifest = dataset.join("manifest.json");
    let mut m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&manifest).unwrap()).unwrap();
    for e in m["sequences"].as_array_mut().unwrap() {
        if e["file"] == file {
            e["sha256"] = serde_json::json!(thorarena::sim::motion::sha256_hex(&planted));
        }
    }
    std::fs::write(&manifest, serde_json::to_string(&m).unwrap()).unwrap();
}

/// A dataset file holding a 1e30 N hand force (an import bug, a hand-edited file) fails
/// `data check`, even with the loosest gate, naming the file, the frame and the field;
/// the same file with 50 N there passes.
#[test]
fn data_check_fails_a_sequence_with_a_force_beyond_the_bound() {
    let tmp = tempfile::tempdir().unwrap();
    let robot = g1();
    let ds = tmp.path().join("ds");
    let mut w = thorarena::sim::motion::DatasetWriter::create(&ds, &robot).unwrap();
    w.add(&standing(&robot, [0.0, 0.0, 5.0])).unwrap();
    w.finish().unwrap();
    let file = "stand/still.safetensors";
    assert!(ds.join(file).is_file());
    let check = || {
        Command::new(BIN)
            .args(["data", "check", ds.to_str().unwrap(), "--max-outside", "1"])
            .output()
            .unwrap()
    };
    plant_force(&ds, file, 3 * 12 + 2, 50.0);
    let ok = check();
    assert!(
        ok.status.success(),
        "{}",
        String::from_utf8_lossy(&ok.stderr)
    );
    plant_force(&ds, file, 3 * 12 + 2, 1e30);
    let bad = check();
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(!bad.status.success(), "passed: {err}");
    for needle in [file, "force_left_sensor", "frame 12", "e30 N", "500 N"] {
        assert!(err.contains(needle), "`{needle}` missing from: {err}");
    }
}

/// A gate that is no share (2, −1, NaN, 1e300) is refused before the check runs: no
/// sequence checked, no `--out` directory made; a dataset of no sequence fails the check
/// instead of passing any gate.
#[test]
fn a_bad_gate_is_refused_before_the_check_and_a_check_over_nothing_fails() {
    let tmp = tempfile::tempdir().unwrap();
    for bad in ["2", "-1", "NaN", "1e300"] {
        let out = tmp.path().join(format!("out-{bad}"));
        let run = Command::new(BIN)
            .args(["data", "check", SAMPLE, "--out", out.to_str().unwrap()])
            .arg(format!("--max-outside={bad}"))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&run.stderr);
        assert!(!run.status.success(), "{bad}: passed: {err}");
        assert!(
            err.contains("--max-outside") && err.contains("share from 0 to 1"),
            "{bad}: {err}"
        );
        assert!(
            !err.contains("checked "),
            "{bad}: the check ran first: {err}"
        );
        assert!(!out.exists(), "{bad}: {} was written", out.display());
        assert!(err.len() < 200, "{bad}: {err}");
    }
    // A dataset whose manifest lists no sequence.
    let empty = tmp.path().join("empty");
    let robot = g1();
    let mut w = thorarena::sim::motion::DatasetWriter::create(&empty, &robot).unwrap();
    w.add(&standing(&robot, [0.0; 3])).unwrap();
    w.finish().unwrap();
    std::fs::remove_dir_all(empty.join("stand")).unwrap();
    let manifest = empty.join("manifest.json");
    let mut m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&manifest).unwrap()).unwrap();
    m["sequences"] = serde_json::json!([]);
    std::fs::write(&manifest, m.to_string()).unwrap();
    assert_eq!(Dataset::open(&empty, &robot).unwrap().len(), 0);
    let run = Command::new(BIN)
        .args([
            "data",
            "check",
            empty.to_str().unwrap(),
            "--max-outside",
            "0",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success(), "a check over nothing passed: {err}");
    assert!(err.contains("no sequence"), "{err}");
}

/// The force spans a run judges a force-trained family's training against
/// (`task_force_spans`, forward kinematics only) are the check's own spans, to the bit,
/// on every task of the sample.
#[test]
fn the_runs_force_spans_are_the_checks_without_its_dynamics() {
    use thorarena::sim::motion::check::task_force_spans;
    let robot = g1();
    let ds = Dataset::open(Path::new(SAMPLE), &robot).unwrap();
    let seqs = ds.load_all().unwrap();
    let started = std::time::Instant::now();
    let check = check_dataset(&ds, &seqs, &robot, &CheckOptions::default(), |_, _| {}).unwrap();
    let check_s = started.elapsed().as_secs_f64();
    let started = std::time::Instant::now();
    let spans = task_force_spans(&seqs, &robot).unwrap();
    let spans_s = started.elapsed().as_secs_f64();
    eprintln!(
        "force spans of the sample: {:.1} ms, the whole check {:.1} ms ({:.1}x)",
        spans_s * 1e3,
        check_s * 1e3,
        check_s / spans_s
    );
    assert_eq!(spans.len(), check.tasks.len());
    for task in &check.tasks {
        assert_eq!(spans[&task.task], task.forces.span, "{}", task.task);
    }
}
