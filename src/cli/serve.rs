//! `thorarena serve`: the benchmark as a service for interactive work — serve a session,
//! evaluate whichever policy process connects, write its results, wait for the next one.

use super::eval::{load_request, RunArgs};
use super::eval_run::evaluate;
use std::path::PathBuf;
use thorarena::policy::registry::{serve_session, PolicyTarget};
use thorarena::policy::Policy;

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
    let ctx = load_request(&args.run.request(policy, None))?;
    let session = args.run.io.session_options(ctx.io.budget_s)?;
    let target = PolicyTarget {
        robot: &ctx.robot,
        profile: &ctx.profile,
        process_profile: ctx.process_profile,
        session: &session,
        envs: ctx.envs,
        launch_log: None,
    };
    for n in 1.. {
        let mut say = |note: &str| eprintln!("{note}");
        let mut policy = serve_session(&args.session, &target, &mut |_| Ok(()), &mut say)?;
        let stem = format!("{}-{}", policy.name(), ctx.dataset_name());
        let out = thorarena::eval::results::free_numbered_dir(&args.out_root, &stem, n);
        let result = evaluate(false, &ctx, &mut policy as &mut dyn Policy, &out);
        drop(policy); // tells the client the run is over
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
