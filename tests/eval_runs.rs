//! Evaluation runs: shards merged with `thorarena merge` reproduce the single run exactly,
//! and a run killed mid-way resumes without losing or duplicating an episode.

use std::path::Path;
use std::process::Command;

const SAMPLE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/sample");

fn eval(out: &Path, extra: &[&str]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_thorarena"));
    // The force setting only: its episodes end early, which keeps this test quick.
    c.args([
        "eval",
        "--dataset",
        SAMPLE,
        "--policy",
        "hold",
        "--settings",
        "force",
        "--out",
        out.to_str().unwrap(),
    ])
    .args(extra);
    c
}

fn summary_settings(run: &Path) -> serde_json::Value {
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("summary.json")).unwrap()).unwrap();
    v["settings"].clone()
}

fn episodes(run: &Path) -> Vec<String> {
    std::fs::read_to_string(run.join("episodes.jsonl"))
        .unwrap()
        .lines()
        .map(str::to_string)
        .collect()
}

#[test]
fn merged_shards_reproduce_the_single_run_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let full = dir.path().join("full");
    assert!(eval(&full, &[]).output().unwrap().status.success());
    let mut shards = Vec::new();
    for i in 0..3 {
        let out = dir.path().join(format!("shard{i}"));
        let o = eval(&out, &["--shard", &format!("{i}/3"), "--workers", "1"])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        shards.push(out);
    }
    assert_eq!(shards.iter().map(|s| episodes(s).len()).sum::<usize>(), 12);
    let merged = dir.path().join("merged");
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_thorarena"));
    cmd.arg("merge")
        .args(&shards)
        .args(["--out", merged.to_str().unwrap()]);
    let o = cmd.output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(summary_settings(&merged), summary_settings(&full));
    // The same records (a run streams them in completion order; merge writes schedule order).
    let sorted = |mut v: Vec<String>| {
        v.sort();
        v
    };
    assert_eq!(sorted(episodes(&merged)), sorted(episodes(&full)));
    // Two shards only: merge refuses and names what is missing.
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_thorarena"));
    cmd.arg("merge")
        .args(&shards[..2])
        .args(["--out", dir.path().join("partial").to_str().unwrap()]);
    let o = cmd.output().unwrap();
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("are in no shard"));
}

