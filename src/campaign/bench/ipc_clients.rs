//! The measured clients of `thorarena bench ipc`, each started as its own process on its
//! own session: the echo policies (Rust — this binary's `client --policy echo` —, C++,
//! Python) and the Python TWIST2 adapter with its network. A client whose program or
//! Python modules are missing is skipped, saying why, rather than failing the benchmark.

use super::round_trip::{adapter_round_trips, echo_round_trips, AdapterTiming};
use super::PerfError;
use crate::eval::LatencySummary;
use crate::policy::inputs::InputBuilder;
use crate::sim::robot::RobotModel;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::Duration;
use thorarena_ipc::{Layout, SimConfig, SimSession, WaitPolicy};

/// How the clients run and how long they are timed.
#[derive(Debug, Clone)]
pub struct IpcClients {
    /// This binary (the Rust echo client is its `client --policy echo`).
    pub exe: PathBuf,
    /// The Python interpreter.
    pub python: String,
    /// The C++ echo policy (`None`: `adapters/cpp/build/echo_policy` of the checkout).
    pub cpp_echo: Option<PathBuf>,
    /// TWIST2's network, for the adapter.
    pub onnx: Option<PathBuf>,
    /// Busy-poll this long before blocking, on both sides, µs.
    pub spin_us: u64,
    /// Untimed round trips first.
    pub warmup: usize,
    /// Timed round trips of an echo client.
    pub steps: usize,
    /// Timed round trips of the adapter (a network call each).
    pub adapter_steps: usize,
}

/// A measurement taken, or why it was not.
#[derive(Debug)]
pub enum Measured<T> {
    /// The figures.
    Taken(T),
    /// The client could not run here (what to install or build).
    Skipped(String),
}

/// Who builds TWIST2's observation in a measured row, and over which transport the
/// adapter's session runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Builder {
    /// The simulator, into the batch's policy-input block (`Hello::input` "twist2"); the
    /// session over iceoryx2's Python binding.
    Simulator,
    /// As `Simulator`, the session over the C ABI through ctypes (`--transport native`).
    SimulatorNative,
    /// The adapter, in numpy (`--observation python`), over the Python binding.
    Adapter,
}

impl Builder {
    /// The row's label.
    pub fn label(self) -> &'static str {
        match self {
            Self::Simulator => "simulator (Rust)",
            Self::SimulatorNative => "simulator (Rust), C ABI client",
            Self::Adapter => "adapter (numpy)",
        }
    }
}

/// The network's own time, as the adapter's `--time-network` prints it (µs).
#[derive(Debug, Clone, serde::Deserialize)]
pub struct NetworkTiming {
    /// Calls timed.
    pub count: usize,
    /// Median, µs.
    pub p50: f64,
    /// 90th percentile, µs.
    pub p90: f64,
    /// Every call, in step order, µs.
    pub each: Vec<f64>,
}

/// One adapter row: the round trips and the network's time over the same steps.
#[derive(Debug, Clone)]
pub struct AdapterRow {
    /// The simulator's side.
    pub timing: AdapterTiming,
    /// The network's side.
    pub network: NetworkTiming,
    /// Per timed step, round trip and build less that step's network call, sorted, µs.
    pub overhead_us: Vec<f64>,
}

impl AdapterRow {
    /// The overhead's quantile `p` (0..=1), µs.
    pub fn overhead_at(&self, p: f64) -> f64 {
        let v = &self.overhead_us;
        v[((v.len() - 1) as f64 * p).round() as usize]
    }
}

/// `ipc_lib`, or the shared library cargo left beside this binary or in its deps/.
pub fn ipc_library(ipc_lib: Option<&Path>, exe: &Path) -> Option<PathBuf> {
    if let Some(lib) = ipc_lib {
        return Some(lib.to_path_buf());
    }
    let dir = exe.parent()?;
    [dir.to_path_buf(), dir.join("deps")]
        .into_iter()
        .map(|d| d.join("libthorarena_ipc.so"))
        .find(|p| p.is_file())
}

