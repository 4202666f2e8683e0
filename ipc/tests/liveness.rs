//! A policy cannot fake being alive: the simulator watches the policy's iceoryx2 node, not
//! the pid the policy reports. A policy process that announces pid 1 (what `getpid()`
//! returns inside a container) or 0 and dies mid-run is gone within a step; one that dies
//! between its hello and its step server is reported and the next policy is accepted.
//!
//! The policy processes are this test binary run again with `ROLE` set (a thread would not
//! do: a node's liveness is its process's).

use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::Duration;
use thorarena_ipc::{
    joint_names_hash, Hello, PolicyClient, PolicyConfig, SimConfig, SimSession, StepOutcome,
    Welcome, FLAG_ACTIVE, MAX_REFERENCE_OFFSETS, PROTOCOL_VERSION,
};

const ROLE: &str = "THORARENA_IPC_LIVENESS_ROLE";
const SESSION: &str = "THORARENA_IPC_LIVENESS_SESSION";
const PID: &str = "THORARENA_IPC_LIVENESS_PID";
const N_JOINTS: usize = 4;

fn joints() -> Vec<String> {
    (0..N_JOINTS).map(|i| format!("joint_{i}")).collect()
}

fn sim(session: &str) -> SimSession {
    SimSession::create(SimConfig {
        session: session.into(),
        n_envs: 2,
        joint_names: joints(),
        control_dt_s: 0.02,
        action_offset_rad: vec![0.0; N_JOINTS],
        action_scale: vec![1.0; N_JOINTS],
        budget: None,
        wait: Default::default(),
        inputs: vec![],
    })
    .unwrap()
}

/// This binary as a policy process playing `role` (see `play_role`).
fn spawn_role(test: &str, role: &str, session: &str, pid: u32) -> Child {
    Command::new(std::env::current_exe().unwrap())
        .args(["--exact", test, "--nocapture", "--test-threads", "1"])
        .env(ROLE, role)
        .env(SESSION, session)
        .env(PID, pid.to_string())
        .stdout(Stdio::null())
        .stderr(Stdio::inherit())
        .spawn()
        .unwrap()
}

/// In a child process: play the role and die without cleaning up (abort: no destructor
/// removes the node, as after SIGKILL).
fn play_role() -> bool {
    let Ok(role) = std::env::var(ROLE) else {
        return false;
    };
    let session = std::env::var(SESSION).unwrap();
    let pid: u32 = std::env::var(PID).unwrap().parse().unwrap();
    match role.as_str() {
        "die-after-10-steps" => {
            let mut config = PolicyConfig::new(&session, "liar", joints(), vec![0.0]);
            config.announced_pid = pid;
            let mut client = PolicyClient::connect(&config, Duration::from_secs(30)).unwrap();
            let mut steps = 0;
            let _ = client.run(|_, _| {
                steps += 1;
                if steps == 10 {
                    std::process::abort();
                }
            });
        }
        "die-after-hello" => hello_then_die(&session, pid),
        other => panic!("unknown role {other}"),
    }
    std::process::abort();
}

/// Says hello as a valid policy would, waits for the welcome, and dies before creating
/// the step server.
fn hello_then_die(session: &str, pid: u32) {
    use iceoryx2::prelude::*;
    // ThorArena's sessions live in this user's own iceoryx2 root.
    let config = thorarena_ipc::session::private_root::config().unwrap();
    let node = NodeBuilder::new()
        .config(&config)
        .create::<ipc::Service>()
        .unwrap();
    let name = ServiceName::new(&format!("thorarena/{session}/hello")).unwrap();
    let hello = node
        .service_builder(&name)
        .request_response::<Hello, Welcome>()
        .open()
        .unwrap();
    let client = hello.client_builder().create().unwrap();
    let pending = client
        .send_copy(Hello {
            protocol_version: PROTOCOL_VERSION,
            n_joints: N_JOINTS as u32,
            joint_names_hash: joint_names_hash(&joints()),
            pid,
            n_refs: 1,
            reference_offsets_s: [0.0; MAX_REFERENCE_OFFSETS],
            name: thorarena_ipc::handshake::to_fixed("liar"),
            input: [0; thorarena_ipc::INPUT_NAME_BYTES],
            ..Hello::blank()
        })
        .unwrap();
    while pending.receive().unwrap().is_none() {
        std::thread::sleep(Duration::from_millis(1));
    }
}

