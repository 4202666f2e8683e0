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
use std::path::PathBuf;
use std::process::Command;
use std::time::Duration;
use thorarena::evaluation::LatencySummary;
use thorarena::perf::{
    adapter_round_trip, answer_socket_echo, ipc_library, shm_round_trips, socket_round_trips,
    Builder, IpcClients, Measured,
};
use thorarena::robot::RobotModel;
use thorarena_ipc::Layout;

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
    let clients = IpcClients {
        exe: std::env::current_exe()?,
        python: args.python.clone(),
        cpp_echo: args.cpp_echo.clone(),
        onnx: args.onnx.clone(),
        spin_us: args.spin_us,
        warmup: args.warmup,
        steps: args.steps,
        adapter_steps: args.adapter_steps,
    };
    let echoes: Vec<&String> = args.clients.iter().filter(|c| *c != "twist2").collect();
    if !echoes.is_empty() {
        echo_table(args, &clients, &robot, &echoes)?;
    }
    if twist2 {
        adapter_table(args, &clients, &robot)?;
    }
    Ok(())
}

/// The echo policies' round trips against the socket baselines, one row per client and
/// environment count.
fn echo_table(
    args: &Args,
    c: &IpcClients,
    robot: &RobotModel,
    clients: &[&String],
) -> anyhow::Result<()> {
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
            let row = match shm_round_trips(c, robot, client, layout, &mut refused)
                .with_context(|| format!("the {client} echo"))?
            {
                Measured::Taken(row) => row,
                Measured::Skipped(why) => {
                    eprintln!("skipping {why}");
                    continue;
                }
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

/// The Python TWIST2 adapter's round trips against its network's time in the same run,
/// with the observation built by the simulator (the adapter's default) and by the adapter
/// in numpy, one row each per environment count.
fn adapter_table(args: &Args, c: &IpcClients, robot: &RobotModel) -> anyhow::Result<()> {
    println!(
        "\nPython TWIST2 adapter (ONNX Runtime, 1 thread), standing observations: {} timed steps after {} warm-up; spin {} µs then block; the network call timed inside the adapter over the same steps; µs",
        args.adapter_steps, args.warmup, args.spin_us
    );
    println!("| envs | observation built by | round trip p50 | p90 | p99 | simulator's build p50 | prepared while waiting p50 | network p50 | network p90 | overhead p50 | overhead p90 | answers noticed polling % |");
    println!("|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    let ipc_lib = ipc_library(args.ipc_lib.as_deref(), &c.exe);
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
            let row = match adapter_round_trip(c, robot, envs, built_by, lib, &mut refused)
                .context("the Python TWIST2 adapter")?
            {
                Measured::Taken(row) => row,
                Measured::Skipped(why) => {
                    eprintln!("skipping {why}");
                    return Ok(());
                }
            };
            let (timing, net) = (&row.timing, &row.network);
            let (rt, build) = (&timing.round_trip, &timing.input_build);
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
                row.overhead_at(0.5),
                row.overhead_at(0.9),
                100.0 * polling / noticed.total().max(1) as f64
            );
        }
    }
    println!("overhead: per step, round trip + simulator's build − that step's network call; goal ≤ 50 µs at 1 and at 64 environments (the history part of the input is prepared while the policy computes, inside the round trip)");
    println!("answers noticed polling: by the simulator's first spin or in the window where the answer was due; the rest cost a kernel wake-up (WaitPolicy::wake_early)");
    Ok(())
}

/// A session's refusal of a connecting client, said on stderr.
fn refused(message: &str) {
    eprintln!("refused: {message}");
}
