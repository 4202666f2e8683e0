//! SoftMimic (arXiv:2510.17792, github.com/Improbable-AI/softmimic, MIT): its published
//! clips imported with `data import --format softmimic-csv`, and what is refused; its
//! 285-wide observation against `tests/fixtures/softmimic_golden/golden.py` (numpy, from the
//! deploy code's formulas), the released networks' actions against the same script's
//! forward pass, the stiffness command reaching the network and `run.json`, and
//! `policy check` for all six networks on their own clips.
//! Skipped, saying so, when `../shared/reference` is absent; never in CI.

use std::path::{Path, PathBuf};
use std::process::Command;
use thorarena::sim::motion::Dataset;

mod common;
mod prereq;

fn thorarena(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_thorarena"))
        .args(args)
        .output()
        .expect("run thorarena")
}

/// Every clip of `softmimic/motions/`, sorted.
fn clips(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "csv"))
        .collect();
    files.sort();
    files
}

/// `data import --format softmimic-csv FILES --out OUT --task TASK [EXTRA…]`.
fn import(files: &[&Path], out: &Path, task: &str, extra: &[&str]) -> std::process::Output {
    let mut args = vec!["data", "import", "--format", "softmimic-csv"];
    args.extend(extra);
    args.extend(files.iter().map(|f| f.to_str().unwrap()));
    args.extend(["--out", out.to_str().unwrap(), "--task", task]);
    thorarena(&args)
}

#[test]
fn every_published_clip_imports_with_its_frames_and_contacts() {
    const TEST: &str = "every_published_clip_imports_with_its_frames_and_contacts";
    let Some(dir) = prereq::reference(TEST, "softmimic/motions") else {
        return;
    };
    let files = clips(&dir);
    assert!(files.len() >= 7, "{files:?}");
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("ds");
    let refs: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    // The walking clips' quaternions are off unit norm (0.977–0.984, which SoftMimic's
    // motion library normalises as it interpolates): refused unless repair is asked for.
    let run = import(&refs, &out, "softmimic", &[]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success());
    assert!(
        stderr.contains("walk.csv") && stderr.contains("--renormalize-quaternions"),
        "{stderr}"
    );
    let run = import(&refs, &out, "softmimic", &["--renormalize-quaternions"]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let ds = Dataset::open(&out, &common::g1()).unwrap();
    assert_eq!(ds.len(), files.len());
    for (i, file) in files.iter().enumerate() {
        let text = std::fs::read_to_string(file).unwrap();
        let rows: Vec<Vec<f64>> = text
            .lines()
            .filter(|l| !l.trim().is_empty())
            .map(|l| l.split(',').map(|v| v.trim().parse().unwrap()).collect())
            .collect();
        let seq = ds.load(i).unwrap();
        assert_eq!(seq.sequence_id, file.file_stem().unwrap().to_str().unwrap());
        assert_eq!(seq.fps, 30.0);
        assert_eq!(seq.joint_pos.len(), rows.len(), "{}", file.display());
        // Joints in the file's (canonical) order; the quaternion x y z w → w x y z.
        let (first, last) = (&rows[0], &rows[rows.len() - 1]);
        for (j, q) in seq.joint_pos[0].iter().enumerate() {
            assert!(
                (q - first[7 + j]).abs() < 1e-6,
                "{} joint {j}",
                file.display()
            );
        }
        let w = seq.root_quat_wxyz[rows.len() - 1];
        let norm = (last[3..7].iter().map(|v| v * v).sum::<f64>()).sqrt();
        assert!((w[0] - last[6] / norm).abs() < 1e-6, "{}", file.display());
        let contacts = &seq.provenance["foot_contact_frames"];
        let left = rows.iter().filter(|r| r[36] >= 0.5).count();
        assert_eq!(contacts["left"], left, "{}", file.display());
        assert_eq!(seq.provenance["format"], "softmimic-csv");
    }
}

#[test]
fn a_truncated_clip_is_refused_naming_its_file_and_row() {
    const TEST: &str = "a_truncated_clip_is_refused_naming_its_file_and_row";
    let Some(stand) = prereq::reference(TEST, "softmimic/motions/stand.csv") else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(stand).unwrap();
    // Cut in the middle of row 11, as a copy interrupted mid-write leaves it.
    let cut: usize = text.lines().take(10).map(|l| l.len() + 1).sum::<usize>() + 40;
    let truncated = tmp.path().join("stand_cut.csv");
    std::fs::write(&truncated, &text[..cut]).unwrap();
    let out = tmp.path().join("ds");
    let run = import(&[&truncated], &out, "stand", &[]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success());
    assert!(stderr.contains("stand_cut.csv"), "{stderr}");
    assert!(stderr.contains("row 11"), "{stderr}");
    assert!(stderr.contains("truncated"), "{stderr}");
    assert!(!out.join("manifest.json").exists(), "nothing written");

    // A contact flag outside [0, 1], and too few frames.
    let mut rows: Vec<String> = text.lines().take(5).map(str::to_string).collect();
    rows[2] = rows[2].rsplit_once(',').unwrap().0.to_string() + ",1.5";
    let flag = tmp.path().join("flag.csv");
    std::fs::write(&flag, rows.join("\n")).unwrap();
    let run = import(&[&flag], &out, "stand", &[]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success());
    assert!(stderr.contains("row 3, column 38"), "{stderr}");
    let short = tmp.path().join("short.csv");
    std::fs::write(&short, text.lines().take(2).collect::<Vec<_>>().join("\n")).unwrap();
    let run = import(&[&short], &out, "stand", &[]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success());
    assert!(
        stderr.contains("short.csv") && stderr.contains("2 frame(s)"),
        "{stderr}"
    );
}

// ---- the adapter: golden observations, the stiffness command, policy check ----

use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3};
use thorarena::policy::softmimic::observation::{
    frame, History, Layout, Stiffness, ISAAC_FROM_CANONICAL,
};
use thorarena::policy::softmimic::{SoftMimicPolicy, DEFAULT_POSE, DEFAULT_STIFFNESS};
use thorarena::policy::{Observation, Policy};
use thorarena::sim::physics::RootState;

