//! `thorarena bench ipc`: the policy round trip — observation batch published to action
//! batch received — for echo policies in Rust, C++ and Python, against a Unix-socket echo
//! moving the same bytes in the same run; and for the Python TWIST2 adapter running the
//! real network against the network's own time (`thorarena::campaign::bench::IpcBench`). The hidden
//! `bench socket-peer` is the socket baseline's echo peer, this binary started again.

use std::path::PathBuf;
use std::time::Duration;
use thorarena::campaign::bench::{answer_socket_echo, IpcBench, IpcClients};
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

/// `bench ipc`: the library times each client and hands over each line as it is measured.
pub(super) fn run(args: &Args) -> anyhow::Result<()> {
    let bench = IpcBench {
        setup: IpcClients {
            exe: std::env::current_exe()?,
            python: args.python.clone(),
            cpp_echo: args.cpp_echo.clone(),
            onnx: args.onnx.clone(),
            spin_us: args.spin_us,
            warmup: args.warmup,
            steps: args.steps,
            adapter_steps: args.adapter_steps,
        },
        clients: args.clients.clone(),
        envs: args.envs.clone(),
        ipc_lib: args.ipc_lib.clone(),
    };
    bench.run(&mut super::bench_eval::print)?;
    Ok(())
}
