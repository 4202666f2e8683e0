//! `thorarena bench ipc`: the policy round trip — observation batch published to action
//! batch received — for echo policies in Rust, C++ and Python at 1 and 64 environments,
//! against a Unix-domain-socket echo moving the same bytes in the same run; and for the
//! Python TWIST2 adapter running the real network (`--clients twist2 --onnx FILE`),
//! against the network's own time measured inside the adapter in the same run, so what
//! the adapter adds to the network is a printed difference.
//!
//! Each echo policy is a separate process answering action = q for every environment, so
//! the figures include the policy reading the observation and writing the actions. The
//! socket baselines (`thorarena::perf::socket_round_trips`) are a `thorarena` process that receives the whole
//! batch over a Unix stream socket into a buffer, answers the same way and sends the
//! actions back: once with blocking reads, once with the shared-memory path's own wait
//! (spin, then block), so the comparison separates what waiting costs from what copying
//! costs.

use anyhow::{bail, Context};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::Duration;
use thorarena::evaluation::LatencySummary;
use thorarena::perf::{
    adapter_round_trips, answer_socket_echo, echo_round_trips, socket_round_trips, AdapterTiming,
};
use thorarena::policy::inputs::InputBuilder;
use thorarena::robot::RobotModel;
use thorarena_ipc::{Layout, SimConfig, SimSession, WaitPolicy};

/// Arguments of `bench ipc`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Timed round trips per (client, environments) pair, after `--warmup` untimed ones.
    #[arg(long, default_value_t = 20_000)]
    pub steps: usize,
    /// Untimed round trips first.
    #[arg(long, default_value_t = 1_000)]
    pub warmup: usize,
    /// Environment counts, comma separated.
    #[arg(long, value_delimiter = ',', default_value = "1,64")]
    pub envs: Vec<usize>,
    /// Clients, comma separated: rust, cpp, python (echo policies: action = q), twist2
    /// (the Python TWIST2 adapter with its network, `--onnx`).
    #[arg(long, value_delimiter = ',', default_value = "rust,cpp,python")]
    pub clients: Vec<String>,
    /// TWIST2's network for the `twist2` client (twist2_1017_25k.onnx, released with
    /// TWIST2, arXiv 2511.02832).
    #[arg(long)]
    pub onnx: Option<PathBuf>,
    /// Timed round trips per environment count for the `twist2` client (a network call
    /// each), after `--warmup` untimed ones.
    #[arg(long, default_value_t = 3_000)]
    pub adapter_steps: usize,
    /// Busy-poll this many µs before blocking, on both sides.
    #[arg(long, default_value_t = 50)]
    pub spin_us: u64,
    /// The C++ echo policy [default: adapters/cpp/build/echo_policy of this checkout,
    /// built by `cargo build --release -p thorarena-ipc && make -C adapters/cpp`].
    #[arg(long)]
    pub cpp_echo: Option<PathBuf>,
    /// Python interpreter.
    #[arg(long, default_value = "python3")]
    pub python: String,
    /// The C ABI library the `twist2` client's extra row loads through ctypes
    /// (`connect(transport="native")`) [default: libthorarena_ipc.so beside this binary, or
    /// in its deps/, as `cargo build --release -p thorarena-ipc` leaves it; the row is
    /// skipped, saying so, without one].
    #[arg(long)]
    pub ipc_lib: Option<PathBuf>,
}

/// Hidden subcommand: the socket baseline's echo peer.
#[derive(Debug, clap::Args)]
pub struct PeerArgs {
    /// Socket path to connect to.
    #[arg(long)]
    pub socket: PathBuf,
    /// Environments per batch.
    #[arg(long)]
    pub envs: usize,
    /// Joints per environment.
    #[arg(long)]
    pub joints: usize,
    /// Reference frames per environment.
    #[arg(long)]
    pub refs: usize,
    /// Busy-poll this many µs before blocking (0: blocking reads).
    #[arg(long, default_value_t = 0)]
    pub spin_us: u64,
}

/// `bench socket-peer`: answers each batch read from the socket with action = q.
pub(super) fn run_peer(args: &PeerArgs) -> anyhow::Result<()> {
    let layout = Layout {
        n_envs: args.envs,
        n_joints: args.joints,
        n_refs: args.refs,
        n_inputs: 0,
    };
    answer_socket_echo(&args.socket, layout, Duration::from_micros(args.spin_us))?;
    Ok(())
}

