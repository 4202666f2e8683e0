//! `thorarena leaderboard` end to end on a small synthetic dataset (one sequence per task):
//! one run per (policy, engine), the table and the paper's tables and figures written, its
//! numbers those of a separate `eval` of the same policy and data, and a second
//! invocation resumes instead of running again. A single-clip entry (`--clip
//! POLICY@DATASET`) runs on its own dataset under pushes, in a table and report of its own.

use std::path::Path;
use std::process::Command;

mod common;
#[path = "common/in_process.rs"]
mod in_process;

fn summary(run: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(run.join("summary.json")).unwrap()).unwrap()
}

#[test]
fn the_leaderboard_writes_its_tables_and_equals_separate_eval_runs() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("lb");
    let run = || {
        Command::new(env!("CARGO_BIN_EXE_thorarena"))
            .args([
                "leaderboard",
                "--policy",
                "balance",
                "--policy",
                "replay",
                "--engines",
                "rapier",
                "--per-task",
                "1",
                "--clip",
                &format!("hold@{}", out.join("synthetic").display()),
                "--clip-settings",
                "no-force,push:20",
                "--out",
                out.to_str().unwrap(),
            ])
            .output()
            .unwrap()
    };
    let o = run();
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{stderr}");
    let table = String::from_utf8_lossy(&o.stdout).into_owned();
    // One row per policy, each setting's FATS, survival and keypoint error.
    assert!(
        table.contains("| balance | rapier |") && table.contains("| replay | rapier |"),
        "{table}"
    );
    assert!(
        table.contains("FATS force") && table.contains("FATS no-force"),
        "{table}"
    );
    for file in [
        "leaderboard.md",
        "report.html",
        "report.md",
        "report-fats.csv",
        "report-diagnostics.csv",
    ] {
        assert!(out.join(file).is_file(), "{file} missing: {stderr}");
    }
    let figures = std::fs::read_dir(out.join("report-figures"))
        .unwrap()
        .count();
    assert!(figures >= 3, "{figures} figures");
    // The paper's tables: task-level FATS under force and the diagnostics.
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(md.contains("push_chair") && md.contains("Survival"), "{md}");

    // A separate `eval` of balance on the same data gives the same scores.
    let runs = out.join("runs");
    let board = summary(&runs.join("balance-rapier"));
    let separate = in_process::eval(
        &out.join("synthetic"),
        "balance",
        None,
        &["force", "no-force"],
        &dir.path().join("separate"),
    );
    let separate = summary(&separate);
    for setting in ["force", "no-force"] {
        let avg = |s: &serde_json::Value| s["settings"][setting]["average"].clone();
        assert_eq!(avg(&board), avg(&separate), "{setting}");
    }
    let fats = board["settings"]["force"]["average"]["fats"]
        .as_f64()
        .unwrap();
    assert!(
        table.contains(&format!("{fats:.1}")),
        "{fats:.1} not in {table}"
    );

    // Run again: every run is complete, nothing runs twice.
    let o = run();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(
        stderr.contains("0 episodes to run (12 already done)"),
        "{stderr}"
    );
}

#[test]
fn a_policy_process_from_a_policy_file_is_scored_like_the_same_policy_in_process() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("lb");
    // The same controller twice: in process, and as a policy process over shared memory
    // (`thorarena client`), which a lock-step run makes bit-identical.
    let file = dir.path().join("policies.toml");
    std::fs::write(
        &file,
        r#"
[[policy]]
policy = "balance"

[[policy]]
name = "balance-process"
command = "{thorarena} client --session {session} --policy balance"
connect_timeout_s = 60
"#,
    )
    .unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_thorarena"))
        .args(["leaderboard", "--policy-file"])
        .arg(&file)
        .args([
            "--engines",
            "rapier",
            "--per-task",
            "1",
            "--settings",
            "force",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{stderr}");
    let table = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(
        table.contains("| balance | rapier |") && table.contains("| balance-process | rapier |"),
        "{table}"
    );
    let runs = out.join("runs");
    let in_proc = summary(&runs.join("balance-rapier"));
    let process = summary(&runs.join("balance-process-rapier"));
    let avg = |s: &serde_json::Value| s["settings"]["force"]["average"].clone();
    assert_eq!(avg(&in_proc), avg(&process));
    assert!(runs.join("balance-process-rapier.policy.log").is_file());
    // The process's run records why it was not sanity-checked.
    let header: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(runs.join("balance-process-rapier/run.json")).unwrap(),
    )
    .unwrap();
    assert!(
        header["sanity"].to_string().contains("policy process"),
        "{}",
        header["sanity"]
    );
}

