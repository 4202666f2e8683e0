//! `thorarena bench eval`: a whole evaluation of one policy in process on one engine —
//! every (sequence, setting) of a dataset on every worker, nothing written — against its
//! physics floor measured in the same run (the same physics steps on the same workers,
//! nothing else): simulated seconds per wall second, the share of the cores kept busy, and
//! the ratio of the run to its floor.

use super::choices::EngineArg;
use std::path::PathBuf;
use thorarena::evaluation::{EvalRequest, EvalSpec};
use thorarena::perf::{physics_floor, time_run};
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
    /// Environment slots [default: the number of workers].
    #[arg(long)]
    pub envs: Option<usize>,
}

pub(super) fn run(args: &Args) -> anyhow::Result<()> {
    let spec = EvalSpec::load(&EvalRequest {
        policy: args.policy.clone(),
        dataset: Some(args.dataset.clone()),
        profile: args.profile.clone(),
        settings: args.settings.clone(),
        engine: args.engine.into(),
        mjcf: args.mjcf.clone(),
        workers: args.workers,
        envs: args.envs,
        ..EvalRequest::default()
    })?;
    for advice in &spec.advice {
        eprintln!("{advice}");
    }
    let PolicyChoice::InProcess(mut policy) =
        registry::policy(&args.policy, &spec.robot, &spec.profile)?
    else {
        anyhow::bail!(
            "bench eval times a policy in process: not `{}`",
            args.policy
        );
    };
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    eprintln!(
        "timing {} on {:?}: {} sequences × {} settings, {} workers, {} slots, {cores} cores…",
        args.policy,
        args.engine,
        spec.sequences.len(),
        spec.settings.len(),
        spec.workers,
        spec.envs
    );
    let run = time_run(&spec, policy.as_mut());
    let floor = physics_floor(&spec, run.physics_steps)?;
    let (wall, floor_s) = (run.wall.as_secs_f64(), floor.as_secs_f64());
    println!(
        "run:   {} episodes, {} control steps ({} physics steps), {:.1} s simulated in {wall:.2} s wall = {:.1} simulated s per wall s",
        run.episodes,
        run.control_steps,
        run.physics_steps,
        run.simulated_s,
        run.real_time_factor()
    );
    println!(
        "       CPU {:.2} s = {:.0} % of {cores} cores busy; policy act p50 {:.0} µs per step",
        run.cpu.as_secs_f64(),
        100.0 * run.cores_busy(cores),
        run.act_p50_us
    );
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
        wall / in_run.max(f64::MIN_POSITIVE)
    );
    Ok(())
}
