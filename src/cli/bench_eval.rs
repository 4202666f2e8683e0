//! `thorarena bench eval`: a whole evaluation of one policy in process on one engine —
//! every (sequence, setting) of a dataset on every worker, nothing written — against its
//! physics floor measured in the same run; with `--policy-command` the policy is a process
//! started for each run, and several `--pipeline-depths` are compared with the first
//! (`thorarena::campaign::bench::EvalBench`). What every `bench` command's benchmark says is printed
//! here ([`print`]).
//!
//! `thorarena bench sweep`: what running a sweep as tasks costs next to running the same
//! episodes directly — `sweep run --jobs N` against one `eval --workers N` per
//! (policy, dataset, latency rule) with all the sweep's settings, timed in the same
//! invocation — and how long planning and a status census take for a sweep of thousands
//! of tasks (`thorarena::campaign::bench::SweepBench`).

use super::choices::EngineArg;
use std::path::PathBuf;
use thorarena::campaign::bench::{BenchLine, EvalBench, SweepBench};
use thorarena::eval::EvalRequest;
use thorarena::policy::launched::PolicyCommand;

/// Arguments of `bench eval`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Dataset directory, or a bundled dataset by name (`sample`, `real-walks`).
    #[arg(long, value_parser = thorarena::sim::motion::dataset_arg, default_value = "data/sample")]
    pub dataset: PathBuf,
    // Its help lists every family of the registry run in process.
    #[arg(long, default_value = "hold", value_parser = thorarena::policy::registry::PolicySource::parse, help = thorarena::policy::registry::policy_help(true))]
    pub policy: thorarena::policy::registry::PolicySource,
    // Its help says how the registry chooses the default.
    #[arg(long, help = thorarena::policy::registry::profile_help())]
    pub profile: Option<String>,
    /// Settings, comma separated, as for `eval`.
    #[arg(long, value_delimiter = ',', default_value = "force,no-force", value_parser = super::choices::SettingArg)]
    pub settings: Vec<thorarena::eval::Setting>,
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

/// `bench eval`: the library runs each depth and hands over each line as the run ends.
pub(super) fn run(args: &Args) -> anyhow::Result<()> {
    let workdir = std::env::current_dir()?;
    let command = args.policy_command.as_deref();
    let policy = match command.map(|c| PolicyCommand::new(c, &workdir, args.connect_timeout)) {
        Some(c) => c.map_err(anyhow::Error::msg)?.into(),
        None => args.policy.clone(),
    };
    let bench = EvalBench {
        request: EvalRequest {
            policy,
            dataset: Some(args.dataset.clone()),
            profile: args.profile.clone(),
            settings: args.settings.clone(),
            engine: args.engine.into(),
            mjcf: args.mjcf.clone(),
            workers: args.workers,
            envs: args.envs,
            ..EvalRequest::default()
        },
        pipeline_depths: args.pipeline_depths.clone(),
    };
    bench.run(&mut print)?;
    Ok(())
}

/// A benchmark's line: figures on standard output, notes on standard error with the
/// options they name written as flags.
pub(super) fn print(line: BenchLine) {
    match line {
        BenchLine::Figure(text) => println!("{text}"),
        BenchLine::Note(text) => eprintln!("{}", super::flags::as_flags(&text)),
    }
}

/// Arguments of `bench sweep`.
#[derive(Debug, clap::Args)]
pub struct SweepArgs {
    /// The sweep spec [default: sweeps/sample.toml of the checkout].
    #[arg(long)]
    pub spec: Option<PathBuf>,
    /// Tasks at a time (and the baseline's workers).
    #[arg(long, default_value_t = 2)]
    pub jobs: usize,
    /// Rounds; each times both, in alternating order.
    #[arg(long, default_value_t = 1)]
    pub repeats: usize,
    /// Also plan a sweep of about this many tasks over the bundled sample and time
    /// planning and `sweep status` (0: skip).
    #[arg(long, default_value_t = 10_000)]
    pub plan_tasks: usize,
}

/// `bench sweep`: a sweep's overhead against `eval`, and planning at scale; the library
/// times each round and hands over each line as it is measured.
pub(super) fn sweep(args: &SweepArgs) -> anyhow::Result<()> {
    let bench = SweepBench {
        exe: std::env::current_exe()?,
        spec: args.spec.clone(),
        jobs: args.jobs,
        repeats: args.repeats,
        plan_tasks: args.plan_tasks,
    };
    bench.run(&mut super::bench_eval::print)?;
    Ok(())
}