fn numbers(file: &str) -> Vec<f64> {
    common::fixture_numbers("softmimic_golden", file)
}

fn assert_close(ours: &[f32], golden: &[f64], tolerance: f64, what: &str) {
    assert_eq!(ours.len(), golden.len(), "{what}");
    for (i, (o, g)) in ours.iter().zip(golden).enumerate() {
        assert!(
            (f64::from(*o) - g).abs() < tolerance,
            "{what} {i}: ours {o}, golden {g}"
        );
    }
}

/// An observation of the robot (no reference: StaticStand observes none).
fn observation(
    step: usize,
    rotation: UnitQuaternion<f64>,
    w_b: [f64; 3],
    q: Vec<f64>,
    qd: Vec<f64>,
) -> Observation {
    let mut root = RootState::at_rest(Isometry3::from_parts(
        Translation3::new(0.0, 0.0, 0.78),
        rotation,
    ));
    root.ang_vel_w = rotation * Vector3::from(w_b);
    Observation {
        env: 0,
        episode_id: 0,
        step,
        time_s: 0.0,
        root,
        q,
        qd,
        last_action: vec![0.0; 29],
        reference: Vec::new(),
    }
}

/// Case A of the golden script: the default pose at rest, first step, stiffness `k`.
fn case_a(k: f64) -> Vec<f32> {
    let obs = observation(
        0,
        UnitQuaternion::identity(),
        [0.0; 3],
        DEFAULT_POSE.to_vec(),
        vec![0.0; 29],
    );
    let s = Stiffness {
        linear: k,
        rotational: k / 60.0,
    };
    let f = frame(Layout::Stand, &obs, &DEFAULT_POSE, &[0.0; 29], [1.0; 2], s);
    let mut out = vec![0.0; 285];
    History::default().push_into(Layout::Stand, f, true, &[], &mut out);
    out
}

