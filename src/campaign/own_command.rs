//! The `thorarena` command lines the library runs, or writes for a cluster engine to run:
//! a sweep task's `eval` of its request, the array task's `sweep task`, and the
//! benchmarks' sweep steps, echo client and socket peer. They are the binary's interface,
//! spelled here once; the tests that run them (sweeps, real Slurm, the Kubernetes manifest,
//! the benchmarks) keep them true to its parser.

use std::ffi::OsString;
use std::path::Path;

/// `eval --request REQUEST --out OUT --workers N --resume`, and for a launched policy
/// the seconds it has to connect: the evaluation a sweep task's attempt runs.
pub fn eval_of_request(
    request: &Path,
    out: &Path,
    workers: usize,
    connect_timeout_s: Option<f64>,
) -> Vec<OsString> {
    let mut words = eval_once(request, out, workers);
    words.push("--resume".into());
    if let Some(s) = connect_timeout_s {
        words.push(format!("--connect-timeout={s}").into());
    }
    words
}

/// `eval --request REQUEST --out OUT --workers N`: one evaluation from a request file.
pub fn eval_once(request: &Path, out: &Path, workers: usize) -> Vec<OsString> {
    let mut words: Vec<OsString> = vec!["eval".into(), "--request".into(), request.into()];
    words.extend(["--out".into(), out.into()]);
    words.extend(["--workers".into(), workers.to_string().into()]);
    words
}

/// `sweep task DIR [--workers N]`: one array task, its index from the engine's
/// environment (`SLURM_ARRAY_TASK_ID`, `JOB_COMPLETION_INDEX`).
pub fn sweep_task(dir: &str, workers: Option<&str>) -> Vec<String> {
    let mut words = vec!["sweep".to_string(), "task".into(), dir.into()];
    if let Some(w) = workers {
        words.extend(["--workers".into(), w.into()]);
    }
    words
}

/// `sweep plan SPEC --out DIR`.
pub fn sweep_plan(spec: &Path, dir: &Path) -> Vec<OsString> {
    vec![
        "sweep".into(),
        "plan".into(),
        spec.into(),
        "--out".into(),
        dir.into(),
    ]
}

/// `sweep run DIR --jobs N`.
pub fn sweep_run(dir: &Path, jobs: usize) -> Vec<OsString> {
    vec![
        "sweep".into(),
        "run".into(),
        dir.into(),
        "--jobs".into(),
        jobs.to_string().into(),
    ]
}

/// `sweep status DIR` or `sweep collect DIR` (`step`).
pub fn sweep_step(step: &str, dir: &Path) -> Vec<OsString> {
    vec!["sweep".into(), step.into(), dir.into()]
}

/// `client --policy echo --session S --spin-us N`: the Rust echo policy of `bench ipc`.
pub fn echo_client(session: &str, spin_us: u64) -> Vec<String> {
    [
        "client",
        "--policy",
        "echo",
        "--session",
        session,
        "--spin-us",
    ]
    .into_iter()
    .map(String::from)
    .chain([spin_us.to_string()])
    .collect()
}

/// `bench socket-peer --envs N --joints J --refs R --spin-us S --socket`: the echo peer of
/// `bench ipc`'s Unix-socket baseline, the socket's path to follow.
pub fn socket_peer(n_envs: usize, n_joints: usize, n_refs: usize, spin_us: u128) -> Vec<String> {
    let mut words: Vec<String> = ["bench", "socket-peer"].map(String::from).into();
    for (flag, value) in [
        ("--envs", n_envs.to_string()),
        ("--joints", n_joints.to_string()),
        ("--refs", n_refs.to_string()),
        ("--spin-us", spin_us.to_string()),
    ] {
        words.extend([flag.to_string(), value]);
    }
    words.push("--socket".into());
    words
}
