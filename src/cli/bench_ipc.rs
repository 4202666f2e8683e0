//! `thorarena bench ipc`: the policy round trip — observation batch published to action
//! batch received — for echo policies in Rust, C++ and Python at 1 and 64 environments,
//! against a Unix-domain-socket echo moving the same bytes in the same run.
//!
//! Each echo policy is a separate process answering action = q for every environment, so
//! the figures include the policy reading the observation and writing the actions. The
//! socket baseline is a `thorarena` process that receives the whole batch over a stream
//! socket into a buffer, answers the same way, and sends the actions back.

use crate::robot::RobotModel;
use crate::runner::LatencyRecorder;
use anyhow::{bail, Context};
use std::io::{BufRead, BufReader, Read, Write};
use std::os::unix::net::{UnixListener, UnixStream};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};
use thorarena_ipc::{
    ActionBatchMut, EnvHeader, Layout, ObsBatch, ObsBatchMut, SimConfig, SimSession, StepOutcome,
    WaitPolicy, FLAG_ACTIVE,
};

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
    /// Clients, comma separated: rust, cpp, python.
    #[arg(long, value_delimiter = ',', default_value = "rust,cpp,python")]
    pub clients: Vec<String>,
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
}

/// Hidden: the socket baseline's echo peer.
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
}

/// Percentiles of one series, µs.
struct Row {
    p50: f64,
    p90: f64,
    p99: f64,
    p999: f64,
    max: f64,
}

impl Row {
    fn of(rec: &LatencyRecorder) -> Self {
        let s = rec.summary();
        Self {
            p50: s.p50_us,
            p90: s.p90_us,
            p99: s.p99_us,
            p999: s.p999_us,
            max: s.max_us,
        }
    }
}

pub(super) fn run(args: &Args) -> anyhow::Result<()> {
    if args.steps == 0 || args.envs.contains(&0) {
        bail!("--steps and every --envs value must be at least 1");
    }
    let robot = super::load_robot("g1_29dof")?;
    let n_joints = robot.n_joints();
    println!(
        "round trip, observation published → actions received, {} timed steps after {} warm-up; spin {} µs then block; µs",
        args.steps, args.warmup, args.spin_us
    );
    println!(
        "| client | envs | batch KB | p50 | p90 | p99 | p99.9 | max | socket p50 | socket p99.9 | socket/shm p50 |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for &envs in &args.envs {
        // The echo policies ask for one reference frame (the current one).
        let layout = Layout {
            n_envs: envs,
            n_joints,
            n_refs: 1,
        };
        let socket = socket_baseline(args, layout).context("the Unix-socket baseline")?;
        for client in &args.clients {
            let Some(row) = shm_round_trips(args, &robot, client, layout)? else {
                continue;
            };
            println!(
                "| {client} | {envs} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1}× |",
                (layout.obs_bytes() + layout.action_bytes()) as f64 / 1024.0,
                row.p50,
                row.p90,
                row.p99,
                row.p999,
                row.max,
                socket.p50,
                socket.p999,
                socket.p50 / row.p50
            );
        }
    }
    println!(
        "goals (2-core machine): Rust p50 ≤ 10 µs and p99.9 ≤ 100 µs at 1 environment; Python p50 ≤ 30 µs; ≥ 5× faster than the socket at 64 environments"
    );
    Ok(())
}

/// Fills every slot as active with a recognisable q.
fn fill(batch: &mut ObsBatchMut, layout: Layout, step: u64) {
    for i in 0..layout.n_envs {
        let mut env = batch.env(i);
        env.set_header(&EnvHeader {
            episode_id: i as u64,
            step,
            flags: FLAG_ACTIVE,
            reserved: 0,
            time_s: step as f64 * 0.02,
        });
        for (j, q) in env.array("q").iter_mut().enumerate() {
            *q = (i * 100 + j) as f64 + step as f64;
        }
    }
}

