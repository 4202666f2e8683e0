//! What the policy-server tests share: an `eval` serving a session on the sample, the
//! Rust client (`thorarena client`) joining it, a run's records, and waiting with a limit.
#![allow(dead_code)] // each test file uses part of it

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};

pub const ROOT: &str = env!("CARGO_MANIFEST_DIR");
pub const BIN: &str = env!("CARGO_BIN_EXE_thorarena");

pub fn session(name: &str) -> String {
    format!("t-{name}-{}", std::process::id())
}

/// `eval` on the sample, force setting only (enough to exercise every task quickly).
pub fn eval_cmd(policy: &str, out: &Path, extra: &[&str]) -> Command {
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

pub fn rust_client(session: &str, policy: &str, extra: &[&str]) -> Child {
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

pub fn finished(child: Child, what: &str) -> Output {
    let out = child.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "{what} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

pub fn episodes(run: &Path) -> String {
    std::fs::read_to_string(run.join("episodes.jsonl")).unwrap()
}

/// Two runs hold the same records, bit for bit. `episodes.jsonl` is appended in the order
/// episodes finish, and with two workers that order is the scheduler's (a busy machine
/// finished `push_chair_001` before `push_chair_000` in one run and not in the other):
/// the records are compared as a set, never the file's line order.
pub fn assert_same_records(got: &str, want: &str) {
    let (got, want) = (sorted_lines(got), sorted_lines(want));
    assert_eq!(got.len(), want.len(), "number of records");
    for (g, w) in got.iter().zip(&want) {
        assert_eq!(g, w);
    }
}

pub fn sorted_lines(s: &str) -> Vec<String> {
    let mut v: Vec<String> = s.lines().map(str::to_string).collect();
    v.sort();
    v
}

/// The same policy in process: the reference every remote run must reproduce.
pub fn in_process(policy: &str, dir: &Path) -> String {
    let out = dir.join(format!("{policy}-in-process"));
    let run = eval_cmd(policy, &out, &[]).spawn().unwrap();
    finished(run, "in-process eval");
    episodes(&out)
}

/// Serves a session, runs `client` against it, returns the run directory.
pub fn over_ipc(session: &str, dir: &Path, client: impl FnOnce() -> Child) -> PathBuf {
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
pub fn serving(name: &str, extra: &[&str]) -> (tempfile::TempDir, String, PathBuf, Child) {
    let dir = tempfile::tempdir().unwrap();
    let s = session(name);
    let out = dir.path().join(&s);
    let run = eval_cmd(&format!("ipc:{s}"), &out, extra).spawn().unwrap();
    (dir, s, out, run)
}

/// Waits for `child` at most `limit`; kills it (by its pid, which we started) and fails
/// the test if it is still running: before liveness came from the policy's node, these
/// runs waited forever.
pub fn wait_at_most(mut child: Child, limit: std::time::Duration, what: &str) -> Output {
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

/// Whether the Python client's modules are importable (else `test` is reported skipped).
pub fn python_ready(test: &str) -> bool {
    crate::prereq::python_modules(
        test,
        &["iceoryx2", "numpy"],
        "pip install ./adapters/python",
    )
}
