//! `thorarena data check`: whether a dataset's motions could be performed under their
//! forces (the check itself: `sim::motion::check`).

use std::path::PathBuf;
use thorarena::campaign::data_check::{run_data_check, DataCheckJob};
use thorarena::eval::pipeline::ProgressLines;
use thorarena::sim::motion::check::{CheckOptions, CHECK_JSON, CHECK_MARKDOWN};

/// Arguments of `data check` (definitions: docs/data-check.md).
#[derive(Debug, clap::Args)]
pub struct CheckArgs {
    /// Dataset directory, or a bundled dataset by name (`sample`, `real-walks`).
    #[arg(value_parser = thorarena::sim::motion::dataset_arg)]
    pub dataset: PathBuf,
    /// Robot of the dataset.
    #[arg(long, default_value = "g1_29dof")]
    pub robot: String,
    /// Also write check.md (with a table per sequence) and check.json into this directory.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Exit with status 1 when a task's share of stance frames whose CoP is outside the
    /// support (with force or without) is above this share, 0 to 1.
    #[arg(long)]
    pub max_outside: Option<f64>,
    /// Cutoff of the zero-phase low-pass applied before differentiating, Hz.
    #[arg(long, default_value_t = thorarena::sim::motion::check::zero_phase::DEFAULT_CUTOFF_HZ)]
    pub cutoff: f64,
    /// A tracker run in process (as `eval --policy` takes it, e.g. `twist2:FILE.onnx`)
    /// on every sequence without force, into OUT/rollout-NAME (resumed when run again):
    /// the sequences it cannot hold are listed. Needs --out.
    #[arg(long, value_name = "POLICY", value_parser = thorarena::policy::registry::PolicySource::parse, requires = "out")]
    pub rollout: Option<thorarena::policy::registry::PolicySource>,
    /// Engine of the tracker's rollouts.
    #[arg(long, value_enum, default_value = "rapier")]
    pub engine: super::choices::EngineArg,
}

/// `data check`: the library checks (and rolls out, and writes); the tables printed, the
/// gate applied.
pub(super) fn run(args: &CheckArgs) -> anyhow::Result<()> {
    let job = DataCheckJob {
        dataset: args.dataset.clone(),
        robot: args.robot.clone(),
        options: CheckOptions {
            cutoff_hz: args.cutoff,
            ..CheckOptions::default()
        },
        out: args.out.clone(),
        tracker: args.rollout.clone(),
        engine: args.engine.into(),
        max_outside: args.max_outside,
    };
    let mut say = |line: &str| eprintln!("{}", super::flags::as_flags(line));
    let check = run_data_check(&job, &mut ProgressLines::new(&mut say))?;
    print!("{}", check.markdown(false));
    if let Some(out) = &args.out {
        eprintln!("{}: {CHECK_MARKDOWN}, {CHECK_JSON}", out.display());
    }
    args.max_outside.map_or(Ok(()), |max| check.gate(max))?;
    Ok(())
}