/// Runs `f` on a thread and fails the test if it takes longer than `limit` (before the
/// fix, these waits never ended).
fn within<T: Send + 'static>(limit: Duration, f: impl FnOnce() -> T + Send + 'static) -> T {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(f());
    });
    rx.recv_timeout(limit).unwrap_or_else(|_| {
        panic!("still waiting after {limit:?}: the dead policy was taken for alive")
    })
}

/// Steps a lock-step session until the policy is gone; returns the steps answered.
fn steps_until_gone(mut sim: SimSession) -> u64 {
    let mut answered = 0;
    loop {
        let outcome = sim
            .step(
                |batch| {
                    for i in 0..2 {
                        batch.env(i).clear(FLAG_ACTIVE);
                    }
                },
                None,
                |_| {},
            )
            .unwrap();
        match outcome {
            StepOutcome::Answered => answered += 1,
            StepOutcome::Missed => panic!("no deadline in lock-step"),
            StepOutcome::PolicyGone => return answered,
        }
    }
}

fn dies_mid_run_announcing(test: &str, pid: u32) {
    let session = format!("live-{pid}-{}", std::process::id());
    let mut child = spawn_role(test, "die-after-10-steps", &session, pid);
    let (announced, answered) = within(Duration::from_secs(60), move || {
        let mut sim = sim(&session);
        let info = sim.accept(Some(Duration::from_secs(30)), |_| {}).unwrap();
        (info.pid, steps_until_gone(sim))
    });
    assert_eq!(announced, pid, "the announced pid is recorded as announced");
    assert!(
        answered >= 9,
        "answered {answered} steps before dying at 10"
    );
    let _ = child.wait();
}

#[test]
fn a_policy_announcing_pid_1_that_dies_mid_run_is_gone() {
    if play_role() {
        return;
    }
    dies_mid_run_announcing("a_policy_announcing_pid_1_that_dies_mid_run_is_gone", 1);
}

#[test]
fn a_policy_announcing_pid_0_that_dies_mid_run_is_gone() {
    if play_role() {
        return;
    }
    dies_mid_run_announcing("a_policy_announcing_pid_0_that_dies_mid_run_is_gone", 0);
}

#[test]
fn a_policy_dying_between_hello_and_step_server_is_reported_and_the_next_accepted() {
    const TEST: &str =
        "a_policy_dying_between_hello_and_step_server_is_reported_and_the_next_accepted";
    if play_role() {
        return;
    }
    let session = format!("live-hello-{}", std::process::id());
    let (created_tx, created) = mpsc::channel();
    let serving = session.clone();
    let accepting = std::thread::spawn(move || {
        let mut sim = sim(&serving);
        let _ = created_tx.send(());
        let mut refusals = Vec::new();
        let info = sim
            .accept(Some(Duration::from_secs(60)), |m| {
                refusals.push(m.to_string())
            })
            .map(|info| info.name);
        (info, refusals)
    });
    created.recv().unwrap();
    let mut liar = spawn_role(TEST, "die-after-hello", &session, 1);
    let _ = liar.wait();
    // The next policy, a live one, is accepted (it stays connected until the check).
    let config = PolicyConfig::new(&session, "honest", joints(), vec![0.0]);
    let (connected_tx, connected) = mpsc::channel();
    let (done, done_rx) = mpsc::channel::<()>();
    let honest = std::thread::spawn(move || {
        let client = PolicyClient::connect(&config, Duration::from_secs(30));
        let _ = connected_tx.send(client.is_ok());
        let _ = done_rx.recv();
    });
    let connected = connected.recv_timeout(Duration::from_secs(40));
    assert_eq!(connected, Ok(true), "the honest policy could not connect");
    let (info, refusals) = within(Duration::from_secs(40), move || accepting.join().unwrap());
    let _ = done.send(());
    honest.join().unwrap();
    assert_eq!(info.unwrap(), "honest");
    assert!(
        refusals
            .iter()
            .any(|m| m.contains("`liar` died after its hello")),
        "{refusals:?}"
    );
}
