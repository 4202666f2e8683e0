//! Policy processes that come and go during a run: a resumed run keeps every episode's
//! faults; a lock-step wait on a live policy is reported; two policies racing for one
//! session, a policy told to wait for a reconnect, one dropped for a broken answer, one
//! lying about its pid, one refused by the run — each ends as the run says, never hanging it;
//! `serve` scores one policy after another.

mod policy_session;
mod prereq;

use policy_session::*;
use std::process::{Command, Stdio};

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
    const TEST: &str = "policy_lifecycle::serve_scores_one_python_policy_after_another";
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