/// Case B: three different frames (the script's `case_b_frames`), oldest first.
fn case_b() -> Vec<f32> {
    let mut history = History::default();
    let mut out = vec![0.0; 285];
    for k in 0..3 {
        let kf = k as f64;
        let rotation = UnitQuaternion::from_quaternion(Quaternion::new(
            1.0,
            0.02 * kf + 0.01,
            -0.03,
            0.05 * kf,
        ));
        let q: Vec<f64> = (0..29)
            .map(|j| {
                DEFAULT_POSE[j]
                    + 0.01 * (j + 1) as f64 * (kf + 1.0) * if j % 2 == 0 { 1.0 } else { -1.0 }
            })
            .collect();
        let qd: Vec<f64> = (0..29)
            .map(|j| 0.1 * (j as f64 - 14.0) + 0.05 * kf)
            .collect();
        let last: Vec<f64> = (0..29)
            .map(|i| 0.02 * (i as f64 - 14.0) + 0.1 * kf)
            .collect();
        let s = 60.0 * 1.25f64.powi(k);
        let obs = observation(
            k as usize,
            rotation,
            [0.1 + 0.1 * kf, -0.2, 0.3 * kf],
            q,
            qd,
        );
        let f = frame(
            Layout::Stand,
            &obs,
            &DEFAULT_POSE,
            &last,
            [1.0; 2],
            Stiffness {
                linear: s,
                rotational: s / 60.0,
            },
        );
        history.push_into(Layout::Stand, f, k == 0, &[], &mut out);
    }
    out
}

#[test]
fn the_285_observation_matches_the_deploy_formulas() {
    assert_close(
        &case_a(60.0),
        &numbers("observation_a.txt"),
        1e-6,
        "case A input",
    );
    assert_close(
        &case_b(),
        &numbers("observation_b.txt"),
        1e-6,
        "case B input",
    );
}

fn network(test: &str, name: &str) -> Option<std::path::PathBuf> {
    prereq::reference(test, &format!("softmimic/onnx/{name}.onnx"))
}

fn load(path: &Path, stiffness: Stiffness) -> SoftMimicPolicy {
    let robot = std::sync::Arc::new(common::g1());
    let profile = thorarena::policy::registry::profile("softmimic", &robot).unwrap();
    SoftMimicPolicy::load(path, robot, &profile, stiffness).unwrap()
}

#[test]
fn the_released_networks_give_the_numpy_forward_pass_actions() {
    const TEST: &str = "the_released_networks_give_the_numpy_forward_pass_actions";
    let (Some(soft), Some(base)) = (
        network(TEST, "StaticStand-SoftMimic"),
        network(TEST, "StaticStand-Baseline"),
    ) else {
        return;
    };
    let soft = load(&soft, DEFAULT_STIFFNESS);
    assert_eq!(soft.layout(), Layout::Stand);
    let a = soft.infer(&case_a(60.0)).unwrap();
    assert_close(&a, &numbers("actions_a.txt"), 2e-5, "case A action");
    let b = soft.infer(&case_b()).unwrap();
    assert_close(&b, &numbers("actions_b.txt"), 2e-5, "case B action");
    let baseline = load(&base, DEFAULT_STIFFNESS).infer(&case_a(60.0)).unwrap();
    assert_close(
        &baseline,
        &numbers("actions_a_baseline.txt"),
        2e-5,
        "baseline action",
    );
}

