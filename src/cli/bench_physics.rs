//! `thorarena bench physics`: cost of one physics step of the standing G1 on each engine of
//! this build at each step size, timed in the same run, with the ratio to rapier at the
//! same step; and MuJoCo's cost on the reference MJCF through its Python package, when
//! installed (`thorarena::campaign::bench::PhysicsBench`).
//!
//! `thorarena bench inference`: one network's cost per environment against the batch size
//! of a tract call, each batch size timed in the same run, with the ratio to batch one
//! (`thorarena::campaign::bench::InferenceBench`).

use std::path::PathBuf;
use thorarena::campaign::bench::{InferenceBench, PhysicsBench};
use thorarena::sim::physics::PhysicsSettings;

/// Arguments of `bench physics`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Bundled robot name or robot directory.
    #[arg(long, default_value = "g1_29dof")]
    pub robot: String,
    /// Physics time steps, s, comma separated.
    #[arg(long, value_delimiter = ',', default_value = "0.001,0.005")]
    pub dt: Vec<f64>,
    /// Solver iterations per physics step (rapier).
    #[arg(long, default_value_t = PhysicsSettings::default().solver_iterations)]
    pub iterations: usize,
    /// Timed physics steps per repeat (after a 1 s settle that is not timed).
    #[arg(long, default_value_t = 2000)]
    pub steps: usize,
    /// Repeats; the median is reported.
    #[arg(long, default_value_t = 5)]
    pub repeats: usize,
    /// Skip the Python MuJoCo baseline even if it is available.
    #[arg(long)]
    pub no_mujoco: bool,
    /// Python interpreter for the MuJoCo baseline.
    #[arg(long, default_value = "python3")]
    pub python: String,
    /// The reference MJCF for the Python MuJoCo baseline [default:
    /// $THORARENA_REFERENCE/g1/g1_sim2sim_29dof.xml, THORARENA_REFERENCE defaulting to
    /// ../shared/reference beside the checkout].
    #[arg(long)]
    pub mjcf: Option<String>,
}

/// `bench physics`: the library times each engine and hands over each line as it is
/// measured.
pub(super) fn run(args: &Args) -> anyhow::Result<()> {
    let bench = PhysicsBench {
        robot: args.robot.clone(),
        dt_s: args.dt.clone(),
        iterations: args.iterations,
        steps: args.steps,
        repeats: args.repeats,
        no_mujoco: args.no_mujoco,
        python: args.python.clone(),
        mjcf: args.mjcf.clone().map(Into::into),
    };
    bench.run(&mut super::bench_eval::print)?;
    Ok(())
}

/// Arguments of `bench inference`.
#[derive(Debug, clap::Args)]
pub struct InferenceArgs {
    /// The ONNX network (one float32 input `[batch, width]`, e.g. TWIST2's).
    pub onnx: PathBuf,
    /// Batch sizes, comma separated.
    #[arg(long, value_delimiter = ',', default_value = "1,2,4,8,16,32,64")]
    pub batches: Vec<usize>,
    /// Environments run through the network per batch size (rounded up to whole batches).
    #[arg(long, default_value_t = 4096)]
    pub envs: usize,
}

/// `bench inference`: the library times each batch size and hands over each row as it is
/// measured.
/// `bench inference`: a network's cost per environment against the batch size.
pub(super) fn inference(args: &InferenceArgs) -> anyhow::Result<()> {
    let bench = InferenceBench {
        onnx: args.onnx.clone(),
        batches: args.batches.clone(),
        envs: args.envs,
    };
    bench.run(&mut super::bench_eval::print)?;
    Ok(())
}
