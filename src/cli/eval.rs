//! `thorarena eval`: the benchmark — every sequence of a dataset with and without force,
//! scored with FATS and the diagnostics; results streamed to a run directory that can be
//! resumed after a crash, or sharded across machines and merged.
//!
//! `thorarena merge`: the shards of one evaluation combined into the single run they add
//! up to — the same records, summary and tables as an unsharded run
//! ([`thorarena::eval::pipeline::merge`]).

use super::eval_run::{score, Notes};
use super::run_args::REQUEST_CONFLICTS;
pub use super::run_args::{RunArgs, RunOutArgs};
use anyhow::Context;
use std::path::PathBuf;
use thorarena::eval::pipeline::{merge_dirs, Evaluation, Place};
use thorarena::eval::{EvalRequest, EvalSpec};

/// Arguments of `eval`.
#[derive(Debug, clap::Args)]
pub struct Args {
    // Its help lists every family of the registry.
    #[arg(long, default_value = "balance", value_parser = thorarena::policy::registry::PolicySource::parse, help = thorarena::policy::registry::policy_help(false))]
    pub policy: thorarena::policy::registry::PolicySource,
    /// Run the evaluation a request file describes (JSON, every field of
    /// `thorarena::eval::EvalRequest`; a sweep task writes one per attempt) instead
    /// of one given by flags. Only --out, --resume, --overwrite, --workers and the
    /// session options (--connect-timeout, --on-policy-failure, --spin-us) go with it.
    #[arg(long, conflicts_with_all = REQUEST_CONFLICTS)]
    pub request: Option<PathBuf>,
    /// Run directory (default: results/<policy>-<dataset name>).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// What to do with a run already in --out, and the shard to run.
    #[command(flatten)]
    pub to: RunOutArgs,
    /// Everything else of the run.
    #[command(flatten)]
    pub run: RunArgs,
}

/// The checked evaluation of `request`; its advice is printed.
pub(super) fn load_request(request: &EvalRequest) -> anyhow::Result<EvalSpec> {
    let spec = EvalSpec::load(request)?;
    for advice in &spec.advice {
        eprintln!("{}", super::flags::as_flags(&advice.to_string()));
    }
    Ok(spec)
}

pub(super) fn run(args: &Args) -> anyhow::Result<()> {
    let request = match &args.request {
        Some(path) => {
            let mut request = EvalRequest::read(path).context("--request")?;
            request.workers = args.run.workers.or(request.workers);
            request
        }
        None => args.run.request(args.policy.clone(), args.to.shard),
    };
    let spec = load_request(&request)?;
    let session = args.run.io.session_options(spec.io.budget_s)?;
    let place = Place::Given {
        out: args.out.clone(),
        resume: args.to.resume,
        overwrite: args.to.overwrite,
    };
    let mut evaluation = Evaluation::of_spec(spec, &request, place, &session, &mut Notes)?;
    score(&mut evaluation)
}

/// Arguments of `merge`.
#[derive(Debug, clap::Args)]
pub struct MergeArgs {
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

/// `merge`: the shards written as one run, its tables printed.
pub(super) fn merge(args: &MergeArgs) -> anyhow::Result<()> {
    let robot = thorarena::policy::registry::robot(&args.robot)?;
    let merged = merge_dirs(&args.runs, &args.out, args.overwrite, &robot)?;
    println!("{}", merged.tables);
    eprintln!(
        "merged {} runs, {} episodes → {}",
        args.runs.len(),
        merged.summary.episodes,
        args.out.display()
    );
    Ok(())
}
