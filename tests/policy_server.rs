//! The policy server end to end: `thorarena eval --policy ipc:<session>` against policy
//! processes in Rust (`thorarena client`), Python and C++ (`adapters/`) gives the same per-episode
//! results as the same policy in process, bit for bit (lock-step mode); a policy killed
//! with SIGKILL mid-episode ends its episodes as `policy_failed` and `--resume` with a new
//! process completes the run exactly; a late policy misses its deadline and the late
//! reply is counted; two sessions run side by side without crossing; a simulator killed
//! with SIGKILL leaves no shared memory that blocks the next run of its session.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");
const BIN: &str = env!("CARGO_BIN_EXE_thorarena");

fn session(name: &str) -> String {
    format!("t-{name}-{}", std::process::id())
}

/// `eval` on the sample, force setting only (enough to exercise every task quickly).
fn eval_cmd(policy: &str, out: &Path, extra: &[&str]) -> Command {
    let mut c = Command::new(BIN);
    c.args([
        "eval",
        "--dataset",
        &format!("{ROOT}/data/sample"),
        "--policy",
        policy,
    ])
    .args(["--settings", "force", "--connect-timeout", "120"])
    .args(["--out", out.to_str().unwrap()])
    .args(extra)
    .stdout(Stdio::null())
    .stderr(Stdio::piped());
    c
}