/// The socket baseline: this binary's `bench socket-peer` answering.
fn socket_baseline(args: &Args, layout: Layout, spin: Duration) -> anyhow::Result<LatencySummary> {
    let mut peer = Command::new(std::env::current_exe()?);
    peer.args(["bench", "socket-peer"])
        .args(["--envs", &layout.n_envs.to_string()])
        .args(["--joints", &layout.n_joints.to_string()])
        .args(["--refs", &layout.n_refs.to_string()])
        .args(["--spin-us", &spin.as_micros().to_string()])
        .arg("--socket");
    Ok(socket_round_trips(
        peer,
        layout,
        args.warmup,
        args.steps,
        spin,
    )?)
}

pub(super) fn run(args: &Args) -> anyhow::Result<()> {
    if args.steps == 0 || args.adapter_steps == 0 || args.envs.contains(&0) {
        bail!("--steps, --adapter-steps and every --envs value must be at least 1");
    }
    if let Some(other) = args
        .clients
        .iter()
        .find(|c| !["rust", "cpp", "python", "twist2"].contains(&c.as_str()))
    {
        bail!("unknown client `{other}` (rust, cpp, python, twist2)");
    }
    let twist2 = args.clients.iter().any(|c| c == "twist2");
    if twist2 && args.onnx.is_none() {
        bail!(
            "the twist2 client needs --onnx FILE: TWIST2's released network (twist2_1017_25k.onnx)"
        );
    }
    let robot = thorarena::registry::robot("g1_29dof")?;
    let echoes: Vec<&String> = args.clients.iter().filter(|c| *c != "twist2").collect();
    if !echoes.is_empty() {
        echo_table(args, &robot, &echoes)?;
    }
    if twist2 {
        adapter_table(args, &robot)?;
    }
    Ok(())
}

/// The echo policies' round trips against the socket baselines, one row per client and
/// environment count.
fn echo_table(args: &Args, robot: &RobotModel, clients: &[&String]) -> anyhow::Result<()> {
    let n_joints = robot.n_joints();
    println!(
        "round trip, observation published → actions received, {} timed steps after {} warm-up; spin {} µs then block; µs",
        args.steps, args.warmup, args.spin_us
    );
    println!(
        "| client | envs | batch KB | p50 | p90 | p99 | p99.9 | max | socket p50 (blocking / spin) | socket p99.9 (blocking / spin) | socket/shm p50 (blocking / spin) |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for &envs in &args.envs {
        // The echo policies ask for one reference frame (the current one).
        let layout = Layout {
            n_envs: envs,
            n_joints,
            n_refs: 1,
            n_inputs: 0,
        };
        let spin = Duration::from_micros(args.spin_us);
        let blocking =
            socket_baseline(args, layout, Duration::ZERO).context("the Unix-socket baseline")?;
        let spinning =
            socket_baseline(args, layout, spin).context("the spinning Unix-socket baseline")?;
        for client in clients {
            let Some(row) = shm_round_trips(args, robot, client, layout)? else {
                continue;
            };
            println!(
                "| {client} | {envs} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} / {:.1} | {:.1} / {:.1} | {:.1}× / {:.1}× |",
                (layout.obs_bytes() + layout.action_bytes()) as f64 / 1024.0,
                row.p50_us,
                row.p90_us,
                row.p99_us,
                row.p999_us,
                row.max_us,
                blocking.p50_us,
                spinning.p50_us,
                blocking.p999_us,
                spinning.p999_us,
                blocking.p50_us / row.p50_us,
                spinning.p50_us / row.p50_us
            );
        }
    }
    println!(
        "goals (2-core machine): Rust p50 ≤ 10 µs and p99.9 ≤ 100 µs at 1 environment; Python p50 ≤ 30 µs; ≥ 5× faster than the socket at 64 environments"
    );
    Ok(())
}

/// The network's own time, as the adapter's `--time-network` prints it (µs).
#[derive(Debug, serde::Deserialize)]
struct NetworkTiming {
    count: usize,
    p50: f64,
    p90: f64,
    /// Every call, in step order.
    each: Vec<f64>,
}

