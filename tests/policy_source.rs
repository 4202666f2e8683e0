//! A policy is one typed value (`PolicySource`), parsed where it enters — a flag, a
//! request file, a sweep spec, a leaderboard's policy file — and refused there with the
//! registry's message; a request may name a command the run starts itself, and a
//! profile's gains are held to bounds a real actuator has before anything runs.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

mod common;
use thorarena::eval::EvalRequest;
use thorarena::policy::launched::PolicyCommand;
use thorarena::policy::registry::PolicySource;

const BIN: &str = env!("CARGO_BIN_EXE_thorarena");

fn thorarena(args: &[&str]) -> Output {
    // Elsewhere than the checkout: a run that is not refused writes nothing there.
    common::run_bin(&std::env::temp_dir(), args)
}

use common::failure as error_of;

fn write(path: &Path, text: &str) -> PathBuf {
    std::fs::write(path, text).unwrap();
    path.to_path_buf()
}

/// `eval --request FILE` into `out`.
fn eval_request(request: &Path, out: &Path) -> Output {
    thorarena(&[
        "eval",
        "--request",
        request.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ])
}

#[test]
fn a_request_files_policy_is_refused_where_the_file_is_read() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    for (policy, says) in [
        (r#""holdx""#, "unknown policy `holdx`"),
        (
            r#""falcon:F.onnx@stiffness=5""#,
            "`falcon` has no parameter `stiffness`",
        ),
        (
            r#""softmimic:F.onnx@stiffness=100,stiffness=200""#,
            "given twice",
        ),
        (
            r#"{"command": "sleep 1", "workdir": "/", "connect_timeout_s": 5}"#,
            "must contain {session}",
        ),
        (
            r#"{"command": "x {session}", "workdir": "/", "connect_timeout_s": 1e300}"#,
            "connect_timeout_s",
        ),
        (
            r#"{"command": "x {session}", "workdir": "/", "connect_timeout_s": 5, "extra": 1}"#,
            "unknown field",
        ),
        ("5", "give a policy argument as a string"),
    ] {
        let request = write(
            &tmp.path().join("request.json"),
            &format!(r#"{{"policy": {policy}, "settings": ["no-force"]}}"#),
        );
        let e = error_of(&eval_request(&request, &out));
        assert!(
            e.contains(says) && e.contains("request.json"),
            "{policy}: {e}"
        );
        assert!(!out.exists(), "{policy}: a refused request wrote {out:?}");
    }
}

#[test]
fn a_policy_is_written_in_todays_spelling_and_read_back_as_the_same_value() {
    let tmp = tempfile::tempdir().unwrap();
    let command = PolicyCommand::new("python3 p.py --session {session}", tmp.path(), 30.0).unwrap();
    for policy in [
        PolicySource::parse("balance").unwrap(),
        PolicySource::parse("softmimic:n/S.onnx@stiffness=60").unwrap(),
        PolicySource::parse("ipc:demo").unwrap(),
        PolicySource::from(command),
    ] {
        let request = EvalRequest {
            policy: policy.clone(),
            ..EvalRequest::default()
        };
        let path = tmp.path().join("r.json");
        request.write(&path).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        match &policy {
            PolicySource::Named(arg) => {
                assert!(
                    text.contains(&format!("\"policy\": \"{}\"", arg.as_str())),
                    "{text}"
                )
            }
            PolicySource::Launched(_) => {
                assert!(text.contains("\"command\": \"python3 p.py"), "{text}")
            }
        }
        assert_eq!(EvalRequest::read(&path).unwrap().policy, policy);
    }
    // The built-ins and a session are made without a string to parse.
    assert_eq!(
        PolicySource::builtin("hold"),
        Some(PolicySource::parse("hold").unwrap())
    );
    assert_eq!(PolicySource::builtin("ipc"), None);
    assert_eq!(
        PolicySource::on_session("s1"),
        PolicySource::parse("ipc:s1").unwrap()
    );
}

#[test]
fn a_request_may_name_a_command_the_run_starts_and_stops() {
    let tmp = tempfile::tempdir().unwrap();
    let request = write(
        &tmp.path().join("request.json"),
        &format!(
            r#"{{"policy": {{"command": "{{thorarena}} client --session {{session}} --policy hold", "workdir": "{}", "connect_timeout_s": 60}},
                "settings": ["no-force"], "selection": {{"sequences": ["push_chair_001"]}}}}"#,
            tmp.path().display()
        ),
    );
    let out = tmp.path().join("run");
    let o = eval_request(&request, &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let log = tmp.path().join("run.policy.log");
    assert!(log.is_file(), "the command's output goes beside the run");
    let records = std::fs::read_to_string(out.join("episodes.jsonl")).unwrap();
    assert_eq!(records.lines().count(), 1, "{records}");
    // A command that cannot start, or exits without connecting, says which it was.
    for (command, workdir, says) in [
        (
            "{thorarena} client --session {session}",
            "/nonexistent",
            "working directory /nonexistent is not a directory",
        ),
        (
            "sh -c 'exit 3' {session}",
            "/",
            "exited (exit status: 3) without connecting",
        ),
    ] {
        let failing = write(
            &tmp.path().join("failing.json"),
            &format!(
                r#"{{"policy": {{"command": "{command}", "workdir": "{workdir}", "connect_timeout_s": 2}},
                    "settings": ["no-force"], "selection": {{"sequences": ["push_chair_001"]}}}}"#
            ),
        );
        let e = error_of(&eval_request(&failing, &tmp.path().join("failed")));
        assert!(e.contains(says), "{command}: {e}");
    }
    // One that exits at once is not waited for: its connect timeout is 60 s.
    let quick = write(
        &tmp.path().join("quick.json"),
        r#"{"policy": {"command": "sh -c 'exit 3' {session}", "workdir": "/", "connect_timeout_s": 60},
            "settings": ["no-force"], "selection": {"sequences": ["push_chair_001"]}}"#,
    );
    let started = std::time::Instant::now();
    let e = error_of(&eval_request(&quick, &tmp.path().join("quick")));
    assert!(
        e.contains("exited (exit status: 3) without connecting"),
        "{e}"
    );
    assert!(
        started.elapsed() < std::time::Duration::from_secs(20),
        "waited {:?} for a command that had exited",
        started.elapsed()
    );
    // A command with nowhere to write its output is refused before it starts.
    let e = error_of(&thorarena(&[
        "eval",
        "--request",
        request.to_str().unwrap(),
    ]));
    assert!(e.contains("--out"), "{e}");
}

