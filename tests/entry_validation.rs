//! Every door refuses what the flags refuse, before anything starts: a request file's
//! budget, shard and selection are held to `eval`'s checks (no panic, no empty run, no key
//! ignored); a budget or measured latency is refused for a policy that runs in process,
//! where it would be recorded and never applied; the leaderboard's pairs are checked
//! before the board runs anything.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

#[path = "common/onnx_model.rs"]
mod onnx_model;

const BIN: &str = env!("CARGO_BIN_EXE_thorarena");
const SAMPLE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/sample");

fn thorarena(args: &[&str]) -> Output {
    Command::new(BIN).args(args).output().unwrap()
}

fn error_of(o: &Output) -> String {
    let e = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(!o.status.success(), "expected an error: {e}");
    assert!(!e.contains("panicked"), "a panic: {e}");
    e
}

/// `eval --request` of `json` (the sample, one sequence, `hold`, with the fields given).
fn eval_request(dir: &Path, json: &str) -> (Output, PathBuf) {
    let request = dir.join("request.json");
    std::fs::write(&request, json).unwrap();
    let out = dir.join("run");
    let o = thorarena(&[
        "eval",
        "--request",
        request.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    (o, out)
}

fn request(fields: &str) -> String {
    format!(
        r#"{{"policy": "hold", "dataset": "{SAMPLE}", "settings": ["no-force"],
            "selection": {{"sequences": ["clean_table_000"]}}, "workers": 1 {fields}}}"#
    )
}

