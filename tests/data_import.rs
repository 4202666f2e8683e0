//! `thorarena data import` end to end: motions become canonical sequences with joints
//! mapped by name (missing ones zeroed and recorded), force logs resampled onto the motion
//! clock with offset and sign, no forces flagged, and repairs only on request.

use std::path::Path;
use std::process::Command;
use thorarena::sim::motion::import::canonical::{to_sequence, ImportOptions};
use thorarena::sim::motion::import::force_csv::ForceLog;
use thorarena::sim::motion::import::{twist_pkl, RawMotion, G1_CANONICAL_JOINTS};
use thorarena::sim::motion::Dataset;

mod common;
use common::g1;

mod prereq;

fn thorarena(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_thorarena"))
        .args(args)
        .output()
        .expect("run thorarena")
}

/// A LAFAN-style CSV: 31 frames at 30 fps, root moving +x, joints at the default pose.
fn write_lafan(path: &Path, quat_scale: f64) {
    let q0 = g1().default_pose();
    let mut text = String::new();
    for k in 0..31 {
        let mut row = vec![0.01 * k as f64, 0.0, 0.78, 0.0, 0.0, 0.0, quat_scale];
        row.extend(&q0);
        text += &row
            .iter()
            .map(|v| v.to_string())
            .collect::<Vec<_>>()
            .join(",");
        text.push('\n');
    }
    std::fs::write(path, text).unwrap();
}