#[test]
fn the_stiffness_command_reaches_the_network_and_the_record() {
    const TEST: &str = "the_stiffness_command_reaches_the_network_and_the_record";
    let (Some(onnx), Some(clip)) = (
        network(TEST, "StaticStand-SoftMimic"),
        prereq::reference(TEST, "softmimic/motions/pour_pause.csv"),
    ) else {
        return;
    };
    // The same state, two stiffness commands: the actions differ, each as the deploy's
    // formulas and a numpy forward pass give them.
    let soft = load(&onnx, DEFAULT_STIFFNESS);
    let a40 = soft.infer(&case_a(40.0)).unwrap();
    let a800 = soft.infer(&case_a(800.0)).unwrap();
    assert_close(&a40, &numbers("actions_a_stiffness40.txt"), 2e-5, "k = 40");
    assert_close(
        &a800,
        &numbers("actions_a_stiffness800.txt"),
        2e-5,
        "k = 800",
    );
    let largest = a40
        .iter()
        .zip(&a800)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0f32, f32::max);
    assert!(
        largest > 0.01,
        "the stiffness changes the actions by {largest} at most"
    );
    // Through the policy argument, into the run's record.
    let tmp = tempfile::tempdir().unwrap();
    let ds = tmp.path().join("ds");
    assert!(import(&[&clip], &ds, "pour", &[]).status.success());
    for k in ["40", "300"] {
        let out = tmp.path().join(format!("run{k}"));
        let run = thorarena(&[
            "eval",
            "--dataset",
            ds.to_str().unwrap(),
            "--policy",
            &format!("softmimic:{}@stiffness={k}", onnx.display()),
            "--settings",
            "no-force",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
        let header: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("run.json")).unwrap()).unwrap();
        let k: f64 = k.parse().unwrap();
        assert_eq!(header["policy_parameters"]["stiffness_n_per_m"], k);
        assert_eq!(
            header["policy_parameters"]["rotational_stiffness_nm_per_rad"],
            k / 60.0
        );
        assert_eq!(header["policy"], "softmimic");
        assert_eq!(header["profile"], "softmimic");
    }
    // A stiffness the networks never saw is refused, naming the range.
    let run = thorarena(&[
        "eval",
        "--dataset",
        ds.to_str().unwrap(),
        "--policy",
        &format!("softmimic:{}@stiffness=5000", onnx.display()),
        "--out",
        tmp.path().join("bad").to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success());
    assert!(stderr.contains("outside 10 to 1000 N/m"), "{stderr}");
}

/// Each released network with the clip it goes with (`deploy/run_mujoco.sh` names stand
/// and walk; pouring and box picking by name).
const PAIRS: [(&str, &str); 6] = [
    ("StaticStand-SoftMimic", "stand"),
    ("StaticStand-Baseline", "stand"),
    ("Pour-SoftMimic", "pour_single"),
    ("Pour-Baseline", "pour_single"),
    ("GMTWalkStand-SoftMimic", "walk_single"),
    ("AMASSPick1-SoftMimic", "boxpick_single"),
];