/// The checkout this binary was built from (`data/` sits at its root).
fn repo_root() -> PathBuf {
    crate::data_dir().join("..")
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
) -> anyhow::Result<Option<Row>> {
    let session = format!("bench-{client}-{}-{}", layout.n_envs, std::process::id());
    let mut sim = SimSession::create(SimConfig {
        session: session.clone(),
        n_envs: layout.n_envs,
        joint_names: robot.joints.iter().map(|j| j.name.clone()).collect(),
        control_dt_s: 0.02,
        action_offset_rad: vec![0.0; layout.n_joints],
        action_scale: vec![1.0; layout.n_joints],
        budget: None,
        wait: WaitPolicy {
            spin: Duration::from_micros(args.spin_us),
            ..WaitPolicy::default()
        },
    })?;
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
    let mut rec = LatencyRecorder::default();
    let mut checked = false;
    for step in 0..(args.warmup + args.steps) as u64 {
        let mut answer_ok = true;
        let outcome = sim.step(
            |b| fill(b, shape, step),
            None,
            |a| {
                // action = q: check one slot, so a broken echo cannot look fast.
                let last = shape.n_envs - 1;
                answer_ok = a.env(last)[1] == (last * 100 + 1) as f64 + step as f64;
            },
        )?;
        if outcome != StepOutcome::Answered || !answer_ok {
            bail!("the {client} echo answered wrongly or went away at step {step} ({outcome:?})");
        }
        checked = true;
        if step >= args.warmup as u64 {
            rec.record(sim.last_round_trip());
        }
    }
    sim.end();
    let _ = child.wait();
    anyhow::ensure!(checked, "no step ran");
    Ok(Some(Row::of(&rec)))
}

/// The socket baseline: a peer process echoes the same batch over a Unix stream socket.
fn socket_baseline(args: &Args, layout: Layout) -> anyhow::Result<Row> {
    let path = std::env::temp_dir().join(format!(
        "thorarena-bench-{}-{}.sock",
        std::process::id(),
        layout.n_envs
    ));
    let _ = std::fs::remove_file(&path);
    let listener = UnixListener::bind(&path)?;
    let mut peer = Command::new(std::env::current_exe()?)
        .args(["bench", "socket-peer", "--socket"])
        .arg(&path)
        .args(["--envs", &layout.n_envs.to_string()])
        .args(["--joints", &layout.n_joints.to_string()])
        .args(["--refs", &layout.n_refs.to_string()])
        .stdout(Stdio::piped())
        .spawn()?;
    let (mut stream, _) = listener.accept()?;
    let mut ready = String::new();
    BufReader::new(peer.stdout.take().expect("piped")).read_line(&mut ready)?;
    let mut obs = vec![0u64; layout.obs_words()];
    let mut actions = vec![0u64; layout.action_words()];
    let mut rec = LatencyRecorder::default();
    for step in 0..(args.warmup + args.steps) as u64 {
        {
            let mut b = ObsBatchMut::new(layout, bytemuck::cast_slice_mut(&mut obs), 0, step);
            fill(&mut b, layout, step);
        }
        let started = Instant::now();
        stream.write_all(bytemuck::cast_slice(&obs))?;
        stream.read_exact(bytemuck::cast_slice_mut(&mut actions))?;
        let took = started.elapsed();
        if step >= args.warmup as u64 {
            rec.record(took);
        }
    }
    drop(stream);
    let _ = peer.wait();
    let _ = std::fs::remove_file(&path);
    Ok(Row::of(&rec))
}

/// `bench socket-peer`: answers each batch read from the socket with action = q.
pub(super) fn run_peer(args: &PeerArgs) -> anyhow::Result<()> {
    let layout = Layout {
        n_envs: args.envs,
        n_joints: args.joints,
        n_refs: args.refs,
    };
    let mut stream = UnixStream::connect(&args.socket)
        .with_context(|| format!("connecting to {}", args.socket.display()))?;
    println!("ready");
    std::io::stdout().flush()?;
    let mut obs = vec![0u64; layout.obs_words()];
    let mut actions = vec![0u64; layout.action_words()];
    loop {
        if stream
            .read_exact(bytemuck::cast_slice_mut(&mut obs))
            .is_err()
        {
            return Ok(()); // the benchmark closed the socket
        }
        let batch = ObsBatch::new(layout, bytemuck::cast_slice(&obs))?;
        let mut out = ActionBatchMut::new(
            layout,
            bytemuck::cast_slice_mut(&mut actions),
            batch.header().seq,
        );
        for i in 0..layout.n_envs {
            let env = batch.env(i);
            if env.is_active() {
                out.env(i).copy_from_slice(env.array("q"));
            }
        }
        stream.write_all(bytemuck::cast_slice(&actions))?;
    }
}
