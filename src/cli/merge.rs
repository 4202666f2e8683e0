//! `thorarena merge`: combine the shards of one evaluation into the single run they add
//! up to — the same records, summary and tables as an unsharded run
//! ([`thorarena::benchmark::merge`]).

use std::path::PathBuf;
use thorarena::results::RunDir;

/// Arguments of `merge`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Run directories (shards of the same evaluation).
    #[arg(required = true)]
    pub runs: Vec<PathBuf>,
    /// Output run directory.
    #[arg(long)]
    pub out: PathBuf,
    /// Robot.
    #[arg(long, default_value = "g1_29dof")]
    pub robot: String,
    /// Replace a run already in `--out` (never one of the shards).
    #[arg(long)]
    pub overwrite: bool,
}

pub(super) fn run(args: &Args) -> anyhow::Result<()> {
    thorarena::results::check_dir(&args.out, args.overwrite, &args.runs)?;
    let robot = thorarena::registry::robot(&args.robot)?;
    let shards: Vec<RunDir> = args.runs.iter().map(RunDir::new).collect();
    let merged = thorarena::benchmark::merge(&shards, &RunDir::new(&args.out), &robot)?;
    println!("{}", merged.tables);
    eprintln!(
        "merged {} runs, {} episodes → {}",
        args.runs.len(),
        merged.summary.episodes,
        args.out.display()
    );
    Ok(())
}
