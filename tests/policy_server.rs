//! The policy server end to end: `thorarena eval --policy ipc:<session>` against policy
//! processes in Rust (`thorarena client`), Python and C++ (`adapters/`) gives the same per-episode
//! results as the same policy in process, bit for bit (lock-step mode); a policy killed
//! with SIGKILL mid-episode ends its episodes as `policy_failed` and `--resume` with a new
//! process completes the run exactly; a late policy misses its deadline and the late
//! reply is counted; two sessions run side by side without crossing; a simulator killed
//! with SIGKILL leaves no shared memory that blocks the next run of its session. (Policies
//! that come and go: `policy_lifecycle.rs`; the slot pipeline: `policy_pipeline.rs`.)

#[path = "../ipc/tests/support/cpp_examples.rs"]
mod cpp_examples;
mod policy_session;
mod prereq;

use policy_session::*;
use std::path::Path;
use std::process::{Command, Stdio};

#[test]
fn balance_rust_policy_against_rust_server_matches_in_process_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let want = in_process("balance", dir.path());
    let s = session("balance");
    let run = over_ipc(&s, dir.path(), || rust_client(&s, "balance", &[]));
    assert_same_records(&episodes(&run), &want);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("summary.json")).unwrap()).unwrap();
    let io = &summary["policy_io"];
    assert!(io["latency"]["count"].as_u64().unwrap() > 100, "{io}");
    assert_eq!(io["deadline_misses"], 0);
    assert_eq!(io["transport"]["policy_failures"], 0);
}

#[test]
fn replay_python_policy_against_rust_server_matches_in_process_bit_for_bit() {
    if !python_ready(
        "policy_server::replay_python_policy_against_rust_server_matches_in_process_bit_for_bit",
    ) {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let want = in_process("replay", dir.path());
    let s = session("python");
    let run = over_ipc(&s, dir.path(), || {
        Command::new("python3")
            .arg(format!(
                "{ROOT}/adapters/python/examples/replay/replay_policy.py"
            ))
            .args(["--session", &s, "--name", "replay", "--timeout", "120"])
            .env("PYTHONPATH", format!("{ROOT}/adapters/python"))
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap()
    });
    assert_same_records(&episodes(&run), &want);
}

#[test]
fn replay_cpp_policy_against_rust_server_matches_in_process_bit_for_bit() {
    let Some(bin) = cpp_examples::examples(
        "policy_server::replay_cpp_policy_against_rust_server_matches_in_process_bit_for_bit",
    ) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let want = in_process("replay", dir.path());
    let s = session("cpp");
    let run = over_ipc(&s, dir.path(), || {
        Command::new(bin.join("replay_policy"))
            .args(["--session", &s, "--name", "replay", "--timeout", "120"])
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap()
    });
    assert_same_records(&episodes(&run), &want);
}

#[test]
fn a_policy_killed_mid_episode_fails_its_episodes_and_resume_completes_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let want = in_process("replay", dir.path());
    let s = session("killed");
    let out = dir.path().join(&s);
    let run = eval_cmd(&format!("ipc:{s}"), &out, &[]).spawn().unwrap();
    let client = rust_client(&s, "replay", &["--die-after-steps", "40"]);
    let run = run.wait_with_output().unwrap();
    let client = client.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    // The policy process's own account, for a run that never met it.
    let client_said = format!(
        "policy process ({}): {}",
        client.status,
        String::from_utf8_lossy(&client.stderr)
    );
    assert!(
        !run.status.success(),
        "the run must report the failure; {client_said}"
    );
    assert!(stderr.contains("did not run"), "{stderr}\n{client_said}");
    let partial = episodes(&out);
    assert!(
        partial.contains("\"termination\":\"policy_failed\""),
        "{partial}"
    );
    // The summary of what finished is written all the same, marked partial.
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["complete"], false);
    let tables = std::fs::read_to_string(out.join("tables.md")).unwrap();
    assert!(
        tables.contains("partial run") && tables.contains("Episodes present / expected"),
        "{tables}"
    );

    let resumed = eval_cmd(&format!("ipc:{s}"), &out, &["--resume"])
        .spawn()
        .unwrap();
    let client = rust_client(&s, "replay", &[]);
    finished(resumed, "resumed eval");
    finished(client, "second policy process");
    let all = episodes(&out);
    assert!(!all.contains("policy_failed"), "failed episodes ran again");
    assert_eq!(sorted_lines(&all), sorted_lines(&want));
}

