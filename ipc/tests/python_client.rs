//! The Python package `thorarena` (`adapters/python`) against the Rust simulator end: a Rust
//! `SimSession` serves a session and the example policies run as real `python3` processes
//! (with `PYTHONPATH=adapters/python`, no install needed). The replay example answers 100
//! steps of two environments with exactly `(reference − offset) / scale` (zeros for inactive
//! slots); a Python policy announcing the wrong joint count is refused and exits non-zero with
//! the simulator's message; a Python policy killed mid-run is reported `PolicyGone` before the
//! step's deadline; a late Python reply is a miss and counted late; a Python policy in a
//! pid namespace of its own judges the simulator by its node, not its pid. When `python3` cannot
//! import `iceoryx2` and `numpy` the tests say so and pass without running (CI installs both).

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

#[path = "../../tests/prereq/mod.rs"]
mod prereq;
use thorarena_ipc::{
    EnvHeader, IpcError, SimConfig, SimSession, StepOutcome, FLAG_ACTIVE, FLAG_RESET,
};

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("ipc/ sits in the repository")
        .to_path_buf()
}

/// True when `python3` can import what the package needs; otherwise records `test` as
/// skipped (a failure in CI).
fn python_ready(test: &str) -> bool {
    prereq::python_modules(
        test,
        &["iceoryx2", "numpy"],
        "pip install ./adapters/python",
    )
}

