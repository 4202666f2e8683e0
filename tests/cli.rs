//! The `thorarena` binary: help, `robot info`, `sim trace`, and clean errors on bad input.

use std::process::Command;

fn thorarena(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_thorarena"))
        .args(args)
        .output()
        .expect("run thorarena")
}

#[test]
fn help_lists_the_subcommands() {
    let out = thorarena(&["--help"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    for sub in ["robot", "sim", "bench"] {
        assert!(text.contains(sub), "--help lacks `{sub}`:\n{text}");
    }
}

#[test]
fn robot_info_prints_joints_bodies_mass_and_keypoints() {
    let out = thorarena(&["robot", "info"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("29 joints, 30 bodies, total mass 33.341 kg"),
        "{text}"
    );
    assert!(text.contains("right_wrist_yaw_joint") && text.contains("twist9 (9 points)"));
}

#[test]
fn unknown_robot_is_an_error_message_not_a_panic() {
    let out = thorarena(&["robot", "info", "--robot", "h1_nonexistent"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.starts_with("error: loading robot `h1_nonexistent`") && err.contains("robot.toml"),
        "{err}"
    );
    assert!(!err.contains("panicked"));
}

#[test]
fn sim_trace_prints_one_json_object_with_a_step_per_physics_step() {
    let out = thorarena(&["sim", "trace", "--scenario", "fixed-base"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(v["scenario"], "fixed-base");
    assert_eq!(v["q"].as_array().unwrap().len(), 800); // 4 s at 5 ms
    assert_eq!(v["targets"].as_array().unwrap().len(), 200); // 4 s at 50 Hz
    assert_eq!(v["joint_names"].as_array().unwrap().len(), 29);
    let bad = thorarena(&["sim", "trace", "--scenario", "fixed-base", "--dt", "0"]);
    assert!(!bad.status.success() && String::from_utf8_lossy(&bad.stderr).contains("--dt"));
}

#[test]
fn eval_on_the_sample_streams_every_episode_and_writes_the_tables() {
    let dir = tempfile::tempdir().unwrap();
    let dataset = concat!(env!("CARGO_MANIFEST_DIR"), "/data/sample");
    let out = thorarena(&[
        "eval",
        "--dataset",
        dataset,
        "--policy",
        "hold",
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    for task in [
        "clean_table",
        "liftdown_water",
        "liftup_water",
        "pull_chair",
        "push_chair",
        "syn_carry",
    ] {
        assert!(stdout.contains(&format!("| {task} |")), "{stdout}");
    }
    assert!(stdout.contains("FATS Std") && stdout.contains("torso height error > 0.25 m"));
    let lines = std::fs::read_to_string(dir.path().join("episodes.jsonl")).unwrap();
    assert_eq!(lines.lines().count(), 24, "12 sequences × 2 settings");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("summary.json")).unwrap())
            .unwrap();
    assert!(
        summary["settings"]["force"]["average"]["fats"]
            .as_f64()
            .unwrap()
            >= 0.0
    );
    let bad = thorarena(&["eval", "--dataset", dataset, "--policy", "twist9000"]);
    assert!(
        !bad.status.success() && String::from_utf8_lossy(&bad.stderr).contains("unknown policy")
    );
}

#[test]
fn eval_writes_a_rollout_trace_for_a_named_sequence() {
    let dir = tempfile::tempdir().unwrap();
    let dataset = concat!(env!("CARGO_MANIFEST_DIR"), "/data/sample");
    let args = [
        "eval",
        "--dataset",
        dataset,
        "--policy",
        "hold",
        "--settings",
        "force",
        "--trace",
        "push_chair/push_chair_000",
    ];
    let out = thorarena(&[&args[..], &["--out", dir.path().to_str().unwrap()]].concat());
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let path = dir
        .path()
        .join("traces/push_chair-push_chair_000-force.json");
    let trace: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let steps = trace.as_array().unwrap();
    let episode: serde_json::Value = std::fs::read_to_string(dir.path().join("episodes.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap())
        .find(|r| r["sequence_id"] == "push_chair_000")
        .unwrap();
    assert_eq!(
        steps.len(),
        episode["series"]["kp_err_m"].as_array().unwrap().len(),
        "one trace step per control step"
    );
    assert_eq!(steps[0]["q"].as_array().unwrap().len(), 29);
    assert_eq!(steps[0]["keypoints_w"].as_array().unwrap().len(), 13);
    let force = |s: &serde_json::Value| {
        s["hand_force_w"][0]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap().powi(2))
            .sum::<f64>()
            .sqrt()
    };
    assert!(
        steps.iter().any(|s| force(s) > 1.0),
        "the chair force is replayed"
    );
    let bad = thorarena(&[
        "eval",
        "--dataset",
        dataset,
        "--trace",
        "push_chair/nope",
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    assert!(!bad.status.success() && String::from_utf8_lossy(&bad.stderr).contains("--trace"));
}

/// A misspelt or incomplete policy or profile gets the message a user needs: the file a
/// network family wants, the nearest name, the profiles there are.
#[test]
fn misspelt_policies_and_profiles_get_the_nearest_name_and_what_exists() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("never");
    for (args, says) in [
        (
            vec!["--policy", "twist2"],
            "needs the network's file: `twist2:FILE.onnx`",
        ),
        (vec!["--policy", "beyondmimic:"], "`beyondmimic:FILE.onnx`"),
        (vec!["--policy", "balanc"], "did you mean `balance`?"),
        (vec!["--policy", "ipc"], "ipc:NAME"),
        (
            vec!["--policy", "hold", "--profile", "twist"],
            "did you mean `twist2`?) (bundled: beyondmimic, default, falcon, gmt, holosoma-ppo, holosoma-wbt, softmimic, twist2, wbc-mjlab",
        ),
    ] {
        let mut a = vec!["eval", "--out", out.to_str().unwrap()];
        a.extend(&args);
        let o = thorarena(&a);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(says), "{args:?}: {err}");
    }
    assert!(!out.exists(), "a refused run writes nothing");
}
