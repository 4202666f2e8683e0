//! `thorarena crosscheck`: the same episodes on rapier and on MuJoCo, compared — the
//! fidelity report of a policy: per episode and per setting, survival, keypoint error and
//! score on each engine and their differences, means with a bootstrap 95 % confidence
//! interval. Both runs are ordinary run directories (`<out>/rapier`, `<out>/mujoco`).

use super::eval::{check_out, evaluate, EvalContext, RunArgs};
use super::policy_arg::make_policy;
use anyhow::{bail, Context};
use std::fmt::Write as _;
use std::path::PathBuf;
use thorarena::results::crosscheck::{compare_settings, pair_episodes, Compared};
use thorarena::results::{read_header, read_summary, EpisodeLog, EPISODES_FILE};

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
    /// Everything else of the runs (`--engine` is ignored: both engines run; `--mjcf`
    /// and `--physics-dt` apply to MuJoCo and rapier as for `eval`).
    #[command(flatten)]
    pub run: RunArgs,
}

fn fmt(c: &Compared, decimals: usize) -> String {
    format!(
        "{:.d$} | {:.d$} | {:+.d$} [{:+.d$}, {:+.d$}]",
        c.a,
        c.b,
        c.diff,
        c.ci95[0],
        c.ci95[1],
        d = decimals
    )
}

pub(super) fn run(args: &Args) -> anyhow::Result<()> {
    if args.policy.starts_with("ipc:") {
        bail!("crosscheck runs the policy twice in process: use a built-in, twist2: or beyondmimic: policy");
    }
    if args.run.engine != super::choices::EngineArg::Rapier {
        bail!("crosscheck runs both engines: leave out --engine");
    }
    let mut rapier_args = args.run.clone();
    rapier_args.mjcf = None;
    let mut mujoco_args = args.run.clone();
    mujoco_args.engine = super::choices::EngineArg::Mujoco;
    // Both contexts first: a missing MuJoCo fails before anything runs.
    let rapier_ctx = EvalContext::load(&rapier_args)?;
    let mujoco_ctx = EvalContext::load(&mujoco_args)?;
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
    for d in &dirs {
        check_out(d, &args.run)?;
    }
    for ((run_args, ctx), dir) in [(&rapier_args, &rapier_ctx), (&mujoco_args, &mujoco_ctx)]
        .into_iter()
        .zip(&dirs)
    {
        eprintln!("== {} → {}", ctx.engine.name(), dir.display());
        let mut policy = make_policy(
            &args.policy,
            &ctx.robot,
            &ctx.profile,
            &run_args.io,
            ctx.envs,
        )?;
        evaluate(run_args, ctx, policy.as_mut(), dir)?;
    }
    let read = |dir: &PathBuf| -> anyhow::Result<_> {
        let header = read_header(dir)?;
        let log = EpisodeLog::read(&dir.join(EPISODES_FILE), &header)?;
        Ok((log.records, read_summary(dir)?.thresholds))
    };
    let (a, thresholds) = read(&dirs[0])?;
    let (b, _) = read(&dirs[1])?;
    let (pairs, unpaired) = pair_episodes(&a, &b, &thresholds);
    if !unpaired.is_empty() {
        bail!(
            "{} episodes ran on one engine only (e.g. {:?})",
            unpaired.len(),
            unpaired[0]
        );
    }
    let settings = compare_settings(&pairs, args.bootstrap, 0);
    let mut table = String::from(
        "| setting | episodes | metric | rapier | mujoco | mujoco − rapier [95 % CI] |\n|---|---:|---|---:|---:|---|\n",
    );
    for s in &settings {
        for (metric, c, d) in [
            ("survival", &s.survival, 3),
            ("keypoint error (mm)", &s.kp_mm, 1),
            ("episode score", &s.score, 2),
        ] {
            let _ = writeln!(
                table,
                "| {} | {} | {metric} | {} |",
                s.setting,
                s.episodes,
                fmt(c, d)
            );
        }
    }
    println!("{table}");
    let json = serde_json::json!({
        "runs": {"rapier": dirs[0], "mujoco": dirs[1]},
        "bootstrap_resamples": args.bootstrap,
        "settings": settings,
        "episodes": pairs,
    });
    let json_path = out.join("crosscheck.json");
    std::fs::write(&json_path, serde_json::to_string_pretty(&json)? + "\n")
        .with_context(|| format!("writing {}", json_path.display()))?;
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record([
        "task",
        "sequence_id",
        "setting",
        "survival_rapier",
        "survival_mujoco",
        "kp_mm_rapier",
        "kp_mm_mujoco",
        "score_rapier",
        "score_mujoco",
    ])?;
    let num = |v: f64| {
        if v.is_finite() {
            v.to_string()
        } else {
            String::new()
        }
    };
    for p in &pairs {
        w.write_record([
            p.task.clone(),
            p.sequence_id.clone(),
            p.setting.clone(),
            num(p.a.survival),
            num(p.b.survival),
            num(p.a.kp_mm),
            num(p.b.kp_mm),
            num(p.a.score),
            num(p.b.score),
        ])?;
    }
    let csv_path = out.join("crosscheck.csv");
    std::fs::write(&csv_path, w.into_inner()?)
        .with_context(|| format!("writing {}", csv_path.display()))?;
    eprintln!("wrote {} and {}", json_path.display(), csv_path.display());
    Ok(())
}