/// The Python TWIST2 adapter's round trips against its network's time in the same run,
/// with the observation built by the simulator (the adapter's default) and by the adapter
/// in numpy, one row each per environment count.
fn adapter_table(args: &Args, robot: &RobotModel) -> anyhow::Result<()> {
    println!(
        "\nPython TWIST2 adapter (ONNX Runtime, 1 thread), standing observations: {} timed steps after {} warm-up; spin {} µs then block; the network call timed inside the adapter over the same steps; µs",
        args.adapter_steps, args.warmup, args.spin_us
    );
    println!("| envs | observation built by | round trip p50 | p90 | p99 | simulator's build p50 | prepared while waiting p50 | network p50 | network p90 | overhead p50 | overhead p90 | answers noticed polling % |");
    println!("|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    let ipc_lib = ipc_library(args);
    if ipc_lib.is_none() {
        eprintln!("skipping the C ABI client's rows: no libthorarena_ipc.so beside this binary (cargo build --release -p thorarena-ipc, or --ipc-lib)");
    }
    let rows: Vec<Builder> = [
        Builder::Simulator,
        Builder::SimulatorNative,
        Builder::Adapter,
    ]
    .into_iter()
    .filter(|b| *b != Builder::SimulatorNative || ipc_lib.is_some())
    .collect();
    for &envs in &args.envs {
        for &built_by in &rows {
            let lib = ipc_lib.as_deref();
            let Some((timing, net)) = adapter_round_trip(args, robot, envs, built_by, lib)? else {
                return Ok(());
            };
            let (rt, build) = (timing.round_trip, timing.input_build);
            // Per step: its round trip and build less its own network call.
            let timed = &net.each[args.warmup..];
            let mut overhead: Vec<f64> = timing
                .per_step_us
                .iter()
                .zip(timed)
                .map(|(total, network)| total - network)
                .collect();
            overhead.sort_by(f64::total_cmp);
            let at = |p: f64| overhead[((overhead.len() - 1) as f64 * p).round() as usize];
            let noticed = timing.noticed;
            let polling = (noticed.spinning + noticed.in_window) as f64;
            println!(
                "| {envs} | {} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} |",
                built_by.label(),
                rt.p50_us,
                rt.p90_us,
                rt.p99_us,
                build.p50_us,
                timing.input_prepare.p50_us,
                net.p50,
                net.p90,
                at(0.5),
                at(0.9),
                100.0 * polling / noticed.total().max(1) as f64
            );
        }
    }
    println!("overhead: per step, round trip + simulator's build − that step's network call; goal ≤ 50 µs at 1 and at 64 environments (the history part of the input is prepared while the policy computes, inside the round trip)");
    println!("answers noticed polling: by the simulator's first spin or in the window where the answer was due; the rest cost a kernel wake-up (WaitPolicy::wake_early)");
    Ok(())
}

/// Who builds TWIST2's observation in a measured row, and over which transport the
/// adapter's session runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Builder {
    /// The simulator, into the batch's policy-input block (`Hello::input` "twist2"); the
    /// session over iceoryx2's Python binding.
    Simulator,
    /// As `Simulator`, the session over the C ABI through ctypes (`--transport native`).
    SimulatorNative,
    /// The adapter, in numpy (`--observation python`), over the Python binding.
    Adapter,
}

impl Builder {
    fn label(self) -> &'static str {
        match self {
            Self::Simulator => "simulator (Rust)",
            Self::SimulatorNative => "simulator (Rust), C ABI client",
            Self::Adapter => "adapter (numpy)",
        }
    }
}

/// `--ipc-lib`, or the shared library cargo left beside this binary or in its deps/.
fn ipc_library(args: &Args) -> Option<PathBuf> {
    if let Some(lib) = &args.ipc_lib {
        return Some(lib.clone());
    }
    let exe = std::env::current_exe().ok()?;
    let dir = exe.parent()?;
    [dir.to_path_buf(), dir.join("deps")]
        .into_iter()
        .map(|d| d.join("libthorarena_ipc.so"))
        .find(|p| p.is_file())
}