#[test]
fn a_profile_with_a_gain_no_actuator_has_is_refused_before_it_runs() {
    let tmp = tempfile::tempdir().unwrap();
    let bundled = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/profiles/default.toml");
    let text = std::fs::read_to_string(bundled).unwrap();
    let wild = text.replacen("knee = 600.0", "knee = 1e300", 1);
    assert_ne!(wild, text, "the profile has no knee kp to change");
    let mine = write(&tmp.path().join("mine.toml"), &wild);
    let out = tmp.path().join("run");
    let e = error_of(&thorarena(&[
        "eval",
        "--policy",
        "hold",
        "--profile",
        mine.to_str().unwrap(),
        "--settings",
        "no-force",
        "--out",
        out.to_str().unwrap(),
    ]));
    assert!(e.contains("kp.knee") && e.contains(" 1e300 "), "{e}");
    assert!(!e.contains("0000000000"), "a number echoed in full: {e}");
    assert!(!out.exists());

    // The same profile as the bundled `default` of a data directory given by
    // THORARENA_DATA: refused too, not run under the name `default`.
    let data = tmp.path().join("data");
    copy_dir(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("data").as_path(),
        &data,
    );
    std::fs::write(data.join("profiles/default.toml"), &wild).unwrap();
    let o = Command::new(BIN)
        .args([
            "eval",
            "--policy",
            "hold",
            "--settings",
            "no-force",
            "--out",
        ])
        .arg(&out)
        .env("THORARENA_DATA", &data)
        .output()
        .unwrap();
    let e = error_of(&o);
    assert!(e.contains("kp.knee"), "{e}");
    assert!(!out.exists());
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        let target = to.join(entry.file_name());
        if entry.file_type().unwrap().is_dir() {
            copy_dir(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), target).unwrap();
        }
    }
}

#[test]
fn a_session_name_the_wire_cannot_carry_is_refused_before_anything_is_served() {
    for args in [
        vec!["eval", "--policy", "ipc:bad name!"],
        vec!["serve", "--session", "", "--once"],
        vec!["serve", "--session", &"s".repeat(65), "--once"],
    ] {
        let e = error_of(&thorarena(&args));
        assert!(e.contains("1 to 64 characters"), "{args:?}: {e}");
        assert!(
            !e.contains("serving session"),
            "{args:?}: served first: {e}"
        );
    }
}

/// A launched policy's output is kept up to a size (`files::capped_log`, 16 MiB), then
/// cut with a note in the log and a warning on the terminal; the process is not stopped
/// by it (its pipe keeps being read). Sweeps and the leaderboard start their policy
/// processes through the same `PolicyCommand::spawn`.
#[test]
fn a_chatty_policys_log_is_capped_with_a_note() {
    let tmp = tempfile::tempdir().unwrap();
    // `yes` writes as fast as the pipe takes it and never connects: 3 s of it would be
    // gigabytes.
    let request = write(
        &tmp.path().join("chatty.json"),
        r#"{"policy": {"command": "yes chatter {session}", "workdir": "/", "connect_timeout_s": 3},
            "settings": ["no-force"], "selection": {"sequences": ["push_chair_001"]}}"#,
    );
    let o = eval_request(&request, &tmp.path().join("run"));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{e}");
    let log = tmp.path().join("run.policy.log");
    let size = std::fs::metadata(&log).unwrap().len();
    let cap = 16 << 20;
    assert!(size > cap && size < cap + 1024, "log of {size} bytes");
    let text = std::fs::read(&log).unwrap();
    let tail = String::from_utf8_lossy(&text[text.len() - 300..]);
    assert!(tail.contains("keeps the first 16777216 bytes"), "{tail}");
    assert!(
        e.contains("warning: ")
            && e.contains("run.policy.log: the policy process's output passed 16 MiB"),
        "{e}"
    );
}
