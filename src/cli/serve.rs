//! `thorarena serve`: the benchmark as a service for interactive work — serve a session,
//! evaluate whichever policy process connects, write its results, wait for the next one.

use super::eval::{load_request, RunArgs};
use super::eval_run::{score, Notes};
use std::path::PathBuf;
use thorarena::eval::pipeline::{Evaluation, Place};

/// Arguments of `serve`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Session name: policies connect to `thorarena/<session>/…` (Python:
    /// `thorarena.connect("<session>", …)`; C: `thorarena_connect`).
    #[arg(long, value_parser = thorarena::policy::registry::PolicySource::session_name)]
    pub session: String,
    /// Evaluate one policy, then exit.
    #[arg(long)]
    pub once: bool,
    /// Directory of the runs: each connection writes `<dir>/<policy name>-<dataset>-<n>/`,
    /// with the first `n` not taken yet.
    #[arg(long, default_value = "results")]
    pub out_root: PathBuf,
    /// Everything else of the run.
    #[command(flatten)]
    pub run: RunArgs,
}

pub(super) fn run(args: &Args) -> anyhow::Result<()> {
    let policy = thorarena::policy::registry::PolicySource::on_session(&args.session);
    let request = args.run.request(policy, None);
    let spec = load_request(&request)?;
    let session = args.run.io.session_options(spec.io.budget_s)?;
    for n in 1.. {
        let place = Place::Numbered {
            root: args.out_root.clone(),
            from: n,
        };
        let mut evaluation =
            Evaluation::of_spec(spec.clone(), &request, place, &session, &mut Notes)?;
        let result = score(&mut evaluation);
        drop(evaluation); // tells the client the run is over
        if let Err(e) = &result {
            eprintln!(
                "run {n} ended with an error: {}",
                super::flags::as_flags(&thorarena::files::log_text::causes_once(e.as_ref()))
            );
        }
        if args.once {
            return result;
        }
        eprintln!("ready for the next policy on session `{}`", args.session);
    }
    Ok(())
}