/// Whether `python` imports `modules`.
fn python_has(python: &str, modules: &str) -> bool {
    Command::new(python)
        .args(["-c", &format!("import {modules}")])
        .output()
        .is_ok_and(|o| o.status.success())
}

fn failed(what: &str, message: impl Into<String>) -> PerfError {
    PerfError::Failed {
        what: what.into(),
        message: message.into(),
    }
}

/// The Python TWIST2 adapter's round trips with `envs` slots, its observation built by
/// `built_by`, against its network's time in the same run; `ipc_lib` for the C ABI row.
pub fn adapter_round_trip(
    c: &IpcClients,
    robot: &RobotModel,
    envs: usize,
    built_by: Builder,
    ipc_lib: Option<&Path>,
    refused: &mut dyn FnMut(&str),
) -> Result<Measured<AdapterRow>, PerfError> {
    let what = "the Python TWIST2 adapter";
    let onnx = c
        .onnx
        .as_ref()
        .ok_or_else(|| PerfError::Precondition("the twist2 client needs its network".into()))?;
    if !python_has(&c.python, "iceoryx2, numpy, onnxruntime") {
        return Ok(Measured::Skipped(format!(
            "twist2: `{} -c 'import iceoryx2, numpy, onnxruntime'` fails (pip install './adapters/python[policies]')",
            c.python
        )));
    }
    let session = format!("bench-twist2-{envs}-{}", std::process::id());
    let config = sim_config(c, robot, &session, envs);
    let mut builder = InputBuilder::new("twist2", envs, &config.action_offset_rad)
        .ok_or_else(|| failed("the simulator's TWIST2 input", "no such input"))?;
    let mut sim = SimSession::create(config)?;
    let python = repo_root().join("adapters/python");
    let (observation, transport) = match built_by {
        Builder::Simulator => ("simulator", "python"),
        Builder::SimulatorNative => ("simulator", "native"),
        Builder::Adapter => ("python", "python"),
    };
    let mut command = Command::new(&c.python);
    command
        .arg(python.join("examples/twist2/run_twist2.py"))
        .args(["--session", &session, "--time-network"])
        .args(["--observation", observation, "--transport", transport])
        .args(["--spin-us", &c.spin_us.to_string()])
        .arg("--onnx")
        .arg(onnx)
        .env("PYTHONPATH", python)
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit());
    if let Some(lib) = ipc_lib {
        command.env("THORARENA_IPC_LIB", lib);
    }
    let mut child = command
        .spawn()
        .map_err(PerfError::io(format!("starting {what}")))?;
    let accepted = sim.accept(Some(Duration::from_secs(60)), |m| refused(m));
    let timed = accepted.map_err(PerfError::from).and_then(|info| {
        let input = info.input.is_some().then_some(&mut builder);
        if input.is_some() == (built_by == Builder::Adapter) {
            return Err(failed(
                what,
                format!("it asked for policy input {:?}", info.input),
            ));
        }
        adapter_round_trips(
            &mut sim,
            c.warmup,
            c.adapter_steps,
            &info.reference_offsets_s,
            input,
        )
    });
    sim.end();
    let timing = match timed {
        Ok(t) => t,
        Err(e) => {
            let _ = child.kill();
            let _ = child.wait();
            return Err(e);
        }
    };
    let out = child
        .wait_with_output()
        .map_err(PerfError::io(format!("waiting for {what}")))?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    #[derive(serde::Deserialize)]
    struct Line {
        network_us: NetworkTiming,
    }
    let network = stdout
        .lines()
        .find_map(|l| serde_json::from_str::<Line>(l).ok())
        .ok_or_else(|| {
            failed(
                what,
                format!("it printed no network timing; its output:\n{stdout}"),
            )
        })?
        .network_us;
    if network.count != c.warmup + c.adapter_steps || network.each.len() != network.count {
        return Err(failed(
            what,
            format!(
                "it timed {} network calls, {} steps were sent",
                network.count,
                c.warmup + c.adapter_steps
            ),
        ));
    }
    // Per step: its round trip and build less its own network call.
    let mut overhead_us: Vec<f64> = timing
        .per_step_us
        .iter()
        .zip(&network.each[c.warmup..])
        .map(|(total, network)| total - network)
        .collect();
    overhead_us.sort_by(f64::total_cmp);
    Ok(Measured::Taken(AdapterRow {
        timing,
        network,
        overhead_us,
    }))
}

