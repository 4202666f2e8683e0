//! `thorarena data check`: whether a dataset's motions could be performed under their
//! forces (the check itself: `sim::motion::check`).

use std::path::PathBuf;
use thorarena::sim::motion::Dataset;

/// Arguments of `data check` (definitions: docs/data-check.md).
#[derive(Debug, clap::Args)]
pub struct CheckArgs {
    /// Dataset directory.
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
}

/// `data check`: the tables printed, the files written, the gate applied.
pub(super) fn run(args: &CheckArgs) -> anyhow::Result<()> {
    use thorarena::sim::motion::check::{check_dataset, CheckOptions, CHECK_JSON, CHECK_MARKDOWN};
    if let Some(out) = &args.out {
        thorarena::eval::results::check_dir(out, false, std::slice::from_ref(&args.dataset))?;
    }
    let robot = thorarena::policy::registry::robot(&args.robot)?;
    let ds = Dataset::open(&args.dataset, &robot)?;
    let opts = CheckOptions {
        cutoff_hz: args.cutoff,
        ..CheckOptions::default()
    };
    let started = std::time::Instant::now();
    let check = check_dataset(&ds, &ds.load_all()?, &robot, &opts, |done, total| {
        eprint!("\rchecked {done}/{total} sequences")
    })?;
    eprintln!(" in {:.1} s", started.elapsed().as_secs_f64());
    print!("{}", check.markdown(false));
    if let Some(out) = &args.out {
        check.write(out)?;
        eprintln!("{}: {CHECK_MARKDOWN}, {CHECK_JSON}", out.display());
    }
    args.max_outside.map_or(Ok(()), |max| check.gate(max))?;
    Ok(())
}