#[test]
fn a_crashed_simulator_leaves_nothing_that_blocks_the_next_run() {
    use std::io::{BufRead, BufReader};
    let dir = tempfile::tempdir().unwrap();
    let want = in_process("hold", dir.path());
    let s = session("crashed-sim");
    let mut crashed = eval_cmd(&format!("ipc:{s}"), &dir.path().join("crashed"), &[])
        .spawn()
        .unwrap();
    let stderr = BufReader::new(crashed.stderr.take().unwrap());
    for line in stderr.lines() {
        if line.unwrap().contains("waiting for a policy") {
            break; // the session's shared memory exists now
        }
    }
    crashed.kill().unwrap(); // SIGKILL: no cleanup at all
    crashed.wait().unwrap();
    let run = over_ipc(&s, dir.path(), || rust_client(&s, "hold", &[]));
    assert_same_records(&episodes(&run), &want);
}

#[test]
fn a_late_policy_misses_its_deadline_and_the_late_reply_is_counted() {
    let dir = tempfile::tempdir().unwrap();
    let s = session("late");
    let out = dir.path().join(&s);
    let run = eval_cmd(
        &format!("ipc:{s}"),
        &out,
        &["--budget", "20ms", "--miss-rule", "hold"],
    )
    .spawn()
    .unwrap();
    let client = rust_client(&s, "replay", &["--delay-ms", "30", "--delay-at-step", "20"]);
    finished(run, "eval with a budget");
    finished(client, "late policy");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let io = &summary["policy_io"];
    assert!(io["deadline_misses"].as_u64().unwrap() >= 1, "{io}");
    assert!(
        io["transport"]["late_replies"].as_u64().unwrap() >= 1,
        "{io}"
    );
    assert_eq!(summary["header"]["io"]["budget_s"], 0.02);
    let tables = std::fs::read_to_string(out.join("tables.md")).unwrap();
    assert!(tables.contains("Deadline misses"), "{tables}");
    // Every episode still ran.
    assert_eq!(episodes(&out).lines().count(), 12);
}

