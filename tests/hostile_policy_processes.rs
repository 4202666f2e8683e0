//! Hostile policy processes: one declaring a name that would become a path outside the
//! output directory, one stopped and continued mid-run (SIGSTOP/SIGCONT), and a second
//! policy racing for a busy session. Each is a clear refusal or an unchanged result,
//! never a panic, a hang or a file outside the run.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Duration;

mod common;
use common::{failure, run_bin as thorarena};

const BIN: &str = env!("CARGO_BIN_EXE_thorarena");
const SAMPLE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/sample");

#[test]
fn a_policy_process_declaring_a_hostile_name_gets_no_directory() {
    let tmp = tempfile::tempdir().unwrap();
    let work = tmp.path().join("work");
    std::fs::create_dir(&work).unwrap();
    let session = format!("hostile-{}", std::process::id());
    let policy = format!("ipc:{session}");
    let eval = Command::new(BIN)
        .current_dir(&work)
        .args([
            "eval",
            "--dataset",
            SAMPLE,
            "--settings",
            "no-force",
            "--policy",
            &policy,
            "--connect-timeout",
            "5",
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(300));
    let client = Command::new(BIN)
        .args([
            "client",
            "--session",
            &session,
            "--policy",
            "hold",
            "--name",
            "../../escaped",
        ])
        .output()
        .unwrap();
    // The policy is told why in its handshake (it was once told "the run is over" and
    // exited 0); the run waits on for another policy, then times out.
    let told = failure(&client);
    assert!(
        told.contains("refused") && told.contains("cannot become a file name"),
        "{told}"
    );
    let e = failure(&eval.wait_with_output().unwrap());
    assert!(
        e.contains("refused a policy: policy name `../../escaped` cannot become a file name"),
        "{e}"
    );
    assert!(!tmp.path().join("escaped").exists());
    assert!(
        !work.join("results").exists()
            || std::fs::read_dir(work.join("results")).unwrap().count() == 0
    );
}

/// `eval` of the sample without force, serving `session` (output `out` under `cwd`), and
/// after a moment a `thorarena client` running `hold` in it.
fn serve_and_join(
    cwd: &Path,
    session: &str,
    out: &str,
) -> (std::process::Child, std::process::Child) {
    let policy = format!("ipc:{session}");
    let eval = Command::new(BIN)
        .current_dir(cwd)
        .args([
            "eval",
            "--dataset",
            SAMPLE,
            "--settings",
            "no-force",
            "--policy",
            &policy,
            "--connect-timeout",
            "30",
            "--out",
            out,
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(300));
    let client = Command::new(BIN)
        .args(["client", "--session", session, "--policy", "hold"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    (eval, client)
}

#[test]
fn a_policy_process_stopped_and_continued_finishes_the_run_unchanged() {
    let tmp = tempfile::tempdir().unwrap();
    let reference = thorarena(
        tmp.path(),
        &[
            "eval",
            "--dataset",
            SAMPLE,
            "--policy",
            "hold",
            "--settings",
            "no-force",
            "--out",
            "in-process",
        ],
    );
    assert!(reference.status.success());
    let session = format!("stopcont-{}", std::process::id());
    let (eval, client) = serve_and_join(tmp.path(), &session, "remote");
    // Ctrl-Z and `fg`, twice, while episodes run.
    for _ in 0..2 {
        std::thread::sleep(Duration::from_millis(800));
        // SAFETY: signalling the child we started.
        unsafe { libc::kill(client.id() as libc::pid_t, libc::SIGSTOP) };
        std::thread::sleep(Duration::from_millis(300));
        unsafe { libc::kill(client.id() as libc::pid_t, libc::SIGCONT) };
    }
    let out = eval.wait_with_output().unwrap();
    let client_out = client.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "eval: {}\nclient: {}",
        String::from_utf8_lossy(&out.stderr),
        String::from_utf8_lossy(&client_out.stderr)
    );
    assert!(
        client_out.status.success(),
        "{}",
        String::from_utf8_lossy(&client_out.stderr)
    );
    let sorted = |p: &Path| {
        let mut v: Vec<String> = std::fs::read_to_string(p)
            .unwrap()
            .lines()
            .map(String::from)
            .collect();
        v.sort();
        v
    };
    assert!(
        sorted(&tmp.path().join("remote/episodes.jsonl"))
            == sorted(&tmp.path().join("in-process/episodes.jsonl")),
        "the stopped policy's episodes differ from the in-process ones"
    );
}

#[test]
fn a_second_policy_on_a_busy_session_is_told_at_once() {
    let tmp = tempfile::tempdir().unwrap();
    let session = format!("busy-{}", std::process::id());
    let (mut eval, mut first) = serve_and_join(tmp.path(), &session, "run");
    std::thread::sleep(Duration::from_millis(1000));
    let started = std::time::Instant::now();
    let second = Command::new(BIN)
        .args([
            "client",
            "--session",
            &session,
            "--policy",
            "hold",
            "--connect-timeout",
            "30",
        ])
        .output()
        .unwrap();
    let waited = started.elapsed();
    let _ = first.kill();
    let _ = eval.kill();
    let _ = first.wait();
    let _ = eval.wait();
    let e = failure(&second);
    assert!(e.contains("is in use: another policy is connected"), "{e}");
    assert!(
        waited < Duration::from_secs(5),
        "told after {waited:?}, not at once"
    );
}