fn rust_client(session: &str, policy: &str, extra: &[&str]) -> Child {
    Command::new(BIN)
        .args([
            "client",
            "--session",
            session,
            "--policy",
            policy,
            "--connect-timeout",
            "120",
        ])
        .args(extra)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

fn finished(child: Child, what: &str) -> Output {
    let out = child.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "{what} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

fn episodes(run: &Path) -> String {
    std::fs::read_to_string(run.join("episodes.jsonl")).unwrap()
}

fn sorted_lines(s: &str) -> Vec<String> {
    let mut v: Vec<String> = s.lines().map(str::to_string).collect();
    v.sort();
    v
}

/// The same policy in process: the reference every remote run must reproduce.
fn in_process(policy: &str, dir: &Path) -> String {
    let out = dir.join(format!("{policy}-in-process"));
    let run = eval_cmd(policy, &out, &[]).spawn().unwrap();
    finished(run, "in-process eval");
    episodes(&out)
}

/// Serves a session, runs `client` against it, returns the run directory.
fn over_ipc(session: &str, dir: &Path, client: impl FnOnce() -> Child) -> PathBuf {
    let out = dir.join(session);
    let run = eval_cmd(&format!("ipc:{session}"), &out, &[])
        .spawn()
        .unwrap();
    let client = client();
    finished(run, "eval over ipc");
    finished(client, "policy client");
    out
}

/// A run serving session `t-NAME-PID` with `extra` flags, in a fresh directory: the
/// directory (kept while it lives), the session, the run directory and the `eval`.
fn serving(name: &str, extra: &[&str]) -> (tempfile::TempDir, String, PathBuf, Child) {
    let dir = tempfile::tempdir().unwrap();
    let s = session(name);
    let out = dir.path().join(&s);
    let run = eval_cmd(&format!("ipc:{s}"), &out, extra).spawn().unwrap();
    (dir, s, out, run)
}

#[path = "../ipc/tests/support/cpp_examples.rs"]
mod cpp_examples;
mod prereq;

fn python_ready(test: &str) -> bool {
    prereq::python_modules(
        test,
        &["iceoryx2", "numpy"],
        "pip install ./adapters/python",
    )
}

#[test]
fn balance_rust_policy_against_rust_server_matches_in_process_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let want = in_process("balance", dir.path());
    let s = session("balance");
    let run = over_ipc(&s, dir.path(), || rust_client(&s, "balance", &[]));
    assert_eq!(episodes(&run), want);
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
    assert_eq!(episodes(&run), want);
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
    assert_eq!(episodes(&run), want);
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
    assert_eq!(episodes(&run), want);
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
    assert_eq!(episodes(&run), want, "lock-step: latency costs nothing");

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
    assert_eq!(episodes(&root.join("hold-sample-1")), want);
}

/// Issue 42: `--resume` rebuilt the policy I/O report from the resumed part only (2 513
/// deadline misses reported where the records held 3 963), and a resume of a complete
/// run reported "latency over 0 steps". The faults now count every record; the latency
/// says which attempt it is of.
#[test]
fn a_resumed_run_reports_the_faults_of_every_episode() {
    let (_dir, s, out, run) = serving("resume-io", &[]);
    // Unusable actions at step 30, then dead at step 400: episodes before stay kept.
    let client = rust_client(
        &s,
        "replay",
        &["--nan-at-step", "30", "--die-after-steps", "400"],
    );
    let _ = run.wait_with_output().unwrap();
    let _ = client.wait_with_output().unwrap();
    let resumed = eval_cmd(&format!("ipc:{s}"), &out, &["--resume"])
        .spawn()
        .unwrap();
    let client = rust_client(&s, "replay", &[]);
    finished(resumed, "resumed eval");
    finished(client, "second policy process");
    let in_records: u64 = episodes(&out)
        .lines()
        .map(|l| {
            let r: serde_json::Value = serde_json::from_str(l).unwrap();
            r["faults"]["invalid_actions"].as_u64().unwrap_or(0)
        })
        .sum();
    assert!(in_records >= 1, "the NaN step is in no record");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(
        summary["policy_io"]["invalid_actions"].as_u64(),
        Some(in_records)
    );
    assert!(summary["policy_io"]["resumed_episodes"].as_u64().unwrap() >= 1);
    let tables = std::fs::read_to_string(out.join("tables.md")).unwrap();
    assert!(tables.contains("The run was resumed"), "{tables}");
    // Resuming the complete run: nothing runs, and the report says so.
    let again = eval_cmd(&format!("ipc:{s}"), &out, &["--resume"])
        .spawn()
        .unwrap();
    let client = rust_client(&s, "replay", &[]);
    finished(again, "resume of a complete run");
    let _ = client.wait_with_output();
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(
        summary["policy_io"]["invalid_actions"].as_u64(),
        Some(in_records)
    );
    let tables = std::fs::read_to_string(out.join("tables.md")).unwrap();
    assert!(
        tables.contains("No control step ran in this attempt"),
        "{tables}"
    );
}

/// Issue 42: in lock-step, a live policy that stops answering stalled `eval` without a
/// word. The wait is reported after 10 s (and the run goes on when the answer comes).
#[test]
fn a_policy_that_keeps_lock_step_waiting_is_reported() {
    let (_dir, s, _out, run) = serving("stall", &["--tasks", "push_chair"]);
    let client = rust_client(&s, "hold", &["--delay-ms", "11500", "--delay-at-step", "5"]);
    let run = finished(run, "eval with a stalling policy");
    finished(client, "stalling policy");
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(
        stderr.contains("has not answered for 10 s") && stderr.contains("alive"),
        "{stderr}"
    );
}

/// Issue 42: of two policies racing for one session, the loser was left waiting for a
/// welcome for its whole connect timeout (120 s here). It is refused as busy as soon as
/// the winner serves the session.
#[test]
fn the_loser_of_a_race_for_a_session_is_refused_as_busy_at_once() {
    let (_dir, s, _out, run) = serving("race", &[]);
    let started = std::time::Instant::now();
    let a = rust_client(&s, "hold", &[]);
    let b = rust_client(&s, "hold", &[]);
    let (a, b) = (a.wait_with_output().unwrap(), b.wait_with_output().unwrap());
    finished(run, "eval");
    let (won, lost) = if a.status.success() { (a, b) } else { (b, a) };
    assert!(
        won.status.success(),
        "{}",
        String::from_utf8_lossy(&won.stderr)
    );
    let refusal = String::from_utf8_lossy(&lost.stderr);
    assert!(!lost.status.success(), "both policies ran the session");
    assert!(refusal.contains("in use"), "{refusal}");
    // The loser was refused while the winner ran, not after a 120 s timeout.
    assert!(
        started.elapsed() < std::time::Duration::from_secs(100),
        "the race took {:?}",
        started.elapsed()
    );
}

/// Issue 42: `serve` made its session again while the Python policy it had just scored
/// was still exiting, took that process's ports for another live run and died. Two
/// Python policies in a row, each started as soon as the one before ends.
#[test]
fn serve_scores_one_python_policy_after_another() {
    const TEST: &str = "policy_server::serve_scores_one_python_policy_after_another";
    if !python_ready(TEST) {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let s = session("serve-py");
    let root = dir.path().join("runs");
    let mut serve = Command::new(BIN)
        .args(["serve", "--session", &s, "--out-root"])
        .arg(&root)
        .args(["--dataset", &format!("{ROOT}/data/sample")])
        .args(["--settings", "force", "--tasks", "push_chair"])
        .args(["--connect-timeout", "120"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    for name in ["first", "second", "third"] {
        let client = Command::new("python3")
            .arg(format!(
                "{ROOT}/adapters/python/examples/replay/replay_policy.py"
            ))
            .args(["--session", &s, "--name", name, "--timeout", "60"])
            .env("PYTHONPATH", format!("{ROOT}/adapters/python"))
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        finished(client, name);
    }
    let _ = serve.kill();
    let out = serve.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("another live run"), "{stderr}");
    for name in ["first", "second", "third"] {
        let scored = std::fs::read_dir(&root).unwrap().flatten().any(|e| {
            e.file_name()
                .to_string_lossy()
                .starts_with(&format!("{name}-sample-"))
                && e.path().join("summary.json").is_file()
        });
        assert!(scored, "{name} was not scored: {stderr}");
    }
}

#[test]
fn a_run_told_to_wait_goes_on_with_a_policy_that_reconnects() {
    let dir = tempfile::tempdir().unwrap();
    let s = session("reconnect");
    let out = dir.path().join(&s);
    let run = eval_cmd(&format!("ipc:{s}"), &out, &["--on-policy-failure", "wait"])
        .spawn()
        .unwrap();
    let dying = rust_client(&s, "replay", &["--die-after-steps", "40"]);
    let _ = dying.wait_with_output();
    let second = rust_client(&s, "replay", &[]);
    finished(run, "eval waiting for a reconnect");
    finished(second, "the policy that reconnected");
    let all = episodes(&out);
    assert_eq!(all.lines().count(), 12, "every episode has one record");
    assert!(
        !all.contains("policy_failed"),
        "the interrupted episode ran again: {all}"
    );
    // ... from its start: the run equals one with a policy that never failed.
    let sorted = |t: &str| {
        let mut v: Vec<&str> = t.lines().collect();
        v.sort();
        v.join("\n")
    };
    let reference = in_process("replay", dir.path());
    assert!(
        sorted(&all) == sorted(&reference),
        "episodes differ from the in-process run"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["policy_io"]["transport"]["policy_failures"], 1);
    assert_eq!(summary["policy_io"]["transport"]["reconnections"], 1);
}

/// Issue 42: a policy dropped for a broken answer (here its batch header) was never told,
/// and waited for observations while a run told to `wait` waited for a policy: neither
/// ever moved. Now it is told to leave, and the run goes on with the next policy.
#[test]
fn a_policy_dropped_for_a_broken_answer_is_told_to_leave_and_the_run_waits_for_another() {
    let (_dir, s, out, run) = serving("broken", &["--on-policy-failure", "wait"]);
    let broken = rust_client(&s, "replay", &["--bad-header-at-step", "40"]);
    let broken = wait_at_most(
        broken,
        std::time::Duration::from_secs(60),
        "the policy with a broken answer",
    );
    assert!(
        String::from_utf8_lossy(&broken.stderr).contains("the run is over"),
        "{}",
        String::from_utf8_lossy(&broken.stderr)
    );
    let second = rust_client(&s, "replay", &[]);
    let run = wait_at_most(
        run,
        std::time::Duration::from_secs(120),
        "eval waiting for a reconnect",
    );
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    finished(second, "the policy that reconnected");
    let all = episodes(&out);
    assert_eq!(all.lines().count(), 12, "every episode has one record");
    assert!(!all.contains("policy_failed"), "{all}");
}

/// Waits for `child` at most `limit`; kills it (by its pid, which we started) and fails
/// the test if it is still running: before liveness came from the policy's node, these
/// runs waited forever.
fn wait_at_most(mut child: Child, limit: std::time::Duration, what: &str) -> Output {
    let start = std::time::Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > limit {
            let _ = child.kill();
            let out = child.wait_with_output().unwrap();
            panic!(
                "{what} still running after {limit:?}: {}",
                String::from_utf8_lossy(&out.stderr)
            );
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    child.wait_with_output().unwrap()
}

#[test]
fn a_policy_that_lies_about_its_pid_and_dies_fails_the_run_instead_of_hanging_it() {
    let dir = tempfile::tempdir().unwrap();
    // Pid 1 is what a policy in a container sees for itself; 0 once meant "always alive".
    // Lock-step, and with a budget (where the dead policy once "missed" every deadline).
    for (pid, extra) in [("1", &[][..]), ("0", &["--budget", "20ms"][..])] {
        let s = session(&format!("liar-{pid}"));
        let out = dir.path().join(&s);
        let run = eval_cmd(&format!("ipc:{s}"), &out, extra).spawn().unwrap();
        let liar = rust_client(
            &s,
            "hold",
            &["--announce-pid", pid, "--die-after-steps", "50"],
        );
        let run = wait_at_most(run, std::time::Duration::from_secs(120), "eval");
        let _ = liar.wait_with_output();
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(
            !run.status.success(),
            "pid {pid}: the run must fail: {stderr}"
        );
        assert!(stderr.contains("ended `policy_failed`"), "{stderr}");
        let records = episodes(&out);
        assert!(records.contains("policy_failed"), "{records}");
    }
}

#[test]
fn eval_exits_non_zero_when_every_episode_was_in_flight_as_its_policy_died() {
    // Every episode of the sample fits the environment slots: all are in flight when the
    // policy dies, so none is left "not run" — the run still failed.
    let dir = tempfile::tempdir().unwrap();
    let s = session("all-in-flight");
    let out = dir.path().join(&s);
    let run = eval_cmd(&format!("ipc:{s}"), &out, &["--envs", "64"])
        .spawn()
        .unwrap();
    let mut dying = rust_client(&s, "hold", &["--die-after-steps", "30"]);
    let start = std::time::Instant::now();
    let mut run = run;
    while run.try_wait().unwrap().is_none() {
        if start.elapsed() > std::time::Duration::from_secs(120) {
            let _ = run.kill();
            let _ = dying.kill();
            let (run, dying) = (
                run.wait_with_output().unwrap(),
                dying.wait_with_output().unwrap(),
            );
            panic!(
                "eval still running after 120 s: {}\nthe policy: {} {}",
                String::from_utf8_lossy(&run.stderr),
                dying.status,
                String::from_utf8_lossy(&dying.stderr)
            );
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    let run = run.wait_with_output().unwrap();
    let _ = dying.wait_with_output();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success(), "{stderr}");
    assert!(stderr.contains("0 did not run"), "{stderr}");
    let records = episodes(&out);
    assert!(
        records.lines().all(|l| l.contains("policy_failed")),
        "{records}"
    );
}

#[test]
fn a_policy_refused_by_the_run_is_told_why_not_that_the_run_is_over() {
    let dir = tempfile::tempdir().unwrap();
    let s = session("refused-resume");
    let out = dir.path().join(&s);
    let run = eval_cmd(&format!("ipc:{s}"), &out, &["--shard", "0/6"])
        .spawn()
        .unwrap();
    let client = rust_client(&s, "hold", &[]);
    finished(run, "first eval");
    finished(client, "hold");
    // Resuming that run with another policy: the policy hears it in its handshake.
    let resumed = Command::new(BIN)
        .args(["eval", "--dataset", &format!("{ROOT}/data/sample")])
        .args(["--policy", &format!("ipc:{s}"), "--settings", "force"])
        .args(["--shard", "0/6", "--resume", "--connect-timeout", "5"])
        .args(["--out", out.to_str().unwrap()])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let other = rust_client(&s, "replay", &["--name", "other"]);
    let told = other.wait_with_output().unwrap();
    let told_err = String::from_utf8_lossy(&told.stderr);
    assert!(!told.status.success(), "{told_err}");
    assert!(
        told_err.contains("refused") && told_err.contains("is a run of policy `hold`, not `other`"),
        "{told_err}"
    );
    let run = wait_at_most(resumed, std::time::Duration::from_secs(60), "eval");
    assert!(!run.status.success());
}

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
        "policy_server::a_two_group_pipeline_gives_the_lock_step_records_over_shared_memory",
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