#[test]
fn a_request_files_values_meet_the_flags_checks() {
    let tmp = tempfile::tempdir().unwrap();
    for (fields, says) in [
        (r#", "io": {"budget_s": 1e300}"#, "1 us to 60 s"),
        (r#", "io": {"budget_s": -0.001}"#, "1 us to 60 s"),
        (r#", "shard": [5, 0]"#, "need 0 <= I < N"),
        (r#", "shard": [5, 2]"#, "need 0 <= I < N"),
    ] {
        let (o, out) = eval_request(tmp.path(), &request(fields));
        let e = error_of(&o);
        assert!(e.contains(says), "{fields}: {e}");
        assert!(!e.contains("1000000000000"), "a huge number echoed: {e}");
        assert!(
            !out.join("run.json").exists(),
            "{fields}: a run was written"
        );
    }
    // A misspelt key under `selection` is refused, not ignored (the whole dataset ran).
    let misspelt = format!(
        r#"{{"policy": "hold", "dataset": "{SAMPLE}", "settings": ["no-force"],
            "selection": {{"sequence": ["clean_table_000"]}}}}"#
    );
    let (o, _) = eval_request(tmp.path(), &misspelt);
    let e = error_of(&o);
    assert!(e.contains("unknown field `sequence`"), "{e}");
}

#[test]
fn a_budget_below_a_microsecond_is_refused_not_rounded_to_zero() {
    let tmp = tempfile::tempdir().unwrap();
    let o = thorarena(&[
        "eval",
        "--policy",
        "ipc:nobody-serves-this",
        "--budget",
        "0.0000000000001us",
        "--out",
        tmp.path().join("run").to_str().unwrap(),
    ]);
    let e = error_of(&o);
    assert!(e.contains("1 us to 60 s"), "{e}");
}

#[test]
fn an_in_process_policy_refuses_a_budget_it_would_not_apply() {
    let tmp = tempfile::tempdir().unwrap();
    for flags in [
        &["--budget", "1us", "--miss-rule", "fail"][..],
        &["--latency-mode", "measured"][..],
    ] {
        let out = tmp.path().join("run");
        let mut args = vec![
            "eval",
            "--dataset",
            SAMPLE,
            "--policy",
            "balance",
            "--sequences",
            "clean_table_000",
            "--settings",
            "no-force",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(flags);
        let e = error_of(&thorarena(&args));
        assert!(
            e.contains("runs inside this process") && e.contains("ipc:SESSION"),
            "{flags:?}: {e}"
        );
        assert!(!out.join("run.json").exists());
    }
}

/// A FALCON-shaped network file (the pair checks read files, never run them).
fn network(dir: &Path, name: &str, fill: f32) -> PathBuf {
    let path = dir.join(name);
    let net = onnx_model::Network {
        inputs: vec![("obs", vec![1, 575])],
        outputs: vec![("actions", "obs", 29, fill)],
        metadata: Vec::new(),
    };
    std::fs::write(&path, net.bytes()).unwrap();
    path
}

#[test]
fn the_leaderboards_pairs_are_checked_before_anything_runs() {
    let tmp = tempfile::tempdir().unwrap();
    let a = network(tmp.path(), "a.onnx", 0.0);
    let b = network(tmp.path(), "b.onnx", 1e-4);
    let a_copy = tmp.path().join("a-copy.onnx");
    std::fs::copy(&a, &a_copy).unwrap();
    let (a, b, a_copy) = (a.display(), b.display(), a_copy.display());
    let pair = format!("softmimic:{a} vs softmimic:{b}@{SAMPLE}");
    let cases: Vec<(Vec<String>, &str)> = vec![
        (
            vec![pair.clone(), "--pair-seconds".into(), "0".into()],
            "--pair-seconds 0",
        ),
        (
            vec![pair.clone(), "--pair-seconds".into(), "NaN".into()],
            "--pair-seconds NaN",
        ),
        (
            vec![pair.clone(), "--pair-stiffness=-5".into()],
            "--pair-stiffness",
        ),
        (
            vec![pair.clone(), "--pair-stiffness=NaN".into()],
            "--pair-stiffness",
        ),
        (
            vec![pair.clone(), "--pair-pushes".into(), "1e300".into()],
            "no setting `eval` takes",
        ),
        (
            vec![format!(
                "softmimic:{a}@stiffness=200 vs softmimic:{b}@{SAMPLE}"
            )],
            "names its parameters",
        ),
        (
            vec![format!("softmimic:{a} vs softmimic:{a}@{SAMPLE}")],
            "one network",
        ),
        (
            vec![format!("softmimic:{a} vs softmimic:{a_copy}@{SAMPLE}")],
            "one network",
        ),
        (vec![format!("hold vs balance@{SAMPLE}")], "no network file"),
    ];
    for (i, (args, says)) in cases.into_iter().enumerate() {
        let out = tmp.path().join(format!("board-{i}"));
        let mut all = vec![
            "leaderboard".to_string(),
            "--policy".into(),
            "hold".into(),
            "--dataset".into(),
            SAMPLE.into(),
            "--engines".into(),
            "rapier".into(),
            "--out".into(),
            out.display().to_string(),
            "--pair".into(),
        ];
        all.extend(args);
        let all: Vec<&str> = all.iter().map(String::as_str).collect();
        let e = error_of(&thorarena(&all));
        assert!(e.contains(says), "{all:?}: {e}");
        assert!(
            !out.join("runs").exists(),
            "{all:?}: the board ran before refusing its pair"
        );
    }
}

/// `thorarena args…`, killed after `limit` (a read of `/dev/zero` would otherwise grow
/// memory until the machine gives out, a FIFO would block forever).
fn thorarena_within(args: &[&str], limit: std::time::Duration) -> Output {
    let mut child = Command::new(BIN)
        .args(args)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let started = std::time::Instant::now();
    while child.try_wait().unwrap().is_none() {
        if started.elapsed() > limit {
            child.kill().unwrap();
            let o = child.wait_with_output().unwrap();
            panic!(
                "{args:?} still running after {limit:?}: {}",
                String::from_utf8_lossy(&o.stderr)
            );
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    child.wait_with_output().unwrap()
}

#[test]
fn a_device_or_fifo_is_refused_wherever_a_file_is_read() {
    let tmp = tempfile::tempdir().unwrap();
    let fifo = tmp.path().join("fifo");
    let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
    // SAFETY: a valid NUL-terminated path; mkfifo does not retain it.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    // A dataset whose first sequence file is a link to /dev/zero.
    let ds = tmp.path().join("ds");
    std::fs::create_dir(&ds).unwrap();
    for entry in std::fs::read_dir(SAMPLE).unwrap() {
        let from = entry.unwrap().path();
        if from.is_file() {
            std::fs::copy(&from, ds.join(from.file_name().unwrap())).unwrap();
        }
    }
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(ds.join("manifest.json")).unwrap()).unwrap();
    let first = ds.join(manifest["sequences"][0]["file"].as_str().unwrap());
    std::fs::create_dir_all(first.parent().unwrap()).unwrap();
    std::os::unix::fs::symlink("/dev/zero", &first).unwrap();
    let fifo = fifo.to_str().unwrap();
    let out = tmp.path().join("out");
    let out = out.to_str().unwrap();
    let limit = std::time::Duration::from_secs(60);
    for (args, says) in [
        (
            vec!["eval", "--request", "/dev/zero", "--out", out],
            "is a device, not a file",
        ),
        (
            vec!["eval", "--request", fifo, "--out", out],
            "is a FIFO, not a file",
        ),
        (
            vec![
                "data",
                "import",
                "--format",
                "lafan-csv",
                "/dev/zero",
                "--out",
                out,
                "--task",
                "walk",
            ],
            "is a device, not a file",
        ),
        (
            vec![
                "data",
                "import",
                "--format",
                "twist-pkl",
                fifo,
                "--out",
                out,
                "--task",
                "walk",
            ],
            "is a FIFO, not a file",
        ),
        (
            vec!["view", "/dev/zero", "--out", out],
            "is a device, not a file",
        ),
        (
            vec![
                "eval",
                "--dataset",
                ds.to_str().unwrap(),
                "--policy",
                "hold",
                "--settings",
                "no-force",
                "--out",
                out,
            ],
            "is a device, not a file",
        ),
    ] {
        let e = error_of(&thorarena_within(&args, limit));
        assert!(e.contains(says), "{args:?}: {e}");
    }
}

/// A run is never written into another run's directory (`--out runs/b0/sub`): its files
/// would mix with that run's, and `merge`, `report` and `--resume` of it would not see it.
#[test]
fn a_run_inside_a_run_directory_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("b0");
    let eval = |out: &Path| {
        thorarena(&[
            "eval",
            "--dataset",
            SAMPLE,
            "--policy",
            "hold",
            "--sequences",
            "clean_table_000",
            "--settings",
            "no-force",
            "--workers",
            "1",
            "--out",
            out.to_str().unwrap(),
        ])
    };
    let o = eval(&run);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let inner = run.join("sub");
    let e = error_of(&eval(&inner));
    assert!(e.contains("lies inside the run"), "{e}");
    assert!(!inner.exists(), "the inner run's directory was made");
}
