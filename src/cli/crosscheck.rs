//! `thorarena crosscheck`: the same episodes on rapier and on MuJoCo, compared — the
//! fidelity report of a policy: per episode and per setting, survival, keypoint error and
//! score on each engine and their differences, means with a bootstrap 95 % confidence
//! interval. Both runs are ordinary run directories (`<out>/rapier`, `<out>/mujoco`).

use super::crosscheck_series::{EpisodeKey, SeriesLog, SERIES_FILE};
use super::eval::{check_out, evaluate, load_spec, FirstSeconds, RunArgs};
use super::policy_arg::make_policy;
use anyhow::{bail, Context};
use std::fmt::Write as _;
use std::path::PathBuf;
use thorarena::results::crosscheck::{
    compare_push_levels, compare_settings, foot_slip_pair, joint_divergence, pair_episodes,
    Compared, CrosscheckFile, EngineRuns, MeanCi, SettingComparison, SLIP_PARTING_M,
};
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

/// The comparison table of `rows` and the table of their joint-angle divergence.
fn tables(first_column: &str, rows: &[SettingComparison], divergence_seconds: f64) -> String {
    let mut table = format!(
        "| {first_column} | episodes | metric | rapier | mujoco | mujoco − rapier [95 % CI] |\n|---|---:|---|---:|---:|---|\n",
    );
    for s in rows {
        for (metric, c, d) in [
            ("survival", &s.survival, 3),
            ("keypoint error (mm)", &s.kp_mm, 1),
            ("FATS", &s.fats, 2),
            ("foot slip per episode (m)", &s.foot_slip_m, 3),
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
    let _ = write!(
        table,
        "\n| {first_column} | episodes | RMS joint-angle divergence over the first {divergence_seconds} s, rad [95 % CI] | feet's slip parts by > {parting_cm} cm: episodes, at (s) [95 % CI] |\n|---|---:|---|---|\n",
        parting_cm = SLIP_PARTING_M * 100.0,
    );
    for s in rows {
        let MeanCi {
            episodes,
            mean,
            ci95,
        } = s.joint_divergence_rad;
        let parts = &s.slip_parts_at_s;
        let when = if s.slip_parted == 0 {
            "—".to_string()
        } else {
            format!(
                "{:.2} [{:.2}, {:.2}]",
                parts.mean, parts.ci95[0], parts.ci95[1]
            )
        };
        let _ = writeln!(
            table,
            "| {} | {episodes} | {mean:.4} [{:.4}, {:.4}] | {} of {}, {when} |",
            s.setting, ci95[0], ci95[1], s.slip_parted, s.episodes,
        );
    }
    table
}

/// The most bootstrap resamples `--bootstrap` takes (10⁶ already pins a 95 % interval's
/// ends to a fraction of a per cent of its width).
const MAX_BOOTSTRAP: usize = 1_000_000;

pub(super) fn run(args: &Args) -> anyhow::Result<()> {
    if args.policy.starts_with("ipc:") {
        bail!("crosscheck runs the policy twice in process: use a built-in, twist2: or beyondmimic: policy");
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
    for d in &dirs {
        check_out(d, &args.run)?;
    }
    // Per engine, each episode's joint angles of the first seconds and the feet's
    // accumulated slip, kept on disk as episodes finish (a resume keeps them).
    let mut series = Vec::new();
    for ((run_args, ctx), dir) in [(&rapier_args, &rapier_ctx), (&mujoco_args, &mujoco_ctx)]
        .into_iter()
        .zip(&dirs)
    {
        eprintln!("== {} → {}", ctx.engine.name(), dir.display());
        let mut log = SeriesLog::open(dir, run_args.resume)?;
        let mut policy = make_policy(
            &args.policy,
            &ctx.robot,
            &ctx.profile,
            &run_args.io,
            ctx.envs,
        )?;
        let seconds = args.divergence_seconds;
        let mut write_error = None;
        let mut sink = |r: &thorarena::evaluation::EpisodeRecord,
                        trace: &thorarena::episode::EpisodeTrace| {
            let q = trace
                .steps
                .iter()
                .take_while(|s| s.time_s <= seconds + 1e-9)
                .map(|s| s.q.clone())
                .collect();
            if let Err(e) = log.append(r.key(), q, trace.foot_slip_m.clone()) {
                write_error.get_or_insert(e);
            }
        };
        let first = FirstSeconds {
            seconds,
            sink: &mut sink,
        };
        evaluate(run_args, ctx, policy.as_mut(), dir, Some(first))?;
        if let Some(e) = write_error {
            return Err(e);
        }
        series.push(log);
    }
    let read = |dir: &PathBuf| -> anyhow::Result<_> {
        let header = read_header(dir)?;
        let log = EpisodeLog::read(&dir.join(EPISODES_FILE), &header)?;
        Ok((header, log.records, read_summary(dir)?.thresholds))
    };
    let (header, a, thresholds) = read(&dirs[0])?;
    let (_, b, _) = read(&dirs[1])?;
    let (mut pairs, unpaired) = pair_episodes(&a, &b, &thresholds);
    if !unpaired.is_empty() {
        bail!(
            "{} episodes ran on one engine only (e.g. {})",
            unpaired.len(),
            unpaired[0]
        );
    }
    let mut without_series = 0;
    for p in &mut pairs {
        let key = EpisodeKey {
            task: p.task.clone(),
            sequence_id: p.sequence_id.clone(),
            setting: p.setting.clone(),
        };
        let (a, b) = (&series[0], &series[1]);
        if let (Some(qa), Some(qb)) = (a.first_q.get(&key), b.first_q.get(&key)) {
            p.joint_divergence = joint_divergence(qa, qb);
        } else {
            without_series += 1;
        }
        if let (Some(sa), Some(sb)) = (a.foot_slip_m.get(&key), b.foot_slip_m.get(&key)) {
            p.foot_slip = foot_slip_pair(sa, sb, header.control_dt_s);
        }
    }
    if without_series > 0 {
        eprintln!(
            "warning: {without_series} of {} episodes have no joint divergence or foot slip: their series are not in {} (a run resumed from an older crosscheck?); --overwrite runs them again",
            pairs.len(),
            SERIES_FILE
        );
    }
    let settings = compare_settings(&pairs, args.bootstrap, 0);
    println!("{}", tables("setting", &settings, args.divergence_seconds));
    let levels = compare_push_levels(&pairs, &header.settings, args.bootstrap, 0);
    if levels.len() < settings.len() {
        println!("Per push force, over its directions:\n");
        println!(
            "{}",
            tables("push per hand", &levels, args.divergence_seconds)
        );
    }
    let json = CrosscheckFile {
        runs: EngineRuns {
            rapier: &dirs[0],
            mujoco: &dirs[1],
        },
        bootstrap_resamples: args.bootstrap,
        divergence_seconds: args.divergence_seconds,
        settings: &settings,
        push_levels: &levels,
        episodes: &pairs,
    };
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
        "joint_divergence_steps",
        "joint_divergence_rms_rad",
        "joint_divergence_max_rad",
        "foot_slip_m_rapier",
        "foot_slip_m_mujoco",
        "foot_slip_parts_at_s",
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
            p.joint_divergence
                .map_or(String::new(), |d| d.steps.to_string()),
            num(p.joint_divergence.map_or(f64::NAN, |d| d.rms_rad)),
            num(p.joint_divergence.map_or(f64::NAN, |d| d.max_rad)),
            num(p.foot_slip.map_or(f64::NAN, |f| f.total_m[0])),
            num(p.foot_slip.map_or(f64::NAN, |f| f.total_m[1])),
            num(p.foot_slip.and_then(|f| f.parts_at_s).unwrap_or(f64::NAN)),
        ])?;
    }
    let csv_path = out.join("crosscheck.csv");
    std::fs::write(&csv_path, w.into_inner()?)
        .with_context(|| format!("writing {}", csv_path.display()))?;
    eprintln!("wrote {} and {}", json_path.display(), csv_path.display());
    Ok(())
}