/// The G1's canonical joint order, read from `data/robots/g1_29dof/robot.toml`.
fn g1_joint_names() -> Vec<String> {
    let path = repo_root().join("data/robots/g1_29dof/robot.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let mut names = Vec::new();
    let mut in_joints = false;
    for line in text.lines() {
        let line = line.trim();
        if line.starts_with("joints = [") {
            in_joints = true;
        } else if in_joints && line.starts_with(']') {
            break;
        } else if in_joints {
            if let Some(rest) = line.strip_prefix("{ name = \"") {
                names.push(rest.split('"').next().unwrap().to_string());
            }
        }
    }
    assert_eq!(names.len(), 29, "joints of {}", path.display());
    names
}

fn unique(name: &str) -> String {
    format!("py-{name}-{}", std::process::id())
}

fn sim_config(session: &str, n_envs: usize, budget: Option<Duration>) -> SimConfig {
    let joints = g1_joint_names();
    let n = joints.len();
    SimConfig {
        session: session.into(),
        n_envs,
        joint_names: joints,
        control_dt_s: 0.02,
        action_offset_rad: (0..n).map(|j| 0.1 + 0.01 * j as f64).collect(),
        action_scale: (0..n).map(|j| 0.25 + 0.05 * j as f64).collect(),
        budget,
        wait: Default::default(),
        inputs: vec![],
    }
}

/// A Python process that is killed if the test ends without waiting for it.
struct Python(Option<Child>);

impl Python {
    /// `python3 ARGS…` from the repository root, with the package on `PYTHONPATH` and
    /// `env` added to its environment.
    fn spawn_with_env(args: &[&str], env: &[(&str, PathBuf)]) -> Self {
        let root = repo_root();
        let child = Command::new("python3")
            .args(args)
            .envs(env.iter().map(|(k, v)| (k, v)))
            .current_dir(&root)
            .env("PYTHONPATH", root.join("adapters/python"))
            .env("PYTHONUNBUFFERED", "1")
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("python3 starts");
        Self(Some(child))
    }

    fn example(scenario: &str, args: &[&str]) -> Self {
        Self::example_with_env(scenario, args, &[])
    }

    /// [`Self::example`] with `env` added to its environment.
    fn example_with_env(scenario: &str, args: &[&str], env: &[(&str, PathBuf)]) -> Self {
        let script = format!("adapters/python/examples/{scenario}/{scenario}_policy.py");
        let mut all = vec![script.as_str()];
        all.extend_from_slice(args);
        Self::spawn_with_env(&all, env)
    }

    fn exited(&mut self) -> bool {
        self.0
            .as_mut()
            .is_some_and(|c| c.try_wait().unwrap().is_some())
    }

    /// The child's stdout, to read while it runs (`wait` then returns none of it).
    fn take_stdout(&mut self) -> std::process::ChildStdout {
        self.0.as_mut().unwrap().stdout.take().unwrap()
    }

    fn wait(mut self) -> Output {
        self.0.take().unwrap().wait_with_output().unwrap()
    }
}

impl Drop for Python {
    fn drop(&mut self) {
        if let Some(child) = self.0.as_mut() {
            let _ = child.kill();
            let _ = child.wait();
        }
    }
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// Step `k` of a one-environment session whose policy echoes: `q` is `k` on every joint,
/// and an answer must be the same.
fn echo_step(sim: &mut SimSession, k: u64, budget: Duration) -> StepOutcome {
    sim.step(
        |batch| {
            let mut env = batch.env(0);
            env.set_header(&active_header(k));
            env.array("q").fill(k as f64);
        },
        Some(budget),
        |actions| assert_eq!(actions.env(0), vec![k as f64; 29].as_slice()),
    )
    .unwrap()
}

fn active_header(step: u64) -> EnvHeader {
    EnvHeader {
        episode_id: 0,
        step,
        flags: FLAG_ACTIVE | if step == 0 { FLAG_RESET } else { 0 },
        reserved: 0,
        time_s: step as f64 * 0.02,
    }
}

#[test]
fn replay_python_policy_against_rust_server() {
    if !python_ready("python_client::replay_python_policy_against_rust_server") {
        return;
    }
    replay_against_rust_server("python", "IceoryxSession");
}

/// The same session with the Python package over the C ABI (`transport="native"`,
/// ctypes on the `libthorarena_ipc.so` cargo built for this test).
#[test]
fn replay_python_policy_over_the_c_abi_against_rust_server() {
    if !python_ready("python_client::replay_python_policy_over_the_c_abi_against_rust_server") {
        return;
    }
    replay_against_rust_server("native", "NativeSession");
}

/// The shared library cargo built beside this test binary (a test build leaves it in
/// deps/, next to the binary).
fn ipc_library() -> PathBuf {
    let exe = std::env::current_exe().unwrap();
    let lib = exe.parent().unwrap().join("libthorarena_ipc.so");
    assert!(
        lib.is_file(),
        "{} is missing: is `cdylib` still in ipc/Cargo.toml's crate-type?",
        lib.display()
    );
    lib
}

/// The replay example over `transport` answers 100 steps of two environments exactly,
/// zeros on a padding slot, and says which session class served it (`class_name`).
fn replay_against_rust_server(transport: &str, class_name: &str) {
    let session = unique(&format!("replay-{transport}"));
    let config = sim_config(&session, 2, None);
    let (offset, scale) = (
        config.action_offset_rad.clone(),
        config.action_scale.clone(),
    );
    let n = offset.len();
    let mut sim = SimSession::create(config).unwrap();
    let python = Python::example_with_env(
        "replay",
        &["--session", &session, "--transport", transport],
        &[("THORARENA_IPC_LIB", ipc_library())],
    );
    let info = sim.accept(Some(Duration::from_secs(30)), |_| {}).unwrap();
    assert_eq!(info.name, "replay-python");
    assert_eq!(info.reference_offsets_s, vec![0.0]);

    let reference = |step: u64, slot: usize, j: usize| {
        (0.1 * step as f64 + j as f64).sin() * (1.0 + slot as f64) + 0.001 * step as f64
    };
    let mut round_trips = Vec::new();
    for step in 0..100u64 {
        // Slot 1 is an inactive padding slot every tenth step.
        let slot1_active = step % 10 != 9;
        let mut got = Vec::new();
        let outcome = sim
            .step(
                |batch| {
                    for slot in 0..2 {
                        let mut env = batch.env(slot);
                        if slot == 1 && !slot1_active {
                            env.clear(0);
                            continue;
                        }
                        env.set_header(&EnvHeader {
                            episode_id: slot as u64,
                            ..active_header(step)
                        });
                        for (j, q) in env.reference(0, "joint_pos").iter_mut().enumerate() {
                            *q = reference(step, slot, j);
                        }
                        env.array("q").fill(-7.0); // not what replay reads
                    }
                },
                None,
                |actions| got = (0..2).map(|i| actions.env(i).to_vec()).collect(),
            )
            .unwrap();
        round_trips.push(sim.last_round_trip());
        assert_eq!(outcome, StepOutcome::Answered, "step {step}");
        for (slot, actions) in got.iter().enumerate() {
            let want: Vec<f64> = if slot == 1 && !slot1_active {
                vec![0.0; n]
            } else {
                (0..n)
                    .map(|j| (reference(step, slot, j) - offset[j]) / scale[j])
                    .collect()
            };
            assert_eq!(actions, &want, "step {step} slot {slot}");
        }
    }
    sim.end();
    let out = python.wait();
    assert!(out.status.success(), "python: {}", text(&out.stderr));
    let stdout = text(&out.stdout);
    assert!(stdout.contains("run over after 100 steps"), "{stdout}");
    assert!(stdout.contains(&format!("over {class_name}")), "{stdout}");
    round_trips.sort();
    eprintln!(
        "python replay over {transport}, 2 envs × 29 joints: round trip p50 {:?}, max {:?} (first step included)",
        round_trips[50], round_trips[99]
    );
}

#[test]
fn a_python_policy_with_the_wrong_joint_count_is_refused_and_exits_with_the_message() {
    if !python_ready("python_client::a_python_policy_with_the_wrong_joint_count_is_refused_and_exits_with_the_message") {
        return;
    }
    refused_with_the_message("python");
}

#[test]
fn a_python_policy_over_the_c_abi_with_the_wrong_joint_count_is_refused_with_the_message() {
    if !python_ready("python_client::a_python_policy_over_the_c_abi_with_the_wrong_joint_count_is_refused_with_the_message") {
        return;
    }
    refused_with_the_message("native");
}

/// A policy joining over `transport` with 23 joint names is refused; it exits non-zero
/// with `SessionRefused`, its status and the simulator's message.
fn refused_with_the_message(transport: &str) {
    let session = unique(&format!("refused-{transport}"));
    let mut sim = SimSession::create(sim_config(&session, 1, None)).unwrap();
    let script = "import sys, thorarena as ta\n\
                  ta.connect(sys.argv[1], name='23dof', joint_names=ta.G1_JOINT_NAMES[:23], \
                  transport=sys.argv[2])\n\
                  print('connected')\n";
    let mut python = Python::spawn_with_env(
        &["-c", script, &session, transport],
        &[("THORARENA_IPC_LIB", ipc_library())],
    );
    let mut refusals = Vec::new();
    let give_up = Instant::now() + Duration::from_secs(60);
    while !python.exited() {
        assert!(Instant::now() < give_up, "the python process never exited");
        match sim.accept(Some(Duration::from_millis(100)), |m| {
            refusals.push(m.to_string())
        }) {
            Err(IpcError::Timeout(..)) => {}
            other => panic!("expected only a refusal, got {other:?}"),
        }
    }
    let out = python.wait();
    let stderr = text(&out.stderr);
    assert!(!out.status.success(), "python exited with success");
    assert!(!text(&out.stdout).contains("connected"));
    assert_eq!(refusals, vec!["23 joints but the robot has 29".to_string()]);
    assert!(stderr.contains("SessionRefused"), "{stderr}");
    assert!(
        stderr.contains("session refused (JOINT_COUNT): 23 joints but the robot has 29"),
        "{stderr}"
    );
}

#[test]
fn a_killed_python_policy_is_gone_before_the_deadline() {
    if !python_ready("python_client::a_killed_python_policy_is_gone_before_the_deadline") {
        return;
    }
    let session = unique("killed");
    let budget = Duration::from_secs(10);
    let mut sim = SimSession::create(sim_config(&session, 1, Some(budget))).unwrap();
    let python = Python::example("echo", &["--session", &session, "--die-after-steps", "5"]);
    sim.accept(Some(Duration::from_secs(30)), |_| {}).unwrap();
    let mut outcomes = Vec::new();
    for step in 0..6u64 {
        let outcome = echo_step(&mut sim, step, budget);
        if outcome == StepOutcome::PolicyGone {
            // Found dead by the liveness check, not by waiting out the budget.
            assert!(
                sim.last_round_trip() < budget,
                "{:?}",
                sim.last_round_trip()
            );
        }
        outcomes.push(outcome);
    }
    let mut want = vec![StepOutcome::Answered; 5];
    want.push(StepOutcome::PolicyGone);
    assert_eq!(outcomes, want);
    assert!(sim.policy().is_none(), "a gone policy is forgotten");
    // Reaped only now: the simulator saw a zombie (or nothing) at /proc/<pid>.
    let status = python.wait().status;
    #[cfg(unix)]
    {
        use std::os::unix::process::ExitStatusExt;
        assert_eq!(status.signal(), Some(9), "{status:?}");
    }
    #[cfg(not(unix))]
    assert!(!status.success());
}

#[test]
fn a_late_python_reply_is_a_miss_and_is_counted_late() {
    if !python_ready("python_client::a_late_python_reply_is_a_miss_and_is_counted_late") {
        return;
    }
    let session = unique("late");
    let budget = Duration::from_millis(500);
    let mut sim = SimSession::create(sim_config(&session, 1, Some(budget))).unwrap();
    let python = Python::example(
        "echo",
        &[
            "--session",
            &session,
            "--delay-at-step",
            "2",
            "--delay-ms",
            "1500",
        ],
    );
    sim.accept(Some(Duration::from_secs(30)), |_| {}).unwrap();
    let mut outcomes = Vec::new();
    for step in 0..4u64 {
        let outcome = sim
            .step(
                |batch| batch.env(0).set_header(&active_header(step)),
                Some(budget),
                |_| {},
            )
            .unwrap();
        outcomes.push(outcome);
        if outcome == StepOutcome::Missed {
            std::thread::sleep(Duration::from_millis(2000)); // let the late reply land
        }
    }
    use StepOutcome::{Answered, Missed};
    assert_eq!(outcomes, vec![Answered, Missed, Answered, Answered]);
    assert_eq!(sim.late_replies(), 1);
    sim.end();
    let out = python.wait();
    assert!(out.status.success(), "python: {}", text(&out.stderr));
}

/// Round-trip latency of the Python echo (one environment, G1): printed, never asserted.
/// `cargo test --release -p thorarena-ipc --test python_client -- --ignored --nocapture`
#[test]
#[ignore = "a measurement: run with --ignored --nocapture"]
fn python_echo_round_trip_latency_is_printed() {
    if !python_ready("python_client::python_echo_round_trip_latency_is_printed") {
        return;
    }
    for n_envs in [1usize, 64] {
        let session = unique(&format!("latency-{n_envs}"));
        let mut sim = SimSession::create(sim_config(&session, n_envs, None)).unwrap();
        let mut python = Python::example("echo", &["--session", &session]);
        let mut stdout = BufReader::new(python.take_stdout());
        let mut line = String::new();
        sim.accept(Some(Duration::from_secs(30)), |_| {}).unwrap();
        stdout.read_line(&mut line).unwrap();
        assert_eq!(line.trim(), "connected");
        let mut round_trips = Vec::new();
        for step in 0..5000u64 {
            let outcome = sim
                .step(
                    |batch| {
                        for i in 0..n_envs {
                            let mut env = batch.env(i);
                            env.set_header(&active_header(step));
                            env.array("q").fill(step as f64);
                        }
                    },
                    None,
                    |actions| assert_eq!(actions.env(0)[0], step as f64),
                )
                .unwrap();
            round_trips.push(sim.last_round_trip());
            assert_eq!(outcome, StepOutcome::Answered);
        }
        sim.end();
        drop(python);
        round_trips.drain(..100); // warm-up
        round_trips.sort();
        let q = |p: f64| round_trips[((round_trips.len() - 1) as f64 * p) as usize];
        eprintln!(
            "python echo, {n_envs} env(s) × 29 joints, {} steps: p50 {:?} p90 {:?} p99 {:?} p99.9 {:?} max {:?}",
            round_trips.len(),
            q(0.5),
            q(0.9),
            q(0.99),
            q(0.999),
            q(1.0)
        );
    }
}

/// A Python policy in a pid namespace of its own (another container, say) cannot see the
/// simulator's process: the pid in the welcome names nothing there. It judges the
/// simulator by its iceoryx2 node instead, so it waits out a pause between steps, and
/// still sees the simulator go. Needs root for `unshare --pid`; skipped, saying so,
/// without it.
#[test]
fn a_python_policy_in_another_pid_namespace_judges_the_simulator_by_its_node() {
    const TEST: &str = "python_client::another_pid_namespace";
    if !python_ready(TEST) {
        return;
    }
    let probe = Command::new("unshare")
        .args(["--pid", "--fork", "--mount-proc", "true"])
        .stderr(Stdio::null())
        .status();
    if !probe.is_ok_and(|s| s.success()) {
        prereq::skip(
            TEST,
            "`unshare --pid --fork --mount-proc` is not permitted (needs root)",
        );
        return;
    }
    let session = unique("pidns");
    let mut sim = SimSession::create(sim_config(&session, 1, None)).unwrap();
    let root = repo_root();
    let mut python = Python(Some(
        Command::new("unshare")
            .args(["--pid", "--fork", "--mount-proc", "python3"])
            .arg("adapters/python/examples/echo/echo_policy.py")
            .args(["--session", &session])
            .current_dir(&root)
            .env("PYTHONPATH", root.join("adapters/python"))
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap(),
    ));
    sim.accept(Some(Duration::from_secs(30)), |_| {}).unwrap();
    let mut step = |k: u64| echo_step(&mut sim, k, Duration::from_secs(10));
    for k in 0..3 {
        let outcome = step(k);
        if outcome != StepOutcome::Answered {
            let out = python.wait();
            panic!(
                "step {k}: {outcome:?}; the policy said: {}{}",
                text(&out.stdout),
                text(&out.stderr)
            );
        }
    }
    // The policy blocks through this pause, checking the simulator's liveness.
    std::thread::sleep(Duration::from_millis(300));
    for k in 3..6 {
        assert_eq!(
            step(k),
            StepOutcome::Answered,
            "the policy left during the pause"
        );
    }
    // The simulator goes without ending the run: its node goes with it.
    drop(sim);
    let start = Instant::now();
    while !python.exited() && start.elapsed() < Duration::from_secs(10) {
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = python.wait();
    let stderr = text(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    assert!(
        stderr.contains("the simulator") && stderr.contains("is gone"),
        "{stderr}"
    );
    assert!(
        start.elapsed() < Duration::from_secs(10),
        "not noticed: {stderr}"
    );
}

/// A Python policy over the C ABI (`transport="native"`) whose simulator goes without
/// ending the run raises `SimulatorGone`, naming the simulator, within seconds: the
/// library's liveness check reaches Python as its own error, not as a timeout or a
/// transport failure.
#[test]
fn a_python_policy_over_the_c_abi_sees_the_simulator_go() {
    const TEST: &str = "python_client::c_abi_simulator_gone";
    if !python_ready(TEST) {
        return;
    }
    let session = unique("gone-native");
    let mut sim = SimSession::create(sim_config(&session, 1, None)).unwrap();
    let script = "import sys, thorarena as ta\n\
                  s = ta.connect(sys.argv[1], name='echo', joint_names=ta.G1_JOINT_NAMES, \
                  transport='native', timeout_s=60)\n\
                  print('connected', type(s).__name__, flush=True)\n\
                  try:\n\
                  \x20   for obs, actions in s.steps():\n\
                  \x20       actions[:] = obs['q']\n\
                  except ta.SimulatorGone as e:\n\
                  \x20   print('gone:', e, flush=True)\n\
                  \x20   sys.exit(3)\n";
    let mut python = Python::spawn_with_env(
        &["-c", script, &session],
        &[("THORARENA_IPC_LIB", ipc_library())],
    );
    sim.accept(Some(Duration::from_secs(30)), |_| {}).unwrap();
    for k in 0..3u64 {
        let outcome = echo_step(&mut sim, k, Duration::from_secs(10));
        assert_eq!(outcome, StepOutcome::Answered, "step {k}");
    }
    drop(sim);
    let start = Instant::now();
    while !python.exited() && start.elapsed() < Duration::from_secs(10) {
        std::thread::sleep(Duration::from_millis(20));
    }
    let noticed_after = start.elapsed();
    let out = python.wait();
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    assert_eq!(out.status.code(), Some(3), "{stdout}{stderr}");
    assert!(stdout.contains("connected NativeSession"), "{stdout}");
    assert!(
        stdout.contains(&format!(
            "gone: the simulator (pid {}) is gone",
            std::process::id()
        )),
        "{stdout}{stderr}"
    );
    assert!(
        noticed_after < Duration::from_secs(10),
        "not noticed: {stdout}{stderr}"
    );
}
