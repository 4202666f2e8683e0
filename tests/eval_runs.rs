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
