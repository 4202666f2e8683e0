//! `thorarena crosscheck`: the same episodes on rapier and on MuJoCo, compared — the
//! fidelity report of a policy: per episode and per setting, survival, keypoint error and
//! score on each engine and their differences, means with a bootstrap 95 % confidence
//! interval. Both runs are ordinary run directories (`<out>/rapier`, `<out>/mujoco`).

use super::eval::{load_spec, OutRules, RunArgs};
use super::eval_run::{evaluate, FirstSeconds};
use super::policy_arg::make_policy;
use anyhow::{bail, Context};
use std::path::PathBuf;
use thorarena::evaluation::EvalSpec;
use thorarena::report::crosscheck_tables;
use thorarena::results::crosscheck::{compare_runs, write_crosscheck, SeriesLog};
use thorarena::results::{RunDir, CROSSCHECK_SERIES_FILE};

/// Arguments of `crosscheck`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// An in-process policy (as `eval --policy`; not `ipc:`).
    #[arg(long, default_value = "balance")]
    pub policy: String,
    /// Output directory (default: results/crosscheck-<policy>-<dataset name>): the two
    /// runs, `crosscheck.json` and `crosscheck.csv`.
    #[arg(long)]
    pub out: Option<PathBuf>,
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

/// The most bootstrap resamples `--bootstrap` takes (10⁶ already pins a 95 % interval's
/// ends to a fraction of a per cent of its width).
const MAX_BOOTSTRAP: usize = 1_000_000;

/// One engine's evaluation into `run`, keeping each episode's series of the first
/// seconds and foot slip beside it as episodes finish (a resume keeps them).
fn run_engine(
    args: &Args,
    run_args: &RunArgs,
    spec: &EvalSpec,
    run: &RunDir,
) -> anyhow::Result<SeriesLog> {
    eprintln!("== {} → {}", spec.engine.name(), run.path().display());
    let mut log = SeriesLog::open(run, run_args.resume)?;
    for (line, why) in &log.dropped_lines {
        eprintln!(
            "--resume: {} line {line} is unreadable ({why}); its episode's series is dropped",
            run.crosscheck_series_file().display()
        );
    }
    let mut policy = make_policy(
        &args.policy,
        &spec.robot,
        &spec.profile,
        &run_args.io.session_options(spec.io.budget_s)?,
        spec.envs,
    )?;
    let seconds = args.divergence_seconds;
    let mut write_error = None;
    let mut sink = |r: &thorarena::evaluation::EpisodeRecord,
                    trace: &thorarena::episode::EpisodeTrace| {
        if let Err(e) = log.append_trace(r.key(), trace, seconds) {
            write_error.get_or_insert(e);
        }
    };
    let first = FirstSeconds {
        seconds,
        sink: &mut sink,
    };
    evaluate(
        run_args.resume,
        spec,
        policy.as_mut(),
        run.path(),
        Some(first),
    )?;
    if let Some(e) = write_error {
        return Err(e.into());
    }
    Ok(log)
}

pub(super) fn run(args: &Args) -> anyhow::Result<()> {
    if thorarena::registry::PolicyArg::parse(&args.policy)?
        .session()
        .is_some()
    {
        bail!("crosscheck runs the policy twice in process: use a built-in, twist2:, beyondmimic: or wbc-mjlab: policy");
    }
    if args.run.engine != super::choices::EngineArg::Rapier {
        bail!("crosscheck runs both engines: leave out --engine");
    }
    if !(args.divergence_seconds.is_finite() && args.divergence_seconds > 0.0) {
        bail!("--divergence-seconds must be a positive number of seconds");
    }
    // Checked before the two evaluations run: a confidence interval needs resamples, and
    // each resample holds one mean per episode in memory.
    if !(1..=MAX_BOOTSTRAP).contains(&args.bootstrap) {
        bail!(
            "--bootstrap {}: the confidence intervals need between 1 and {MAX_BOOTSTRAP} resamples",
            args.bootstrap
        );
    }
    let mut rapier_args = args.run.clone();
    rapier_args.mjcf = None;
    let mut mujoco_args = args.run.clone();
    mujoco_args.engine = super::choices::EngineArg::Mujoco;
    if let Some(dt) = args.mujoco_physics_dt {
        mujoco_args.physics_dt = Some(dt);
    }
    // Both contexts first: a missing MuJoCo fails before anything runs.
    let rapier_ctx = load_spec(&rapier_args, &args.policy)?;
    let mujoco_ctx =
        load_spec(&mujoco_args, &args.policy).with_context(|| match args.mujoco_physics_dt {
            Some(dt) => format!("the MuJoCo run (--mujoco-physics-dt {dt})"),
            None => "the MuJoCo run".to_string(),
        })?;
    let out = match &args.out {
        Some(o) => o.clone(),
        None => {
            let name = format!(
                "crosscheck-{}-{}",
                args.policy.split(':').next().unwrap_or("policy"),
                rapier_ctx.dataset_name()
            );
            thorarena::names::check_name("crosscheck directory", &name)?;
            PathBuf::from("results").join(name)
        }
    };
    let dirs = [out.join("rapier"), out.join("mujoco")];
    for (d, spec) in dirs.iter().zip([&rapier_ctx, &mujoco_ctx]) {
        OutRules::of(&args.run, spec).check(d)?;
    }
    // Per engine, each episode's joint angles of the first seconds and the feet's
    // accumulated slip, kept on disk as episodes finish (a resume keeps them).
    let runs = dirs.clone().map(RunDir::new);
    let mut series = Vec::new();
    for ((run_args, spec), run) in [(&rapier_args, &rapier_ctx), (&mujoco_args, &mujoco_ctx)]
        .into_iter()
        .zip(&runs)
    {
        series.push(run_engine(args, run_args, spec, run)?);
    }
    let check = compare_runs(
        [&runs[0], &runs[1]],
        [&series[0], &series[1]],
        args.bootstrap,
    )?;
    if check.without_series > 0 {
        eprintln!(
            "warning: {} of {} episodes have no joint divergence or foot slip: their series are not in {} (a run resumed from an older crosscheck?); --overwrite runs them again",
            check.without_series,
            check.pairs.len(),
            CROSSCHECK_SERIES_FILE
        );
    }
    println!(
        "{}",
        crosscheck_tables("setting", &check.settings, args.divergence_seconds)
    );
    if check.push_levels.len() < check.settings.len() {
        println!("Per push force, over its directions:\n");
        println!(
            "{}",
            crosscheck_tables("push per hand", &check.push_levels, args.divergence_seconds)
        );
    }
    let [json_path, csv_path] = write_crosscheck(
        &out,
        [&dirs[0], &dirs[1]],
        &check,
        args.bootstrap,
        args.divergence_seconds,
    )?;
    eprintln!("wrote {} and {}", json_path.display(), csv_path.display());
    Ok(())
}
