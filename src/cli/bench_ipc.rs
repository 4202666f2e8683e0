//! `thorarena bench ipc`: the policy round trip — observation batch published to action
//! batch received — for echo policies in Rust, C++ and Python at 1 and 64 environments,
//! against a Unix-domain-socket echo moving the same bytes in the same run.
//!
//! Each echo policy is a separate process answering action = q for every environment, so
//! the figures include the policy reading the observation and writing the actions. The
//! socket baselines (`bench_socket`) are a `thorarena` process that receives the whole
//! batch over a Unix stream socket into a buffer, answers the same way and sends the
//! actions back: once with blocking reads, once with the shared-memory path's own wait
//! (spin, then block), so the comparison separates what waiting costs from what copying
//! costs.

use super::bench_socket::socket_baseline;
use anyhow::{bail, Context};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::Duration;
use thorarena::evaluation::LatencyRecorder;
use thorarena::robot::RobotModel;
use thorarena_ipc::{
    EnvHeader, Layout, ObsBatchMut, SimConfig, SimSession, StepOutcome, WaitPolicy, FLAG_ACTIVE,
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

/// Percentiles of one series, µs.
pub(super) struct Row {
    p50: f64,
    p90: f64,
    p99: f64,
    p999: f64,
    max: f64,
}

impl Row {
    pub(super) fn of(rec: &LatencyRecorder) -> Self {
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
    let robot = thorarena::registry::robot("g1_29dof")?;
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
        };
        let spin = Duration::from_micros(args.spin_us);
        let blocking = socket_baseline(args.warmup, args.steps, layout, Duration::ZERO)
            .context("the Unix-socket baseline")?;
        let spinning = socket_baseline(args.warmup, args.steps, layout, spin)
            .context("the spinning Unix-socket baseline")?;
        for client in &args.clients {
            let Some(row) = shm_round_trips(args, &robot, client, layout)? else {
                continue;
            };
            println!(
                "| {client} | {envs} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} / {:.1} | {:.1} / {:.1} | {:.1}× / {:.1}× |",
                (layout.obs_bytes() + layout.action_bytes()) as f64 / 1024.0,
                row.p50,
                row.p90,
                row.p99,
                row.p999,
                row.max,
                blocking.p50,
                spinning.p50,
                blocking.p999,
                spinning.p999,
                blocking.p50 / row.p50,
                spinning.p50 / row.p50
            );
        }
    }
    println!(
        "goals (2-core machine): Rust p50 ≤ 10 µs and p99.9 ≤ 100 µs at 1 environment; Python p50 ≤ 30 µs; ≥ 5× faster than the socket at 64 environments"
    );
    Ok(())
}

/// Fills every slot as active with a recognisable q.
pub(super) fn fill(batch: &mut ObsBatchMut, layout: Layout, step: u64) {
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