/// A session of `envs` slots for the G1 with the identity action mapping.
fn sim_config(c: &IpcClients, robot: &RobotModel, session: &str, envs: usize) -> SimConfig {
    let n_joints = robot.n_joints();
    SimConfig {
        session: session.to_string(),
        n_envs: envs,
        joint_names: robot.joints.iter().map(|j| j.name.clone()).collect(),
        control_dt_s: 0.02,
        action_offset_rad: vec![0.0; n_joints],
        action_scale: vec![1.0; n_joints],
        budget: None,
        wait: WaitPolicy {
            spin: Duration::from_micros(c.spin_us),
            ..WaitPolicy::default()
        },
        inputs: crate::policy::inputs::offers(n_joints),
    }
}

/// The checkout this binary was built from: the C++ and Python clients live there.
fn repo_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Starts echo client `client` on `session`, or says why it cannot run here.
fn spawn_echo(c: &IpcClients, client: &str, session: &str) -> Result<Measured<Child>, PerfError> {
    let spin = c.spin_us.to_string();
    let mut cmd = match client {
        "rust" => {
            let mut cmd = Command::new(&c.exe);
            cmd.args(crate::campaign::own_command::echo_client(
                session, c.spin_us,
            ));
            cmd
        }
        "cpp" => {
            let exe = c
                .cpp_echo
                .clone()
                .unwrap_or_else(|| repo_root().join("adapters/cpp/build/echo_policy"));
            if !exe.is_file() {
                return Ok(Measured::Skipped(format!(
                    "cpp: {} not found (build it: cargo build --release -p thorarena-ipc && make -C adapters/cpp)",
                    exe.display()
                )));
            }
            let mut cmd = Command::new(&exe);
            cmd.args(["--session", session, "--spin-us", &spin]);
            cmd
        }
        "python" => {
            if !python_has(&c.python, "iceoryx2, numpy") {
                return Ok(Measured::Skipped(format!(
                    "python: `{} -c 'import iceoryx2, numpy'` fails (pip install ./adapters/python)",
                    c.python
                )));
            }
            let python = repo_root().join("adapters/python");
            let mut cmd = Command::new(&c.python);
            cmd.arg(python.join("examples/echo/echo_policy.py"))
                .args(["--session", session, "--spin-us", &spin])
                .env("PYTHONPATH", python);
            cmd
        }
        other => {
            return Err(PerfError::Precondition(format!(
                "unknown client `{other}` (rust, cpp, python)"
            )))
        }
    };
    let child = cmd
        .stdout(Stdio::null())
        .stderr(Stdio::inherit())
        .spawn()
        .map_err(PerfError::io(format!("starting the {client} echo policy")))?;
    Ok(Measured::Taken(child))
}

/// Echo client `client`'s round trips over shared memory with `layout`.
pub fn shm_round_trips(
    c: &IpcClients,
    robot: &RobotModel,
    client: &str,
    layout: Layout,
    refused: &mut dyn FnMut(&str),
) -> Result<Measured<LatencySummary>, PerfError> {
    let session = format!("bench-{client}-{}-{}", layout.n_envs, std::process::id());
    let mut sim = SimSession::create(sim_config(c, robot, &session, layout.n_envs))?;
    let mut child = match spawn_echo(c, client, &session)? {
        Measured::Taken(child) => child,
        Measured::Skipped(why) => return Ok(Measured::Skipped(why)),
    };
    let info = sim.accept(Some(Duration::from_secs(60)), |m| refused(m))?;
    if sim.layout() != Some(layout) {
        return Err(failed(
            &format!("the {client} echo"),
            format!(
                "it asked for {} reference frames; the socket baseline moves {} per environment",
                info.reference_offsets_s.len(),
                layout.n_refs
            ),
        ));
    }
    let summary = echo_round_trips(&mut sim, c.warmup, c.steps)?;
    sim.end();
    let _ = child.wait();
    Ok(Measured::Taken(summary))
}