/// Issue 42: under a budget, a policy too slow for its deadlines first sees episodes
/// mid-way (the simulator stepped them with the miss rule meanwhile). It is scored as
/// slow — every episode recorded, none `policy_failed`, its misses counted — where its
/// own client once quit with "this process never saw it start".
#[test]
fn a_policy_slower_than_its_budget_on_every_step_is_scored_not_failed() {
    let (_dir, s, out, run) = serving(
        "slow",
        &[
            "--budget",
            "5ms",
            "--miss-rule",
            "hold",
            "--latency-mode",
            "measured",
        ],
    );
    let client = rust_client(&s, "replay", &["--delay-ms", "12", "--delay-at-step", "0"]);
    finished(run, "eval with a budget the policy never meets");
    finished(client, "slow policy");
    let records = episodes(&out);
    assert_eq!(records.lines().count(), 12, "{records}");
    assert!(!records.contains("policy_failed"), "{records}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let misses = summary["policy_io"]["deadline_misses"].as_u64().unwrap();
    assert!(misses > 100, "{}", summary["policy_io"]);
}

#[test]
fn two_sessions_side_by_side_never_cross() {
    let dir = tempfile::tempdir().unwrap();
    let want_replay = in_process("replay", dir.path());
    let want_hold = in_process("hold", dir.path());
    let (a, b) = (session("side-a"), session("side-b"));
    let (out_a, out_b) = (dir.path().join(&a), dir.path().join(&b));
    let run_a = eval_cmd(&format!("ipc:{a}"), &out_a, &["--workers", "1"])
        .spawn()
        .unwrap();
    let run_b = eval_cmd(&format!("ipc:{b}"), &out_b, &["--workers", "1"])
        .spawn()
        .unwrap();
    let client_a = rust_client(&a, "replay", &[]);
    let client_b = rust_client(&b, "hold", &[]);
    finished(run_a, "eval a");
    finished(run_b, "eval b");
    finished(client_a, "client a");
    finished(client_b, "client b");
    // Slot assignment differs with one worker; the episodes do not.
    assert_eq!(sorted_lines(&episodes(&out_a)), sorted_lines(&want_replay));
    assert_eq!(sorted_lines(&episodes(&out_b)), sorted_lines(&want_hold));
}

#[test]
fn invalid_actions_never_reach_the_physics_and_follow_the_miss_rule() {
    let dir = tempfile::tempdir().unwrap();
    let want = in_process("hold", dir.path());
    let records = |run: &Path| -> Vec<serde_json::Value> {
        episodes(run)
            .lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect()
    };
    // `hold`: the NaN step applies the last action instead — for the hold policy that is
    // its own zero action, so the episodes are the in-process ones plus a counted fault.
    let s = session("nan-hold");
    let run = over_ipc(&s, dir.path(), || {
        rust_client(&s, "hold", &["--nan-at-step", "30"])
    });
    let held = records(&run);
    let faults: u64 = held
        .iter()
        .map(|r| r["faults"]["invalid_actions"].as_u64().unwrap_or(0))
        .sum();
    assert!(faults >= 1, "the NaN step is counted");
    let strip = |mut r: serde_json::Value| {
        r.as_object_mut().unwrap().remove("faults");
        r.to_string()
    };
    let want_records: Vec<String> = want
        .lines()
        .map(|l| strip(serde_json::from_str(l).unwrap()))
        .collect();
    assert_eq!(
        held.into_iter().map(strip).collect::<Vec<_>>(),
        want_records
    );

    // `fail`: the episodes that got NaN end there, as `invalid_action`.
    let s = session("nan-fail");
    let out = dir.path().join(&s);
    let run = eval_cmd(&format!("ipc:{s}"), &out, &["--miss-rule", "fail"])
        .spawn()
        .unwrap();
    let client = rust_client(&s, "hold", &["--nan-at-step", "30"]);
    finished(run, "eval with --miss-rule fail");
    finished(client, "NaN policy");
    let failed = records(&out);
    let ended: Vec<_> = failed
        .iter()
        .filter(|r| r["termination"] == "invalid_action")
        .collect();
    assert!(!ended.is_empty(), "{failed:?}");
    for r in ended {
        assert_eq!(r["faults"]["invalid_actions"], 1);
        assert!(r["series"]["kp_err_m"].as_array().unwrap().len() < 30);
    }
    assert_eq!(failed.len(), 12, "the other episodes still ran");
}

#[test]
fn measured_latency_delays_actions_in_simulated_time_and_ignored_latency_does_not() {
    let dir = tempfile::tempdir().unwrap();
    let want = in_process("replay", dir.path());
    let slow = ["--delay-ms", "6", "--delay-at-step", "0"];
    let s = session("slow-ignored");
    let run = over_ipc(&s, dir.path(), || rust_client(&s, "replay", &slow));
    assert_same_records(&episodes(&run), &want); // lock-step: latency costs nothing

    let s = session("slow-measured");
    let out = dir.path().join(&s);
    let run = eval_cmd(&format!("ipc:{s}"), &out, &["--latency-mode", "measured"])
        .spawn()
        .unwrap();
    let client = rust_client(&s, "replay", &slow);
    finished(run, "eval with measured latency");
    finished(client, "slow policy");
    let measured = episodes(&out);
    assert_eq!(measured.lines().count(), 12);
    assert_ne!(measured, want, "a 6 ms policy acts a physics step late");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["header"]["io"]["latency_mode"], "measured");
    assert!(summary["policy_io"]["latency"]["p50_us"].as_f64().unwrap() >= 6000.0);
}

#[test]
fn serve_evaluates_the_policy_that_connects() {
    let dir = tempfile::tempdir().unwrap();
    let want = in_process("hold", dir.path());
    let s = session("serve");
    let root = dir.path().join("runs");
    let serve = Command::new(BIN)
        .args(["serve", "--session", &s, "--once", "--out-root"])
        .arg(&root)
        .args(["--dataset", &format!("{ROOT}/data/sample")])
        .args(["--settings", "force", "--connect-timeout", "120"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let client = rust_client(&s, "hold", &[]);
    finished(serve, "serve --once");
    finished(client, "policy");
    assert_same_records(&episodes(&root.join("hold-sample-1")), &want);
}
