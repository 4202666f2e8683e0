//! `thorarena bench eval`: a whole evaluation of one policy in process on one engine —
//! every (sequence, setting) of a dataset on every worker, nothing written — against its
//! physics floor measured in the same run (the same physics steps on the same workers,
//! nothing else): simulated seconds per wall second, the share of the cores kept busy, and
//! the ratio of the run to its floor. With `--policy-command` the policy is a process the
//! bench starts for each run; with several `--pipeline-depths` the runs are compared with
//! the first (wall-time ratio, and whether every record is the same).

use super::choices::EngineArg;
use std::path::PathBuf;
use std::time::Duration;
use thorarena::evaluation::{EvalRequest, EvalSpec};
use thorarena::leaderboard::{LaunchedPolicy, PolicyProcess};
use thorarena::perf::{physics_floor, time_run, RunTiming};
use thorarena::policy::Policy;
use thorarena::registry::{self, PolicyChoice};

/// Arguments of `bench eval`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Dataset directory.
    #[arg(long, default_value = "data/sample")]
    pub dataset: PathBuf,
    /// Policy in process: a built-in (hold, replay, balance) or a network
    /// (`twist2:FILE.onnx`, `wbc-mjlab:FILE.onnx`, …; see `thorarena policies`).
    #[arg(long, default_value = "hold")]
    pub policy: String,
    /// Dynamics profile [default: the policy family's].
    #[arg(long)]
    pub profile: Option<String>,
    /// Settings, comma separated, as for `eval`.
    #[arg(long, value_delimiter = ',', default_value = "force,no-force")]
    pub settings: Vec<String>,
    /// Physics engine.
    #[arg(long, value_enum, default_value = "rapier")]
    pub engine: EngineArg,
    /// MJCF of the robot for `--engine mujoco` [default: generated from the robot model].
    #[arg(long)]
    pub mjcf: Option<PathBuf>,
    /// Worker threads [default: one per core].
    #[arg(long)]
    pub workers: Option<usize>,
    /// Environment slots [default: as for `eval`: one per worker, a network in process
    /// its family's count per worker (TWIST2 4, BeyondMimic family 8)].
    #[arg(long)]
    pub envs: Option<usize>,
    /// A policy process instead of `--policy`: a shell command joining session
    /// `{session}` (`{thorarena}` is this binary), started afresh for each run, e.g.
    /// `python3 examples/twist2/run_twist2.py --session {session} --onnx FILE`. Its CPU
    /// time counts in the cores busy.
    #[arg(long)]
    pub policy_command: Option<String>,
    /// Seconds the policy process has to connect.
    #[arg(long, default_value_t = 120.0)]
    pub connect_timeout: f64,
    /// Pipeline depths to run, one run each (see `eval --pipeline-depth`); the later runs
    /// are compared with the first.
    #[arg(long, value_delimiter = ',', default_value = "1")]
    pub pipeline_depths: Vec<usize>,
}

pub(super) fn run(args: &Args) -> anyhow::Result<()> {
    if args.pipeline_depths.is_empty() {
        anyhow::bail!("--pipeline-depths: give at least one depth");
    }
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut first: Option<(usize, RunTiming)> = None;
    for &depth in &args.pipeline_depths {
        let spec = load_spec(args, depth)?;
        let (label, mut policy) = start_policy(args, &spec, depth)?;
        eprintln!(
            "timing {label} on {:?}: {} sequences × {} settings, {} workers, {} slots, pipeline depth {depth}, {cores} cores…",
            args.engine,
            spec.sequences.len(),
            spec.settings.len(),
            spec.workers,
            spec.envs
        );
        let run = time_run(&spec, policy.as_mut());
        let policy_cpu = policy.cpu_time();
        drop(policy);
        print_run(&run, policy_cpu, cores, depth);
        match &first {
            None => {
                print_floor(&spec, &run)?;
                first = Some((depth, run));
            }
            Some((base_depth, base)) => println!(
                "versus depth {base_depth}: wall {:.2} s / {:.2} s = {:.2}; records {}",
                run.wall.as_secs_f64(),
                base.wall.as_secs_f64(),
                run.wall.as_secs_f64() / base.wall.as_secs_f64().max(f64::MIN_POSITIVE),
                if run.records_fingerprint == base.records_fingerprint {
                    "identical"
                } else {
                    "DIFFER"
                }
            ),
        }
    }
    Ok(())
}

