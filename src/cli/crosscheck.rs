//! `thorarena crosscheck`: the same episodes on rapier and on MuJoCo, compared — the
//! fidelity report of a policy: per episode and per setting, survival, keypoint error and
//! score on each engine and their differences, means with a bootstrap 95 % confidence
//! interval. Both runs are ordinary run directories (`<out>/rapier`, `<out>/mujoco`).

use super::choices::EngineArg;
use super::eval::{RunArgs, RunOutArgs};
use super::eval_run::{print_evaluated, Progress};
use super::flags::as_flags;
use std::path::PathBuf;
use thorarena::eval::pipeline::{
    compare_engines, CrosscheckObserver, CrosscheckRequest, EvalObserver, Evaluated,
};
use thorarena::eval::results::RunDir;
use thorarena::eval::EvalSpec;
use thorarena::report::crosscheck_report;

/// Arguments of `crosscheck`.
#[derive(Debug, clap::Args)]
pub struct Args {
    // Its help lists every family of the registry run in process.
    #[arg(long, default_value = "balance", value_parser = thorarena::policy::registry::PolicySource::parse, help = thorarena::policy::registry::policy_help(true))]
    pub policy: thorarena::policy::registry::PolicySource,
    /// Output directory (default: results/crosscheck-<policy>-<dataset name>): the two
    /// runs, `crosscheck.json` and `crosscheck.csv`.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// What to do with a comparison already in --out, and the shard to run.
    #[command(flatten)]
    pub to: RunOutArgs,
    /// Bootstrap resamples of the confidence intervals.
    #[arg(long, default_value_t = 2000)]
    pub bootstrap: usize,
    /// The joint angles of both engines are compared over this many seconds from each
    /// episode's start (closed loop: each engine's policy sees its own state).
    #[arg(long, default_value_t = 1.0)]
    pub divergence_seconds: f64,
    /// MuJoCo's physics step, s, when it differs from rapier's (e.g. 0.001 with
    /// `--mjcf` of TWIST2's model, the step it was validated at, while rapier runs the
    /// profile's 5 ms); default: `--physics-dt`, else the profile's.
    #[arg(long)]
    pub mujoco_physics_dt: Option<f64>,
    /// Everything else of the runs (`--engine` is refused: both engines run; `--mjcf`
    /// applies to MuJoCo, `--physics-dt` to both unless `--mujoco-physics-dt` is given).
    #[command(flatten)]
    pub run: RunArgs,
}

pub(super) fn run(args: &Args) -> anyhow::Result<()> {
    if args.run.engine != EngineArg::Rapier {
        anyhow::bail!("crosscheck runs both engines: leave out --engine");
    }
    let [rapier, mujoco] = CrosscheckRequest::engine_requests(
        &args.run.request(args.policy.clone(), args.to.shard),
        args.mujoco_physics_dt,
    );
    let request = CrosscheckRequest {
        rapier,
        mujoco,
        out: args.out.clone(),
        resume: args.to.resume,
        overwrite: args.to.overwrite,
        bootstrap: args.bootstrap,
        divergence_s: args.divergence_seconds,
    };
    let mut terminal = Terminal {
        resume: args.to.resume,
        progress: None,
    };
    let compared = compare_engines(&request, &mut terminal)?;
    println!(
        "{}",
        crosscheck_report(&compared.check, args.divergence_seconds)
    );
    let [json, csv] = &compared.files;
    eprintln!("wrote {} and {}", json.display(), csv.display());
    Ok(())
}

/// Each engine's run as `eval` shows one.
struct Terminal {
    resume: bool,
    progress: Option<Progress>,
}

impl CrosscheckObserver for Terminal {
    fn note(&mut self, text: &str) {
        eprintln!("{}", as_flags(text));
    }

    fn engine_starting(&mut self, spec: &EvalSpec, run: &RunDir, policy: &str) {
        eprintln!("== {} → {}", spec.engine.name(), run.path().display());
        self.progress = Some(Progress::new(policy, spec, run, self.resume));
    }

    fn eval_observer(&mut self) -> &mut dyn EvalObserver {
        self.progress.as_mut().expect("an engine is running")
    }

    fn engine_done(&mut self, spec: &EvalSpec, run: &RunDir, done: &Evaluated) {
        if let Some(progress) = self.progress.take() {
            progress.finish();
        }
        print_evaluated(done, spec, run);
    }
}