#[test]
fn a_killed_run_resumes_without_losing_or_duplicating_episodes() {
    let dir = tempfile::tempdir().unwrap();
    let full = dir.path().join("full");
    assert!(eval(&full, &[]).output().unwrap().status.success());
    let run = dir.path().join("killed");
    let mut child = eval(&run, &["--workers", "1"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(60);
    loop {
        let n = std::fs::read_to_string(run.join("episodes.jsonl"))
            .map(|t| t.lines().count())
            .unwrap_or(0);
        if n >= 3 {
            break;
        }
        assert!(
            std::time::Instant::now() < deadline,
            "the run produced no episodes"
        );
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let before = episodes(&run).len();
    assert!(before < 12, "killed before the end ({before} episodes)");
    // A torn write at the moment of the kill is tolerated.
    let mut text = std::fs::read_to_string(run.join("episodes.jsonl")).unwrap();
    text.push_str("{\"task\": \"clean_ta");
    std::fs::write(run.join("episodes.jsonl"), text).unwrap();
    let o = eval(&run, &["--resume"]).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let lines = episodes(&run);
    assert_eq!(lines.len(), 12);
    let unique: std::collections::HashSet<_> = lines.iter().collect();
    assert_eq!(unique.len(), 12, "no duplicates");
    assert_eq!(summary_settings(&run), summary_settings(&full));
    // Resuming with another configuration is refused.
    let o = Command::new(env!("CARGO_BIN_EXE_thorarena"))
        .args([
            "eval",
            "--dataset",
            SAMPLE,
            "--policy",
            "replay",
            "--resume",
            "--out",
            run.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(
        !o.status.success() && String::from_utf8_lossy(&o.stderr).contains("another configuration")
    );
}

/// `--tasks` and `--sequences` run part of a dataset, and every file says so: run.json
/// records the selection, tables.md warns it is not full coverage, `report` flags it, and
/// a resume with another selection is refused.
#[test]
fn tasks_and_sequences_run_part_of_a_dataset_and_the_run_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("part");
    let o = eval(
        &run,
        &[
            "--tasks",
            "push_chair,clean_table",
            "--sequences",
            "push_chair_001,clean_table/clean_table_000",
        ],
    )
    .output()
    .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut tasks: Vec<(String, String)> = episodes(&run)
        .iter()
        .map(|l| {
            let v: serde_json::Value = serde_json::from_str(l).unwrap();
            (
                v["task"].as_str().unwrap().to_string(),
                v["sequence_id"].as_str().unwrap().to_string(),
            )
        })
        .collect();
    tasks.sort();
    assert_eq!(
        tasks,
        [
            ("clean_table".to_string(), "clean_table_000".to_string()),
            ("push_chair".to_string(), "push_chair_001".to_string())
        ]
    );
    let header: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("run.json")).unwrap()).unwrap();
    assert_eq!(
        header["subset"]["tasks"],
        serde_json::json!(["push_chair", "clean_table"])
    );
    assert_eq!(header["subset"]["dataset_sequences"], 12);
    let tables = std::fs::read_to_string(run.join("tables.md")).unwrap();
    assert!(
        tables.contains("Part of the dataset: 2 of the dataset's 12 sequences"),
        "{tables}"
    );
    let report = dir.path().join("r.html");
    let o = Command::new(env!("CARGO_BIN_EXE_thorarena"))
        .args([
            "report",
            run.to_str().unwrap(),
            "--out",
            report.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(std::fs::read_to_string(&report)
        .unwrap()
        .contains("ran part of its dataset"));
    // Resuming with the whole dataset is another configuration.
    let o = eval(&run, &["--resume"]).output().unwrap();
    assert!(
        !o.status.success() && String::from_utf8_lossy(&o.stderr).contains("subset"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    // Names the dataset does not hold are errors that say what it has.
    for (flag, value, says) in [
        ("--tasks", "push_chiar", "it has: clean_table"),
        (
            "--sequences",
            "push_chair/clean_table_000",
            "no sequence `push_chair/clean_table_000`",
        ),
        ("--tasks", "push_chair,push_chair", "given twice"),
    ] {
        let o = eval(&dir.path().join("bad"), &[flag, value])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && err.contains(says),
            "{flag} {value}: {err}"
        );
    }
    let o = eval(
        &dir.path().join("bad"),
        &["--tasks", "pull_chair", "--sequences", "clean_table_000"],
    )
    .output()
    .unwrap();
    assert!(
        !o.status.success()
            && String::from_utf8_lossy(&o.stderr).contains("no sequence is of the tasks")
    );
}

/// `episodes.csv` has one row per episode whose scores average to the FATS of
/// `tables.md`, and FATS comes with its bootstrap interval (also in `summary.json`).
#[test]
fn episodes_csv_rows_average_to_the_tables_fats_and_fats_has_an_interval() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("run");
    let o = eval(&run, &[]).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut csv = csv::Reader::from_path(run.join("episodes.csv")).unwrap();
    let head: Vec<String> = csv.headers().unwrap().iter().map(str::to_string).collect();
    assert_eq!(
        head,
        [
            "task",
            "sequence_id",
            "setting",
            "survival",
            "kp_error_mean_mm",
            "kp_error_rms_mm",
            "score",
            "termination"
        ]
    );
    let rows: Vec<csv::StringRecord> = csv.records().map(Result::unwrap).collect();
    assert_eq!(rows.len(), 12);
    let mut by_task: std::collections::BTreeMap<String, Vec<f64>> = Default::default();
    for r in &rows {
        let (mean, rms): (f64, f64) = (r[4].parse().unwrap(), r[5].parse().unwrap());
        assert!(mean > 0.0 && rms >= mean, "RMS ≥ mean: {r:?}");
        by_task
            .entry(r[0].to_string())
            .or_default()
            .push(r[6].parse().unwrap());
    }
    let fats = by_task
        .values()
        .map(|v| v.iter().sum::<f64>() / v.len() as f64)
        .sum::<f64>()
        / by_task.len() as f64;
    let settings = summary_settings(&run);
    let average = settings["force"]["average"]["fats"].as_f64().unwrap();
    assert!((fats - average).abs() < 1e-9, "{fats} vs {average}");
    let ci = &settings["force"]["fats_ci95"];
    let (lo, hi) = (ci[0].as_f64().unwrap(), ci[1].as_f64().unwrap());
    assert!(
        lo < average && average < hi,
        "[{lo}, {hi}] around {average}"
    );
    let tables = std::fs::read_to_string(run.join("tables.md")).unwrap();
    assert!(
        tables.contains(&format!(
            "| 95 % interval (bootstrap over episodes within tasks) | [{lo:.2}, {hi:.2}] |"
        )),
        "{tables}"
    );
    assert!(tables.contains("KP rows are the RMS"), "{tables}");
}

#[test]
fn a_request_file_runs_the_evaluation_its_flags_would() {
    let dir = tempfile::tempdir().unwrap();
    let by_flags = dir.path().join("flags");
    let o = eval(&by_flags, &["--workers", "1"]).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));

    // The same evaluation as a request: the library's type, serialized.
    let request = thorarena::eval::EvalRequest {
        policy: thorarena::policy::registry::PolicySource::parse("hold").unwrap(),
        dataset: Some(SAMPLE.into()),
        settings: vec!["force".parse().unwrap()],
        ..Default::default()
    };
    let file = dir.path().join("request.json");
    request.write(&file).unwrap();
    let by_request = dir.path().join("request");
    let run = |extra: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_thorarena"))
            .args(["eval", "--request", file.to_str().unwrap()])
            .args(extra)
            .output()
            .unwrap()
    };
    let o = run(&["--workers", "1", "--out", by_request.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(summary_settings(&by_request), summary_settings(&by_flags));
    let header = |run: &Path| -> serde_json::Value {
        let mut h: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(run.join("run.json")).unwrap()).unwrap();
        h.as_object_mut().unwrap().remove("created");
        h
    };
    assert_eq!(header(&by_request), header(&by_flags));

    // A flag that describes the evaluation does not go with a request.
    let o = run(&[
        "--settings",
        "no-force",
        "--out",
        by_request.to_str().unwrap(),
    ]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && e.contains("--request"), "{e}");

    // A request with a field no evaluation has is refused, naming the file and the field.
    std::fs::write(&file, r#"{"policy": "hold", "setings": ["force"]}"#).unwrap();
    let o = run(&["--out", dir.path().join("typo").to_str().unwrap()]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && e.contains("request.json") && e.contains("setings"),
        "{e}"
    );
}
