//! `policy check ipc:SESSION`: a policy process passes the same gate as a network in
//! process — standing, tracking a reference, and doing clearly worse with zero action —
//! under the profile it declares, with the same report as the same policy in process.
//! Python's replay example passes it over a session on the first 3 s of the sample's
//! table-cleaning sequence (it is open loop: it falls after 3.6 s of that reference, and
//! at once on a walk, as `replay` does in process); a process that answers zeros (the PD
//! alone holding the default pose) is no better than zero action, and the command fails
//! naming the check.

mod policy_session;
mod prereq;

use policy_session::*;
use std::process::{Command, Stdio};
use std::time::Duration;

/// `policy check ipc:S` against the Python process `script` (its arguments `args`, after
/// `--session S`): the check's output and exit status, and the process's.
fn check_against(
    name: &str,
    script: &[&str],
    extra: &[&str],
) -> (std::process::Output, std::process::Output) {
    let s = session(name);
    let check = Command::new(BIN)
        .args(["policy", "check", &format!("ipc:{s}")])
        .args(["--sequence", "clean_table_000"])
        .args(extra)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let client = Command::new("python3")
        .args(script)
        .args(["--session", &s])
        .env("PYTHONPATH", format!("{ROOT}/adapters/python"))
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let check = wait_at_most(check, Duration::from_secs(300), "policy check");
    let client = wait_at_most(client, Duration::from_secs(60), "the policy process");
    (check, client)
}

#[test]
fn the_python_replay_process_passes_and_a_process_of_zeros_fails() {
    let test =
        "process_policy_check::the_python_replay_process_passes_and_a_process_of_zeros_fails";
    if !python_ready(test) {
        return;
    }
    let replay = format!("{ROOT}/adapters/python/examples/replay/replay_policy.py");
    let script = [replay.as_str(), "--timeout", "60", "--name", "replay"];
    // The whole default window: the report in process, line for line.
    let in_process = Command::new(BIN)
        .args(["policy", "check", "replay", "--sequence", "clean_table_000"])
        .output()
        .unwrap();
    let (check, client) = check_against("replay-10s", &script, &[]);
    assert!(
        client.status.success(),
        "{}",
        String::from_utf8_lossy(&client.stderr)
    );
    assert_eq!(
        String::from_utf8_lossy(&check.stdout),
        String::from_utf8_lossy(&in_process.stdout)
    );
    assert_eq!(check.status.code(), in_process.status.code());
    let (check, client) = check_against("replay", &script, &["--track-seconds", "3"]);
    let out = String::from_utf8_lossy(&check.stdout);
    let err = String::from_utf8_lossy(&check.stderr);
    assert!(check.status.success(), "{out}\n{err}");
    assert!(
        client.status.success(),
        "{}",
        String::from_utf8_lossy(&client.stderr)
    );
    for name in ["pass stand", "pass track", "pass zero_action"] {
        assert!(out.contains(name), "{name}: {out}");
    }
    let zeros = r#"
import argparse, thorarena as ta
p = argparse.ArgumentParser(); p.add_argument("--session"); a = p.parse_args()
s = ta.connect(a.session, name="zeros", joint_names=ta.G1_JOINT_NAMES, timeout_s=60, profile="default")
for obs, actions in s.steps():
    actions[:] = 0.0
"#;
    let (check, client) = check_against("zeros", &["-c", zeros], &["--track-seconds", "3"]);
    let out = String::from_utf8_lossy(&check.stdout);
    let err = String::from_utf8_lossy(&check.stderr);
    assert!(!check.status.success(), "a process of zeros passed: {out}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(out.contains("FAIL"), "{out}");
    assert!(err.contains("policy check failed ("), "{err}");
    assert!(
        client.status.success(),
        "{}",
        String::from_utf8_lossy(&client.stderr)
    );
}