/// Imports a unit-norm `m.csv` as task `walk` into `<dir>/ds`; returns the dataset dir.
fn import_walk_csv(dir: &Path) -> std::path::PathBuf {
    let motion = dir.join("m.csv");
    write_lafan(&motion, 1.0);
    let out = dir.join("ds");
    let (m, o) = (motion.to_str().unwrap(), out.to_str().unwrap());
    let run = thorarena(&[
        "data",
        "import",
        "--format",
        "lafan-csv",
        m,
        "--out",
        o,
        "--task",
        "walk",
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    out
}

#[test]
fn csv_motion_with_force_logs_is_resampled_shifted_and_sign_flipped() {
    let dir = tempfile::tempdir().unwrap();
    let motion = dir.path().join("wipe_01.csv");
    write_lafan(&motion, 1.0);
    // Left: fx = 10·t at 100 Hz; right: constant fz = 4 N.
    let left: String = "time,fx,fy,fz\n".to_string()
        + &(0..=200)
            .map(|i| format!("{},{},0,0\n", i as f64 * 0.01, 10.0 * i as f64 * 0.01))
            .collect::<String>();
    let right: String = (0..=200)
        .map(|i| format!("{},0,0,4\n", i as f64 * 0.01))
        .collect();
    std::fs::write(dir.path().join("l.csv"), left).unwrap();
    std::fs::write(dir.path().join("r.csv"), right).unwrap();
    let out = dir.path().join("ds");
    let o = thorarena(&[
        "data",
        "import",
        "--format",
        "lafan-csv",
        motion.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--task",
        "clean_table",
        "--forces",
        dir.path().join("l.csv").to_str().unwrap(),
        dir.path().join("r.csv").to_str().unwrap(),
        "--force-offset",
        "0.5",
        "--flip-force-sign",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let seq = Dataset::open(&out, &g1()).unwrap().load(0).unwrap();
    assert_eq!(
        (seq.task.as_str(), seq.sequence_id.as_str(), seq.n_frames()),
        ("clean_table", "wipe_01", 31)
    );
    assert!(seq.forces_recorded);
    // Frame 15 is t = 0.5 s on the motion clock, t = 1.0 s in the log: fx = −10 N after the flip.
    assert!(
        (seq.force_sensor[0][15][0] + 10.0).abs() < 1e-4,
        "{:?}",
        seq.force_sensor[0][15]
    );
    assert!((seq.force_sensor[1][30][2] + 4.0).abs() < 1e-5);
    assert_eq!(seq.provenance["force_offset_s"], 0.5);
}

#[test]
fn motion_without_forces_gets_zero_forces_and_a_flag() {
    let dir = tempfile::tempdir().unwrap();
    let out = import_walk_csv(dir.path());
    let seq = Dataset::open(&out, &g1()).unwrap().load(0).unwrap();
    assert!(!seq.forces_recorded);
    assert!(seq
        .force_sensor
        .iter()
        .flatten()
        .flatten()
        .all(|f| *f == 0.0));
    assert!(seq.provenance["forces"]
        .as_str()
        .unwrap()
        .contains("none recorded"));
}

#[test]
fn quaternions_off_unit_norm_are_rejected_unless_repair_is_asked_for() {
    let dir = tempfile::tempdir().unwrap();
    let motion = dir.path().join("m.csv");
    write_lafan(&motion, 1.05);
    let out = dir.path().join("ds");
    let args = [
        "data",
        "import",
        "--format",
        "lafan-csv",
        motion.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--task",
        "walk",
    ];
    let o = thorarena(&args);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("m.csv") && err.contains("--renormalize-quaternions"),
        "{err}"
    );
    let mut repaired = args.to_vec();
    repaired.push("--renormalize-quaternions");
    let o = thorarena(&repaired);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let seq = Dataset::open(&out, &g1()).unwrap().load(0).unwrap();
    assert_eq!(seq.provenance["renormalized_quaternion_frames"], 31);
}

#[test]
fn a_gmt_motion_without_wrists_gets_zero_wrist_angles_recorded_in_provenance() {
    let robot = g1();
    let names: Vec<String> = G1_CANONICAL_JOINTS
        .iter()
        .filter(|n| !n.contains("wrist"))
        .map(|n| n.to_string())
        .collect();
    assert_eq!(names.len(), 23);
    let raw = RawMotion {
        fps: 30.0,
        root_pos: vec![[0.0, 0.0, 0.8]; 3],
        root_quat_wxyz: vec![[1.0, 0.0, 0.0, 0.0]; 3],
        joint_pos: vec![(0..23).map(|i| 0.01 * i as f64).collect(); 3],
        joint_names: names,
        joint_vel: None,
        provenance: Default::default(),
    };
    let opts = ImportOptions {
        task: "walk".into(),
        sequence_id: "gmt".into(),
        renormalize_quaternions: false,
        trim_glitches: false,
        forces: None::<[ForceLog; 2]>,
        force_offset_s: 0.0,
        force_sign: 1.0,
    };
    let seq = to_sequence(raw, &robot, &opts, Path::new("gmt.pkl")).unwrap();
    let wrist = robot.joint_index("left_wrist_pitch_joint").unwrap();
    let elbow = robot.joint_index("right_elbow_joint").unwrap();
    assert_eq!(seq.joint_pos[0][wrist], 0.0);
    assert!(
        (seq.joint_pos[0][elbow] - 0.22).abs() < 1e-12,
        "right elbow is GMT column 22"
    );
    assert_eq!(
        seq.provenance["missing_joints_set_to_zero"]
            .as_array()
            .unwrap()
            .len(),
        6
    );
}

#[test]
fn imported_twist2_walks_equal_the_pickles_arrays() {
    let Some(motions) = prereq::reference("data_import::twist2_walks", "twist2/motions") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let mut files: Vec<_> = std::fs::read_dir(&motions)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    let mut args = vec![
        "data".to_string(),
        "import".into(),
        "--format".into(),
        "twist-pkl".into(),
    ];
    args.extend(files.iter().map(|f| f.to_str().unwrap().to_string()));
    args.extend([
        "--out".into(),
        dir.path().to_str().unwrap().into(),
        "--task".into(),
        "walk".into(),
    ]);
    let o = Command::new(env!("CARGO_BIN_EXE_thorarena"))
        .args(&args)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let ds = Dataset::open(dir.path(), &g1()).unwrap();
    assert_eq!(ds.len(), files.len());
    for (i, f) in files.iter().enumerate() {
        let raw = twist_pkl::read_twist_pkl(f).unwrap();
        let seq = ds.load(i).unwrap();
        assert_eq!(seq.n_frames(), raw.root_pos.len());
        // Stored as float32: equal to the pickle's float64 values rounded to float32.
        for (a, b) in seq
            .joint_pos
            .iter()
            .flatten()
            .zip(raw.joint_pos.iter().flatten())
        {
            assert_eq!(*a, *b as f32 as f64);
        }
        for (a, b) in seq
            .root_pos
            .iter()
            .flatten()
            .zip(raw.root_pos.iter().flatten())
        {
            assert_eq!(*a, *b as f32 as f64);
        }
    }
}

#[test]
fn exported_npz_holds_the_datasets_arrays_and_an_index() {
    let dir = tempfile::tempdir().unwrap();
    let ds_dir = import_walk_csv(dir.path());
    let out = dir.path().join("npz");
    let o = thorarena(&[
        "data",
        "export",
        "--format",
        "npz",
        ds_dir.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let seq = Dataset::open(&ds_dir, &g1()).unwrap().load(0).unwrap();
    let mut npz = npyz::npz::NpzArchive::open(out.join("walk/m.npz")).unwrap();
    let joint_pos: Vec<f32> = npz
        .by_name("joint_pos")
        .unwrap()
        .unwrap()
        .into_vec()
        .unwrap();
    let expected: Vec<f32> = seq.joint_pos.iter().flatten().map(|v| *v as f32).collect();
    assert_eq!(joint_pos, expected);
    let fps: Vec<f64> = npz.by_name("fps").unwrap().unwrap().into_vec().unwrap();
    assert_eq!(fps, vec![30.0]);
    let index: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("index.json")).unwrap()).unwrap();
    assert_eq!(index["joint_names"].as_array().unwrap().len(), 29);
    assert_eq!(index["sequences"][0]["file"], "walk/m.npz");
}

/// A dataset without force logs: `data info` says so, `eval` runs `no-force` alone by
/// default, refuses an explicit replay setting (it would print a second no-force column
/// under the name `force`) unless asked, and takes a push, which replays nothing.
#[test]
fn a_dataset_without_force_logs_runs_no_force_unless_asked_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let ds = import_walk_csv(dir.path());
    let ds = ds.to_str().unwrap();
    let info = thorarena(&["data", "info", ds]);
    let text = String::from_utf8_lossy(&info.stdout);
    assert!(info.status.success());
    assert!(
        text.contains("1 of 1 sequences have no force logs"),
        "{text}"
    );
    let eval = |out: &str, extra: &[&str]| {
        let out = dir.path().join(out);
        let mut args = vec!["eval", "--dataset", ds, "--policy", "hold", "--out"];
        args.push(out.to_str().unwrap());
        args.extend(extra);
        let o = thorarena(&args);
        (o, out)
    };
    let (o, out) = eval("default", &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stderr).contains("running `no-force` only"));
    let header: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("run.json")).unwrap()).unwrap();
    let names: Vec<&str> = header["settings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["no-force"]);
    for settings in ["force", "no-force,0.5"] {
        let (o, _) = eval("refused", &["--settings", settings]);
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && e.contains("no sequence evaluated"),
            "{settings}: {e}"
        );
    }
    let (o, _) = eval(
        "asked",
        &["--settings", "force", "--replay-without-force-logs"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (o, _) = eval("push", &["--settings", "push:20"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // A sweep refuses the replay setting when it plans, not in every task.
    let spec = dir.path().join("spec.toml");
    std::fs::write(
        &spec,
        format!("datasets = [\"{ds}\"]\nsettings = [\"no-force\", \"0.5\"]\n[[policy]]\npolicy = \"hold\"\n"),
    )
    .unwrap();
    let sweep = dir.path().join("sweep");
    let o = thorarena(&[
        "sweep",
        "plan",
        spec.to_str().unwrap(),
        "--out",
        sweep.to_str().unwrap(),
    ]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && e.contains("has force logs"), "{e}");
}

/// A value a float32 sequence file cannot hold (1e308), or an angle no joint reaches
/// (1e30 rad), is refused naming file, frame and column; appended to an existing dataset,
/// the refusal leaves that dataset whole and readable.
#[test]
fn an_impossible_joint_value_is_refused_and_never_breaks_a_dataset() {
    let dir = tempfile::tempdir().unwrap();
    let ds = import_walk_csv(dir.path());
    for bad in ["1e308", "1e30", "-40"] {
        let motion = dir.path().join("bad.csv");
        write_lafan(&motion, 1.0);
        let text = std::fs::read_to_string(&motion).unwrap();
        let mut rows: Vec<Vec<String>> = text
            .lines()
            .map(|l| l.split(',').map(str::to_string).collect())
            .collect();
        rows[5][7 + 3] = bad.to_string(); // frame 5, left knee
        let text: String = rows.iter().map(|r| r.join(",") + "\n").collect();
        std::fs::write(&motion, text).unwrap();
        let run = thorarena(&[
            "data",
            "import",
            "--format",
            "lafan-csv",
            motion.to_str().unwrap(),
            "--out",
            ds.to_str().unwrap(),
            "--task",
            "walk",
        ]);
        let err = String::from_utf8_lossy(&run.stderr);
        assert!(!run.status.success(), "{bad}: imported: {err}");
        assert!(!err.contains("panicked"), "{err}");
        assert!(
            err.contains("bad.csv") && err.contains("frame 5") && err.contains("left_knee_joint"),
            "{bad}: {err}"
        );
        let dataset = Dataset::open(&ds, &g1()).expect("the dataset is still readable");
        assert_eq!(dataset.len(), 1, "{bad}: the bad sequence was appended");
        dataset.load(0).expect("its sequence still loads");
    }
}

/// A trace as `eval --trace` writes it: 40 steps of 20 ms standing in the default pose
/// with 10 N on each hand; `edit` changes step 5.
fn write_trace(path: &Path, edit: impl Fn(&mut thorarena::eval::episode::TraceStep)) {
    let steps: Vec<thorarena::eval::episode::TraceStep> = (0..40)
        .map(|k| {
            let mut s = thorarena::eval::episode::TraceStep {
                time_s: 0.02 * (k + 1) as f64,
                root_pos: [0.0, 0.0, 0.78],
                root_quat_wxyz: [1.0, 0.0, 0.0, 0.0],
                q: g1().default_pose(),
                targets: g1().default_pose(),
                hand_force_w: [[10.0, 0.0, 0.0]; 2],
                keypoints_w: Vec::new(),
                reference_keypoints_w: Vec::new(),
                kp_err_m: 0.0,
                reference_root_pos: None,
                reference_root_quat_wxyz: None,
                reference_q: None,
                feet: None,
            };
            if k == 5 {
                edit(&mut s);
            }
            s
        })
        .collect();
    std::fs::write(path, serde_json::to_string(&steps).unwrap()).unwrap();
}

fn import_rollout(trace: &Path, out: &Path) -> std::process::Output {
    thorarena(&[
        "data",
        "import",
        "--format",
        "rollout",
        trace.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--task",
        "rollout",
    ])
}

/// `data import --format rollout` meets the bounds every other format meets: a joint at
/// 1e30 rad or a knee at 10 rad (7 past its limit), a zero root quaternion and a 1e30 N
/// hand force are refused naming the file, the step and the field — the quaternion as
/// the quaternion, not as the forces it would have made NaN — and nothing is written.
#[test]
fn a_rollout_beyond_the_import_bounds_is_refused_naming_step_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let clean = dir.path().join("clean.json");
    write_trace(&clean, |_| {});
    let run = import_rollout(&clean, &dir.path().join("ok"));
    assert!(
        run.status.success(),
        "a clean trace: {}",
        String::from_utf8_lossy(&run.stderr)
    );
    type Edit = fn(&mut thorarena::eval::episode::TraceStep);
    let cases: [(&str, Edit, &[&str]); 4] = [
        (
            "far",
            |s| s.q[0] = 1e30,
            &["`q`", "left_hip_pitch_joint", "1e30 rad"],
        ),
        (
            "knee",
            |s| s.q[3] = 10.0,
            &["`q`", "left_knee_joint", "10 rad", "widened by 1 rad"],
        ),
        (
            "zero",
            |s| s.root_quat_wxyz = [0.0; 4],
            &["`root_quat_wxyz`", "root quaternion", "not a rotation"],
        ),
        (
            "force",
            |s| s.hand_force_w[1] = [0.0, 0.0, 1e30],
            &["`hand_force_w` (right)", "1e30 N", "500 N"],
        ),
    ];
    for (name, edit, needles) in cases {
        let trace = dir.path().join(format!("{name}.json"));
        write_trace(&trace, edit);
        let out = dir.path().join(format!("ds-{name}"));
        let run = import_rollout(&trace, &out);
        let err = String::from_utf8_lossy(&run.stderr);
        assert!(!run.status.success(), "{name}: imported: {err}");
        assert!(
            !err.contains("panicked") && !err.contains("force_left_sensor"),
            "{name}: {err}"
        );
        for needle in [&format!("{name}.json"), "step 5"]
            .into_iter()
            .chain(needles.iter().copied())
        {
            assert!(
                err.contains(needle),
                "{name}: `{needle}` missing from: {err}"
            );
        }
        assert!(
            !out.join("manifest.json").exists(),
            "{name}: a dataset was written"
        );
    }
}

/// One 1e30 N sample in a force log is refused naming the log, its row and the force's
/// columns; a 400 N one (beyond any task, within the bound) imports.
#[test]
fn a_force_log_sample_beyond_the_bound_is_refused_naming_file_row_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let motion = dir.path().join("m.csv");
    write_lafan(&motion, 1.0);
    let log = |spike: &str| -> String {
        "time,fx,fy,fz\n".to_string()
            + &(0..=100)
                .map(|i| {
                    let fz = if i == 7 { spike } else { "5" };
                    format!("{},0,0,{fz}\n", i as f64 * 0.01)
                })
                .collect::<String>()
    };
    let right = dir.path().join("r.csv");
    std::fs::write(&right, log("5")).unwrap();
    for (spike, ok) in [("400", true), ("1e30", false)] {
        let left = dir.path().join(format!("left-{spike}.csv"));
        std::fs::write(&left, log(spike)).unwrap();
        let out = dir.path().join(format!("ds-{spike}"));
        let run = thorarena(&[
            "data",
            "import",
            "--format",
            "lafan-csv",
            motion.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--task",
            "clean_table",
            "--forces",
            left.to_str().unwrap(),
            right.to_str().unwrap(),
        ]);
        let err = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.success(), ok, "{spike}: {err}");
        if !ok {
            for needle in [
                &format!("left-{spike}.csv") as &str,
                "row 9",
                "fx, fy, fz",
                "1e30 N",
                "500 N",
            ] {
                assert!(err.contains(needle), "`{needle}` missing from: {err}");
            }
            assert!(!out.join("manifest.json").exists());
        }
    }
}