#[test]
fn policy_check_passes_for_every_released_network_on_its_own_clip() {
    const TEST: &str = "policy_check_passes_for_every_released_network_on_its_own_clip";
    let Some(dir) = prereq::reference(TEST, "softmimic") else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let ds = tmp.path().join("ds");
    let clips: Vec<PathBuf> = ["stand", "pour_single", "walk_single", "boxpick_single"]
        .iter()
        .map(|c| dir.join(format!("motions/{c}.csv")))
        .collect();
    let refs: Vec<&Path> = clips.iter().map(PathBuf::as_path).collect();
    let run = import(&refs, &ds, "softmimic", &["--renormalize-quaternions"]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    for (network, clip) in PAIRS {
        let out = thorarena(&[
            "policy",
            "check",
            &format!(
                "softmimic:{}",
                dir.join(format!("onnx/{network}.onnx")).display()
            ),
            "--dataset",
            ds.to_str().unwrap(),
            "--sequence",
            clip,
        ]);
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "{network} on {clip}:\n{stdout}\n{}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(stdout.contains("under profile `softmimic`"), "{stdout}");
        assert!(stdout.contains(&format!("softmimic/{clip}")), "{stdout}");
    }
}

#[test]
fn the_policy_acts_in_the_canonical_order() {
    const TEST: &str = "the_policy_acts_in_the_canonical_order";
    let Some(onnx) = network(TEST, "StaticStand-SoftMimic") else {
        return;
    };
    let mut policy = load(&onnx, DEFAULT_STIFFNESS);
    let obs = observation(
        0,
        UnitQuaternion::identity(),
        [0.0; 3],
        DEFAULT_POSE.to_vec(),
        vec![0.0; 29],
    );
    let mut actions = vec![vec![0.0; 29]];
    policy.act(std::slice::from_ref(&obs), &mut actions);
    let golden = numbers("actions_a.txt");
    for (i, &c) in ISAAC_FROM_CANONICAL.iter().enumerate() {
        assert!(
            (actions[0][c] - golden[i]).abs() < 2e-5,
            "Isaac joint {i} → canonical {c}"
        );
    }
}

#[test]
fn a_sweep_varies_the_stiffness_like_any_axis_and_each_run_records_its_value() {
    const TEST: &str = "a_sweep_varies_the_stiffness_like_any_axis_and_each_run_records_its_value";
    let (Some(onnx), Some(clip)) = (
        network(TEST, "StaticStand-SoftMimic"),
        prereq::reference(TEST, "softmimic/motions/pour_pause.csv"),
    ) else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let ds = tmp.path().join("ds");
    assert!(import(&[&clip], &ds, "pour", &[]).status.success());
    let spec = tmp.path().join("stiffness.toml");
    std::fs::write(
        &spec,
        format!(
            "datasets = [\"ds\"]\nsettings = [\"push:20\"]\n\n[[policy]]\npolicy = \"softmimic:{}\"\nparameters = {{ stiffness = [40, 300] }}\n",
            onnx.display()
        ),
    )
    .unwrap();
    let sweep = tmp.path().join("sweep");
    for args in [
        vec![
            "sweep",
            "plan",
            spec.to_str().unwrap(),
            "--out",
            sweep.to_str().unwrap(),
        ],
        vec!["sweep", "run", sweep.to_str().unwrap(), "--jobs", "2"],
        vec!["sweep", "collect", sweep.to_str().unwrap()],
    ] {
        let o = thorarena(&args);
        assert!(
            o.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
    let csv = std::fs::read_to_string(sweep.join("results.csv")).unwrap();
    assert_eq!(
        csv.lines().count(),
        3,
        "a header and one row per stiffness:\n{csv}"
    );
    for k in ["40", "300"] {
        assert!(
            csv.contains(&format!("softmimic:StaticStand-SoftMimic@stiffness={k}")),
            "{csv}"
        );
    }
    let mut recorded: Vec<f64> = walk_run_headers(&sweep)
        .iter()
        .map(|h| {
            h["policy_parameters"]["stiffness_n_per_m"]
                .as_f64()
                .unwrap()
        })
        .collect();
    recorded.sort_by(f64::total_cmp);
    recorded.dedup();
    assert_eq!(
        recorded,
        [40.0, 300.0],
        "the task runs and their collected copies"
    );
}

/// Every `run.json` under `dir`.
fn walk_run_headers(dir: &Path) -> Vec<serde_json::Value> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap().flatten() {
        let path = entry.path();
        if path.is_dir() {
            out.extend(walk_run_headers(&path));
        } else if path.file_name().is_some_and(|n| n == "run.json") {
            out.push(serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap());
        }
    }
    out
}

/// Case C of the golden script: GMTWalkStand-SoftMimic on `walk.csv` at the deploy's first
/// step, whose motion counter has advanced once (reference time 0.02 s), against the
/// adapter at an episode's first step (t = 0): the two agree only because the adapter reads
/// its reference one control step ahead as the deploy does (read at t = 0, the reference
/// joints differ from the golden's by more than the test allows: checked first). The robot
/// is on the reference pose at rest. The reference terms come
/// from ThorArena's own reference (the imported clip, interpolated), the golden's from the
/// deploy's motion library (forward differences at 30 fps, its soft contact labels), so
/// each term is held to what the two constructions can share: joints, height and gravity
/// to 1e-4; the root velocities to 0.05 m/s and the yaw rates to 0.15 rad/s, because
/// ThorArena's reference differentiates centrally and the deploy's library forward, half
/// a 30 fps frame apart (measured here: 0.034 m/s and 0.121 rad/s at most, in the future
/// frames of this turning walk; 0.009 and 0.015 at the current one); and the foot contacts
/// wherever the clip's label is clear (≥ 0.99 or ≤ 0.01; between, the clip's labels are
/// soft and the adapter's are not).
#[test]
fn the_1159_observation_matches_the_deploy_formulas_on_a_walk() {
    const TEST: &str = "the_1159_observation_matches_the_deploy_formulas_on_a_walk";
    let (Some(onnx), Some(walk)) = (
        network(TEST, "GMTWalkStand-SoftMimic"),
        prereq::reference(TEST, "softmimic/motions/walk.csv"),
    ) else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let ds = tmp.path().join("ds");
    let run = import(&[&walk], &ds, "walk", &["--renormalize-quaternions"]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let seq = Dataset::open(&ds, &common::g1()).unwrap().load(0).unwrap();
    let reference = thorarena::sim::motion::Reference::new(&seq);
    let t = 0.0;
    let golden = numbers("observation_c_walk.txt");
    // The golden's newest reference_dof_pos frame (history starts 3 + 3 + 29 · 3 · 3 in)
    // against the reference at the robot's own clock: a walk moves enough in 0.02 s for a
    // one-step lag to fail the 1e-4 below.
    let ref_at = 3 * (3 + 3 + 29 * 3) + 2 * 29;
    let lagging = reference.sample(t);
    let lag = ISAAC_FROM_CANONICAL
        .iter()
        .enumerate()
        .map(|(i, &c)| (lagging.joint_pos[c] - golden[ref_at + i]).abs())
        .fold(0.0, f64::max);
    assert!(
        lag > 1e-3,
        "the walk's first 0.02 s moves a joint by only {lag} rad"
    );
    let mut policy = load(&onnx, DEFAULT_STIFFNESS);
    assert_eq!(policy.layout(), Layout::Track);
    let frames: Vec<_> = policy
        .reference_offsets_s()
        .iter()
        .map(|dt| reference.sample(t + dt))
        .collect();
    let now = &frames[0];
    let mut obs = observation(
        0,
        now.world_from_root.rotation,
        [0.0; 3],
        now.joint_pos.clone(),
        vec![0.0; 29],
    );
    obs.reference = frames.clone();
    let mut actions = vec![vec![0.0; 29]];
    policy.act(std::slice::from_ref(&obs), &mut actions);
    let ours = &policy.last_inputs()[0];
    assert_eq!(ours.len(), golden.len());
    // Index ranges of the terms (history part: 3 frames each).
    let mut at = 0;
    let mut check = |width: usize, tolerance: f64, what: &str, clear_only: bool| {
        for i in at..at + width {
            let (o, mut g) = (f64::from(ours[i]), golden[i]);
            if clear_only {
                // A clear label is the contact it rounds to.
                if (0.01..0.99).contains(&g) {
                    continue;
                }
                g = g.round();
            }
            if std::env::var_os("SOFTMIMIC_GOLDEN_DIFFS").is_some() {
                eprintln!("{what} {i} {:.5}", (o - g).abs());
                continue;
            }
            assert!(
                (o - g).abs() <= tolerance,
                "{what} (input {i}): ours {o}, deploy {g}"
            );
        }
        at += width;
    };
    for (width, tolerance, what) in [
        (3, 1e-6, "base_ang_vel"),
        (3, 1e-4, "projected_gravity"),
        (29, 1e-5, "joint_pos"),
        (29, 1e-6, "joint_vel"),
        (29, 1e-6, "actions"),
        (29, 1e-4, "reference_dof_pos"),
        (2, 0.05, "reference_xy_vel"),
        (1, 0.15, "reference_yaw_vel"),
        (1, 1e-4, "reference_root_height"),
        (3, 1e-3, "reference_gravity"),
    ] {
        check(width * 3, tolerance, what, false);
    }
    check(2 * 3, 0.0, "reference_foot_contact", true);
    check(3, 1e-6, "desired_stiffness_log", false);
    check(3, 1e-6, "desired_rotational_stiffness_log", false);
    for (width, tolerance, what, clear) in [
        (29, 1e-4, "reference_dof_pos_future", false),
        (2, 0.05, "reference_xy_vel_future", false),
        (1, 0.15, "reference_yaw_vel_future", false),
        (1, 1e-4, "reference_root_height_future", false),
        (3, 1e-3, "reference_gravity_future", false),
        (2, 0.0, "reference_foot_contact_future", true),
    ] {
        check(width * 20, tolerance, what, clear);
    }
    assert_eq!(at, 1159);
}