fn adapter_round_trip(
    args: &Args,
    robot: &RobotModel,
    envs: usize,
    built_by: Builder,
    ipc_lib: Option<&Path>,
) -> anyhow::Result<Option<(AdapterTiming, NetworkTiming)>> {
    let onnx = args.onnx.as_ref().context("--onnx")?;
    let ok = Command::new(&args.python)
        .args(["-c", "import iceoryx2, numpy, onnxruntime"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !ok {
        eprintln!(
            "skipping twist2: `{} -c 'import iceoryx2, numpy, onnxruntime'` fails (pip install './adapters/python[policies]')",
            args.python
        );
        return Ok(None);
    }
    let session = format!("bench-twist2-{envs}-{}", std::process::id());
    let config = sim_config(args, robot, &session, envs);
    let mut builder = InputBuilder::new("twist2", envs, &config.action_offset_rad)
        .context("the simulator's TWIST2 input")?;
    let mut sim = SimSession::create(config)?;
    let python = repo_root().join("adapters/python");
    let (observation, transport) = match built_by {
        Builder::Simulator => ("simulator", "python"),
        Builder::SimulatorNative => ("simulator", "native"),
        Builder::Adapter => ("python", "python"),
    };
    let mut command = Command::new(&args.python);
    command
        .arg(python.join("examples/twist2/run_twist2.py"))
        .args(["--session", &session, "--time-network"])
        .args(["--observation", observation, "--transport", transport])
        .args(["--spin-us", &args.spin_us.to_string()])
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
        .context("starting the Python TWIST2 adapter")?;
    let accepted = sim.accept(Some(Duration::from_secs(60)), |m| eprintln!("refused: {m}"));
    let timed = accepted.map_err(anyhow::Error::from).and_then(|info| {
        let input = info.input.is_some().then_some(&mut builder);
        if input.is_some() == (built_by == Builder::Adapter) {
            bail!("the adapter asked for policy input {:?}", info.input);
        }
        Ok(adapter_round_trips(
            &mut sim,
            args.warmup,
            args.adapter_steps,
            &info.reference_offsets_s,
            input,
        )?)
    });
    sim.end();
    let timed = match timed {
        Ok(t) => t,
        Err(e) => {
            let _ = child.kill();
            let _ = child.wait();
            return Err(e.context("the Python TWIST2 adapter"));
        }
    };
    let out = child.wait_with_output()?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    #[derive(serde::Deserialize)]
    struct Line {
        network_us: NetworkTiming,
    }
    let line = stdout
        .lines()
        .find_map(|l| serde_json::from_str::<Line>(l).ok())
        .with_context(|| format!("the adapter printed no network timing; its output:\n{stdout}"))?;
    if line.network_us.count != args.warmup + args.adapter_steps
        || line.network_us.each.len() != line.network_us.count
    {
        bail!(
            "the adapter timed {} network calls, {} steps were sent",
            line.network_us.count,
            args.warmup + args.adapter_steps
        );
    }
    Ok(Some((timed, line.network_us)))
}

/// A session of `envs` slots for the G1 with the identity action mapping.
fn sim_config(args: &Args, robot: &RobotModel, session: &str, envs: usize) -> SimConfig {
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
            spin: Duration::from_micros(args.spin_us),
            ..WaitPolicy::default()
        },
        inputs: thorarena::policy::inputs::offers(n_joints),
    }
}

/// The checkout this binary was built from: the C++ and Python echo clients live there.
fn repo_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn spawn_client(args: &Args, client: &str, session: &str) -> anyhow::Result<Option<Child>> {
    let spin = args.spin_us.to_string();
    let mut cmd = match client {
        "rust" => {
            let mut c = Command::new(std::env::current_exe()?);
            c.args([
                "client",
                "--policy",
                "echo",
                "--session",
                session,
                "--spin-us",
                &spin,
            ]);
            c
        }
        "cpp" => {
            let exe = args
                .cpp_echo
                .clone()
                .unwrap_or_else(|| repo_root().join("adapters/cpp/build/echo_policy"));
            if !exe.is_file() {
                eprintln!(
                    "skipping cpp: {} not found (build it: cargo build --release -p thorarena-ipc && make -C adapters/cpp)",
                    exe.display()
                );
                return Ok(None);
            }
            let mut c = Command::new(&exe);
            c.args(["--session", session, "--spin-us", &spin]);
            c
        }
        "python" => {
            let ok = Command::new(&args.python)
                .args(["-c", "import iceoryx2, numpy"])
                .output()
                .is_ok_and(|o| o.status.success());
            if !ok {
                eprintln!("skipping python: `{} -c 'import iceoryx2, numpy'` fails (pip install ./adapters/python)", args.python);
                return Ok(None);
            }
            let python = repo_root().join("adapters/python");
            let mut c = Command::new(&args.python);
            c.arg(python.join("examples/echo/echo_policy.py"))
                .args(["--session", session, "--spin-us", &spin])
                .env("PYTHONPATH", python);
            c
        }
        other => bail!("unknown client `{other}` (rust, cpp, python)"),
    };
    Ok(Some(
        cmd.stdout(Stdio::null())
            .stderr(Stdio::inherit())
            .spawn()
            .with_context(|| format!("starting the {client} echo policy"))?,
    ))
}

fn shm_round_trips(
    args: &Args,
    robot: &RobotModel,
    client: &str,
    layout: Layout,
) -> anyhow::Result<Option<LatencySummary>> {
    let session = format!("bench-{client}-{}-{}", layout.n_envs, std::process::id());
    let mut sim = SimSession::create(sim_config(args, robot, &session, layout.n_envs))?;
    let Some(mut child) = spawn_client(args, client, &session)? else {
        return Ok(None);
    };
    let info = sim.accept(Some(Duration::from_secs(60)), |m| eprintln!("refused: {m}"))?;
    let shape = sim.layout().expect("connected");
    if shape != layout {
        bail!(
            "the {client} echo asked for {} reference frames; the socket baseline moves {} per environment",
            info.reference_offsets_s.len(),
            layout.n_refs
        );
    }
    let summary = echo_round_trips(&mut sim, args.warmup, args.steps)
        .with_context(|| format!("the {client} echo"))?;
    sim.end();
    let _ = child.wait();
    Ok(Some(summary))
}
