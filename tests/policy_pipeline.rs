//! The two-group slot pipeline over shared memory (`--pipeline-depth 2`): the lock-step
//! records from Rust and Python policies, both groups' episodes run again after a
//! reconnect, the rules it refuses, and `bench eval` timing a policy process at both depths.

mod policy_session;
mod prereq;

use policy_session::*;
use std::process::{Command, Stdio};

/// `--pipeline-depth 2`: the workers step one half of the slots while the policy process
/// answers for the other; every episode's record is the lock-step one, for any split of
/// slots over workers, from a Rust and a Python policy process.
#[test]
fn a_two_group_pipeline_gives_the_lock_step_records_over_shared_memory() {
    let dir = tempfile::tempdir().unwrap();
    let want = sorted_lines(&in_process("replay", dir.path()));
    for (workers, envs) in [("2", "2"), ("1", "3"), ("2", "5")] {
        let s = session(&format!("pipe-{workers}-{envs}"));
        let out = dir.path().join(&s);
        let extra = [
            "--pipeline-depth",
            "2",
            "--workers",
            workers,
            "--envs",
            envs,
        ];
        let run = eval_cmd(&format!("ipc:{s}"), &out, &extra).spawn().unwrap();
        let client = rust_client(&s, "replay", &[]);
        finished(run, "eval with a two-group pipeline");
        finished(client, "policy client");
        assert_eq!(
            sorted_lines(&episodes(&out)),
            want,
            "{workers} workers, {envs} slots"
        );
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        assert_eq!(summary["policy_io"]["transport"]["policy_failures"], 0);
    }
    if !python_ready(
        "policy_pipeline::a_two_group_pipeline_gives_the_lock_step_records_over_shared_memory",
    ) {
        return;
    }
    let s = session("pipe-python");
    let out = dir.path().join(&s);
    let run = eval_cmd(
        &format!("ipc:{s}"),
        &out,
        &["--pipeline-depth", "2", "--envs", "4"],
    )
    .spawn()
    .unwrap();
    let client = Command::new("python3")
        .arg(format!(
            "{ROOT}/adapters/python/examples/replay/replay_policy.py"
        ))
        .args(["--session", &s, "--name", "replay", "--timeout", "120"])
        .env("PYTHONPATH", format!("{ROOT}/adapters/python"))
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    finished(run, "eval with a two-group pipeline");
    finished(client, "Python policy");
    assert_eq!(sorted_lines(&episodes(&out)), want, "Python policy");
}

/// A policy that dies while the other group's physics runs: both groups' episodes end
/// (the replacement never continues an episode it did not start) and run again from
/// their start with the policy that reconnects.
#[test]
fn a_two_group_pipeline_reruns_both_groups_episodes_after_a_reconnect() {
    let dir = tempfile::tempdir().unwrap();
    let want = sorted_lines(&in_process("replay", dir.path()));
    let s = session("pipe-reconnect");
    let out = dir.path().join(&s);
    let extra = [
        "--on-policy-failure",
        "wait",
        "--pipeline-depth",
        "2",
        "--envs",
        "4",
    ];
    let run = eval_cmd(&format!("ipc:{s}"), &out, &extra).spawn().unwrap();
    let dying = rust_client(&s, "replay", &["--die-after-steps", "40"]);
    let _ = dying.wait_with_output();
    let second = rust_client(&s, "replay", &[]);
    finished(run, "eval waiting for a reconnect");
    finished(second, "the policy that reconnected");
    let all = episodes(&out);
    assert!(!all.contains("policy_failed"), "{all}");
    assert_eq!(sorted_lines(&all), want);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["policy_io"]["transport"]["policy_failures"], 1);
    assert_eq!(summary["policy_io"]["transport"]["reconnections"], 1);
}

/// The pipeline refuses what it cannot honour, before any policy is awaited.
#[test]
fn a_pipeline_refuses_deadlines_measured_latency_and_too_few_slots() {
    let dir = tempfile::tempdir().unwrap();
    for (extra, says) in [
        (
            &["--pipeline-depth", "2", "--budget", "2ms"][..],
            "--pipeline-depth 2 with --budget",
        ),
        (
            &["--pipeline-depth", "2", "--latency-mode", "measured"][..],
            "--pipeline-depth 2 with --latency-mode measured",
        ),
        (&["--pipeline-depth", "3"][..], "--pipeline-depth 3: 1"),
        (&["--pipeline-depth", "0"][..], "--pipeline-depth 0: 1"),
        (
            &["--pipeline-depth", "2", "--envs", "1"][..],
            "needs at least 2 environment slots",
        ),
    ] {
        let out = eval_cmd("ipc:never-served", &dir.path().join("refused"), extra)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{extra:?}: {stderr}");
        assert!(stderr.contains(says), "{extra:?}: {stderr}");
        assert!(!stderr.contains("waiting for a policy"), "{stderr}");
    }
}

/// `bench eval --policy-command` starts the policy process for each run, times both
/// pipeline depths against each other, counts the process's CPU in the cores busy, and
/// says whether the records agree.
#[test]
fn bench_eval_times_a_policy_process_at_both_pipeline_depths() {
    let out = Command::new(BIN)
        .args(["bench", "eval", "--dataset", &format!("{ROOT}/data/sample")])
        .args(["--settings", "force", "--pipeline-depths", "1,2"])
        .args([
            "--policy-command",
            "{thorarena} client --session {session} --policy replay",
        ])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for line in ["run (depth 1): 12 episodes", "run (depth 2): 12 episodes"] {
        assert!(stdout.contains(line), "{stdout}");
    }
    assert!(stdout.contains("(of it the policy process "), "{stdout}");
    assert!(stdout.contains("ratio: run / floor = "), "{stdout}");
    let versus = stdout
        .lines()
        .find(|l| l.starts_with("versus depth 1: wall "))
        .unwrap_or_else(|| panic!("{stdout}"));
    assert!(versus.ends_with("records identical"), "{versus}");
}