#[test]
fn a_policy_process_that_never_connects_fails_the_leaderboard_quoting_its_output() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("policies.toml");
    std::fs::write(
        &file,
        r#"
[[policy]]
name = "broken"
command = "echo 'cannot load the network' >&2; exit 3 # {session}"
connect_timeout_s = 2
"#,
    )
    .unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_thorarena"))
        .args(["leaderboard", "--policy-file"])
        .arg(&file)
        .args([
            "--engines",
            "rapier",
            "--per-task",
            "1",
            "--settings",
            "no-force",
            "--out",
        ])
        .arg(dir.path().join("lb"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(!o.status.success(), "{stderr}");
    assert!(
        stderr.contains("broken on rapier") && stderr.contains("cannot load the network"),
        "{stderr}"
    );
    // A file naming a session no one starts is refused, saying what to give instead.
    std::fs::write(&file, "[[policy]]\npolicy = \"ipc:mine\"\n").unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_thorarena"))
        .args(["leaderboard", "--policy-file"])
        .arg(&file)
        .args(["--engines", "rapier", "--per-task", "1", "--out"])
        .arg(dir.path().join("lb2"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(
        !o.status.success() && stderr.contains("{session}"),
        "{stderr}"
    );
}

/// Issue 42, probe item 13: names that collide or cannot name a run were found late (a
/// policy's log overwritten, an engine run twice), a name went verbatim into
/// `leaderboard.md`, and a policy's `setsid` grandchild outlived the run. Each is refused
/// before anything runs, or stopped with the policy.
#[test]
fn leaderboard_names_are_checked_first_and_a_policys_escaped_descendants_are_stopped() {
    let dir = tempfile::tempdir().unwrap();
    let run = |file_text: &str, extra: &[&str]| {
        let file = dir.path().join("policies.toml");
        std::fs::write(&file, file_text).unwrap();
        Command::new(env!("CARGO_BIN_EXE_thorarena"))
            .args(["leaderboard", "--policy-file"])
            .arg(&file)
            .args(["--per-task", "1", "--settings", "force", "--out"])
            .arg(dir.path().join("lb"))
            .args(extra)
            .output()
            .unwrap()
    };
    let process = |name: &str| {
        format!(
            "[[policy]]\nname = \"{name}\"\ncommand = \"{{thorarena}} client --session {{session}} --policy balance\"\n"
        )
    };
    for (text, extra, wants) in [
        (
            format!("{}{}", process("dup"), process("dup")),
            vec!["--engines", "rapier"],
            "would share the run directory",
        ),
        (
            process("fine"),
            vec!["--engines", "rapier,rapier"],
            "--engines names rapier twice",
        ),
        (
            process("a|b"),
            vec!["--engines", "rapier"],
            "cannot become a file name",
        ),
    ] {
        let o = run(&text, &extra);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && stderr.contains(wants), "{stderr}");
        assert!(
            !dir.path().join("lb/runs").exists(),
            "{wants}: something ran before the refusal"
        );
    }
    // A policy whose command leaves a grandchild in a session of its own, and a long
    // name (its session name once grew past iceoryx2's limit).
    let marker = 3_000_000 + std::process::id() % 1_000_000;
    let long = "p".repeat(60);
    let o = run(
        &format!(
            "[[policy]]\nname = \"{long}\"\ncommand = \"setsid sleep {marker} & {{thorarena}} client --session {{session}} --policy balance\"\nconnect_timeout_s = 60\n"
        ),
        &["--engines", "rapier"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let survivors: Vec<String> = std::fs::read_dir("/proc")
        .unwrap()
        .flatten()
        .filter_map(|e| std::fs::read(e.path().join("cmdline")).ok())
        .map(|c| String::from_utf8_lossy(&c).replace('\0', " "))
        .filter(|c| c.contains(&format!("sleep {marker}")))
        .collect();
    assert!(survivors.is_empty(), "outlived the run: {survivors:?}");
}

mod prereq;

/// FALCON among the general policies and a SoftMimic pair on its own clip: the rows and
/// cells are those of separate `eval` runs of the same policy and data.
#[test]
fn falcon_and_a_compliant_pair_on_the_leaderboard_equal_separate_eval_runs() {
    const TEST: &str = "falcon_and_a_compliant_pair_on_the_leaderboard_equal_separate_eval_runs";
    let (Some(falcon), Some(softmimic)) = (
        prereq::reference(TEST, "falcon/g1_29dof_falcon.onnx"),
        prereq::reference(TEST, "softmimic"),
    ) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("lb");
    let clip = dir.path().join("stand");
    let import = Command::new(env!("CARGO_BIN_EXE_thorarena"))
        .args(["data", "import", "--format", "softmimic-csv"])
        .arg(softmimic.join("motions/stand.csv"))
        .args(["--task", "stand", "--out"])
        .arg(&clip)
        .output()
        .unwrap();
    assert!(
        import.status.success(),
        "{}",
        String::from_utf8_lossy(&import.stderr)
    );
    let onnx = |name: &str| {
        format!(
            "softmimic:{}",
            softmimic.join(format!("onnx/{name}.onnx")).display()
        )
    };
    let pair = format!(
        "{} vs {}@{}",
        onnx("StaticStand-SoftMimic"),
        onnx("StaticStand-Baseline"),
        clip.display()
    );
    let o = Command::new(env!("CARGO_BIN_EXE_thorarena"))
        .args([
            "leaderboard",
            "--engines",
            "rapier",
            "--per-task",
            "1",
            "--settings",
            "no-force,payload:6",
        ])
        .args(["--policy", &format!("falcon:{}", falcon.display())])
        .args([
            "--pair",
            &pair,
            "--pair-seconds",
            "3",
            "--pair-stiffness",
            "300",
        ])
        .args(["--pair-pushes", "20", "--pair-headings", "0,180"])
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{stderr}");
    let table = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(
        table.contains("| falcon (g1_29dof_falcon) | rapier |"),
        "{table}"
    );
    assert!(
        table.contains("compliant − baseline") && table.contains("Δ survival"),
        "{table}"
    );
    assert!(
        table.contains("StaticStand-SoftMimic, stiffness=300"),
        "{table}"
    );
    // Pushes on both hands held for the clip are no SoftMimic training event: marked, with
    // what its training was; FALCON without force replays nothing to mark.
    assert!(
        table.contains(" † |") && table.contains("`softmimic`: events on one wrist at a time"),
        "{table}"
    );
    // FALCON without force replays nothing to mark; 6 kg at each wrist weighs 59 N, beyond
    // the 50 N down of its curriculum: marked, with the reason.
    let falcon_row = table
        .lines()
        .find(|l| l.starts_with("| falcon (g1_29dof_falcon) | rapier |"))
        .unwrap();
    let cells: Vec<&str> = falcon_row.split('|').collect();
    assert!(!cells[3].contains('†'), "no-force: {falcon_row}");
    assert!(cells[7].contains('†'), "payload: {falcon_row}");
    // The global (not re-anchored) keypoint error stands beside the re-anchored one.
    let number = |k: usize| cells[k].trim().parse::<f64>().unwrap();
    assert!(number(5) > 0.0 && number(6) > 0.0, "{falcon_row}");
    assert!(
        table.contains("under `payload:6:hand=both`: its disturbance lies outside")
            && table.contains("59 N down, beyond 50"),
        "{table}"
    );

    // FATS of FALCON's row: a separate eval's.
    let board = summary(&out.join("runs/falcon-g1_29dof_falcon-rapier"));
    let separate = in_process::eval(
        &out.join("synthetic"),
        &format!("falcon:{}", falcon.display()),
        None,
        &["no-force"],
        &dir.path().join("separate-falcon"),
    );
    let avg = |s: &serde_json::Value| s["settings"]["no-force"]["average"].clone();
    assert_eq!(avg(&board), avg(&summary(&separate)));

    // The baseline's pushed cells: a separate eval on the pair's clip.
    let pair_dir = out.join("pairs/StaticStand-SoftMimic-vs-StaticStand-Baseline");
    let separate = in_process::eval(
        &pair_dir.join("clip"),
        &onnx("StaticStand-Baseline"),
        None,
        &["no-force", "push:20@0", "push:20@180"],
        &dir.path().join("separate-baseline"),
    );
    let separate = summary(&separate);
    let csv = std::fs::read_to_string(out.join("pairs.csv")).unwrap();
    for setting in ["push-20@0", "push-20@180"] {
        let fats = separate["settings"][setting]["average"]["fats"]
            .as_f64()
            .unwrap();
        let row = csv
            .lines()
            .find(|l| {
                l.contains(",baseline,") && l.contains(&format!(",push:20@{},", &setting[8..]))
            })
            .unwrap_or_else(|| panic!("{setting} not in\n{csv}"));
        let cell: f64 = row.split(',').nth(6).unwrap().parse().unwrap();
        assert_eq!(cell, fats, "{setting}: {row}");
    }
    // The force log replays a synthetic sequence's forces on the clip, and says so.
    let grafted = std::fs::read_to_string(pair_dir.join("force-log/manifest.json")).unwrap();
    assert!(grafted.contains("stand+forces-push_chair_000"), "{grafted}");
    assert!(csv.contains("force-log:push_chair/push_chair_000"), "{csv}");
}

/// `--pair-seconds 1e300` is refused before anything runs, naming the flag (it once became
/// a clip of 0 s, blamed on the policy's sanity check after the first member started).
#[test]
fn pair_seconds_beyond_any_clip_are_refused_up_front_naming_the_flag() {
    let dir = tempfile::tempdir().unwrap();
    let sample = concat!(env!("CARGO_MANIFEST_DIR"), "/data/sample");
    let (a, b) = (dir.path().join("a.onnx"), dir.path().join("b.onnx"));
    let pair = format!(
        "softmimic:{} vs softmimic:{}@{sample}",
        a.display(),
        b.display()
    );
    for (seconds, shown) in [("1e300", "1e300"), ("1e5", "100000")] {
        let out = dir.path().join("lb");
        let o = Command::new(env!("CARGO_BIN_EXE_thorarena"))
            .args(["leaderboard", "--pair", &pair, "--pair-seconds", seconds])
            .args(["--engines", "rapier", "--out"])
            .arg(&out)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{seconds}: {stderr}");
        assert!(
            stderr.contains(&format!("--pair-seconds {shown}")) && !stderr.contains("sanity"),
            "{seconds}: {stderr}"
        );
        assert!(stderr.len() < 400, "{seconds}: {stderr}");
        assert!(!out.join("pairs").exists(), "{seconds}: a pair ran");
    }
}

/// A policy process whose command changed since its run is not resumed, and the message
/// says what to do with the leaderboard's own flags (`--rerun NAME`), never `eval`'s
/// `--resume` or `--overwrite`; with `--rerun` the run starts again and finishes. A
/// `--rerun` naming no policy of the board is refused before anything runs.
#[test]
fn a_changed_policy_command_is_rerun_with_the_leaderboards_own_flag() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("lb");
    let file = dir.path().join("policies.toml");
    let board = |command: &str, extra: &[&str]| {
        std::fs::write(
            &file,
            format!(
                "[[policy]]\nname = \"bal\"\ncommand = \"{command}\"\nconnect_timeout_s = 60\n"
            ),
        )
        .unwrap();
        let o = Command::new(env!("CARGO_BIN_EXE_thorarena"))
            .args(["leaderboard", "--policy-file"])
            .arg(&file)
            .args([
                "--engines",
                "rapier",
                "--per-task",
                "1",
                "--settings",
                "force",
            ])
            .arg("--out")
            .arg(&out)
            .args(extra)
            .output()
            .unwrap();
        (
            o.status.success(),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )
    };
    let first = "{thorarena} client --session {session} --policy balance";
    let (ok, stderr) = board(first, &[]);
    assert!(ok, "{stderr}");
    // Another controller behind the same name: the run's header differs in its policy.
    let changed = "{thorarena} client --session {session} --policy hold";
    let (ok, stderr) = board(changed, &[]);
    assert!(!ok, "resumed a run of another command: {stderr}");
    assert!(
        stderr.contains("--rerun bal")
            && !stderr.contains("--overwrite")
            && !stderr.contains("--resume"),
        "{stderr}"
    );
    let (ok, stderr) = board(changed, &["--rerun", "other"]);
    assert!(
        !ok && stderr.contains("--rerun") && stderr.contains("`other`"),
        "{stderr}"
    );
    let (ok, stderr) = board(changed, &["--rerun", "bal"]);
    assert!(ok, "{stderr}");
    assert!(stderr.contains("again from the start"), "{stderr}");
    let header = std::fs::read_to_string(out.join("runs/bal-rapier/run.json")).unwrap();
    let header: serde_json::Value = serde_json::from_str(&header).unwrap();
    assert_eq!(header["policy"], "hold", "{header}");
}

/// `--real-walks SETTINGS`: every general policy again on the bundled real human walks, in
/// a table and a report of their own, each run the `eval` of the same policy on
/// `--dataset real-walks` (recorded `unchecked`: the gate is its run on the board's data).
#[test]
fn the_real_walks_track_runs_every_general_policy_on_the_bundled_walks() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("lb");
    let sample = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/sample");
    let o = Command::new(env!("CARGO_BIN_EXE_thorarena"))
        .args(["leaderboard", "--policy", "hold", "--engines", "rapier"])
        .args([
            "--dataset",
            sample.to_str().unwrap(),
            "--settings",
            "no-force",
        ])
        .args([
            "--real-walks",
            "no-force,push:10",
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    let table = String::from_utf8_lossy(&o.stdout);
    let (general, real) = table
        .split_once("on real human walks")
        .unwrap_or_else(|| panic!("no real-walks table: {table}"));
    assert!(general.contains("| hold | rapier |"), "{table}");
    assert!(
        real.contains("| hold | rapier |") && real.contains("FATS push-10"),
        "{table}"
    );
    assert!(out.join("real-walks.html").is_file());
    let run = out.join("runs/hold-rapier-real-walks");
    let header: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("run.json")).unwrap()).unwrap();
    assert_eq!(header["subset"], serde_json::Value::Null, "{header}");
    assert_eq!(header["sequences"].as_array().unwrap().len(), 10);
    // A built-in is exempt from the check wherever it runs; a network would be `unchecked`.
    assert_eq!(header["sanity"]["status"], "exempt");
    // The row is what eval prints for the same policy on the same walks.
    let alone = dir.path().join("alone");
    let e = Command::new(env!("CARGO_BIN_EXE_thorarena"))
        .args([
            "eval",
            "--dataset",
            "real-walks",
            "--policy",
            "hold",
            "--unchecked",
        ])
        .args([
            "--settings",
            "no-force,push:10",
            "--out",
            alone.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(e.status.success(), "{}", String::from_utf8_lossy(&e.stderr));
    assert_eq!(summary(&run)["settings"], summary(&alone)["settings"]);
}