fn load_spec(args: &Args, pipeline_depth: usize) -> anyhow::Result<EvalSpec> {
    let policy = match &args.policy_command {
        Some(_) => "ipc:bench".to_string(),
        None => args.policy.clone(),
    };
    let spec = EvalSpec::load(&EvalRequest {
        policy,
        dataset: Some(args.dataset.clone()),
        profile: args.profile.clone(),
        settings: args.settings.clone(),
        engine: args.engine.into(),
        mjcf: args.mjcf.clone(),
        workers: args.workers,
        envs: args.envs,
        pipeline_depth,
        ..EvalRequest::default()
    })?;
    for advice in &spec.advice {
        eprintln!("{}", super::flags::as_flags(&advice.to_string()));
    }
    Ok(spec)
}

/// The policy of one run: in process, or a process started for it.
enum Timed {
    InProcess(Box<dyn Policy>),
    Process(Box<LaunchedPolicy>),
}

impl Timed {
    fn as_mut(&mut self) -> &mut dyn Policy {
        match self {
            Self::InProcess(p) => p.as_mut(),
            Self::Process(p) => p.as_mut(),
        }
    }

    /// CPU time of the policy's own processes (none in process: it is the bench's).
    fn cpu_time(&self) -> Option<Duration> {
        match self {
            Self::InProcess(_) => None,
            Self::Process(p) => Some(p.cpu_time()),
        }
    }
}

fn start_policy(args: &Args, spec: &EvalSpec, depth: usize) -> anyhow::Result<(String, Timed)> {
    let Some(command) = &args.policy_command else {
        let arg = registry::PolicyArg::parse(&args.policy)?;
        let PolicyChoice::InProcess(policy) = arg.load(&spec.robot, &spec.profile)? else {
            anyhow::bail!(
                "bench eval times a policy in process or one it starts (--policy-command): not `{}`",
                args.policy
            );
        };
        return Ok((args.policy.clone(), Timed::InProcess(policy)));
    };
    let process = PolicyProcess {
        name: "bench".into(),
        command: command.clone(),
        profile: args.profile.clone(),
        connect_timeout_s: args.connect_timeout,
        workdir: std::env::current_dir()?,
    };
    let session = format!("bench-eval-{}-{depth}", std::process::id());
    let log = std::env::temp_dir().join(format!("thorarena-{session}.log"));
    let launched = LaunchedPolicy::start(&process, &session, spec, &log, &mut |note| {
        eprintln!("{note}")
    })
    .map_err(anyhow::Error::msg)?;
    Ok((format!("`{command}`"), Timed::Process(Box::new(launched))))
}

fn print_run(run: &RunTiming, policy_cpu: Option<Duration>, cores: usize, depth: usize) {
    println!(
        "run (depth {depth}): {} episodes, {} control steps ({} physics steps), {:.1} s simulated in {:.2} s wall = {:.1} simulated s per wall s",
        run.episodes,
        run.control_steps,
        run.physics_steps,
        run.simulated_s,
        run.wall.as_secs_f64(),
        run.real_time_factor()
    );
    let cpu = run.cpu + policy_cpu.unwrap_or_default();
    let busy = cpu.as_secs_f64() / (run.wall.as_secs_f64() * cores as f64).max(f64::MIN_POSITIVE);
    let policy_part = policy_cpu
        .map(|c| format!(" (of it the policy process {:.2} s)", c.as_secs_f64()))
        .unwrap_or_default();
    println!(
        "       CPU {:.2} s{policy_part} = {:.0} % of {cores} cores busy; policy act p50 {:.0} µs per step",
        cpu.as_secs_f64(),
        100.0 * busy,
        run.act_p50_us
    );
}

fn print_floor(spec: &EvalSpec, run: &RunTiming) -> anyhow::Result<()> {
    let floor_s = physics_floor(spec, run.physics_steps)?.as_secs_f64();
    let in_run = run.physics_wall_slowest_worker.as_secs_f64();
    println!(
        "floor: the slowest worker inside its physics steps in this run: {in_run:.2} s ({:.1} µs per step)",
        in_run * 1e6 * spec.workers as f64 / run.physics_steps.max(1) as f64
    );
    println!(
        "       the same {} steps of a robot standing still, on {} workers: {floor_s:.2} s ({:.1} µs per step)",
        run.physics_steps,
        spec.workers,
        floor_s * 1e6 * spec.workers as f64 / run.physics_steps.max(1) as f64
    );
    println!(
        "ratio: run / floor = {:.2} (1.00: the run costs what its physics costs)",
        run.wall.as_secs_f64() / in_run.max(f64::MIN_POSITIVE)
    );
    Ok(())
}
