//! `thorarena eval`: the benchmark — every sequence of a dataset with and without force,
//! scored with FATS and the diagnostics; results streamed to a run directory.

use crate::episode::TerminationRule;
use crate::motion::Dataset;
use crate::policy::{HoldPolicy, Policy, ReplayPolicy};
use crate::profile::{bundled_profile_path, load_profile};
use crate::report::{diagnostics_table, task_fats_table};
use crate::runner::{run_eval, summarize, task_thresholds, write_record, EvalPlan, Setting};
use anyhow::{bail, Context};
use std::path::PathBuf;
use std::sync::Mutex;

/// Arguments of `eval`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Dataset directory (canonical format).
    #[arg(long, default_value = "data/sample")]
    pub dataset: PathBuf,
    /// Policy: `hold` (default pose) or `replay` (reference joints, open loop).
    #[arg(long, default_value = "replay")]
    pub policy: String,
    /// Dynamics profile (a name under data/profiles or a .toml path).
    #[arg(long, default_value = "default")]
    pub profile: String,
    /// Settings, comma separated: `force`, `no-force`, or a replay coefficient.
    #[arg(long, value_delimiter = ',', default_value = "force,no-force")]
    pub settings: Vec<String>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub workers: Option<usize>,
    /// Keypoint set of the tracking error.
    #[arg(long, default_value = "default")]
    pub keypoints: String,
    /// Run directory (default: results/<policy>-<dataset name>).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Robot.
    #[arg(long, default_value = "g1_29dof")]
    pub robot: String,
}

pub(super) fn run(args: &Args) -> anyhow::Result<()> {
    let robot = super::load_robot(&args.robot)?;
    let profile_path = if args.profile.ends_with(".toml") {
        PathBuf::from(&args.profile)
    } else {
        bundled_profile_path(&args.profile)
    };
    let profile = load_profile(&profile_path, &robot)?;
    if robot.keypoint_set(&args.keypoints).is_none() {
        bail!(
            "unknown keypoint set `{}` for robot {}",
            args.keypoints,
            robot.name
        );
    }
    let settings: Vec<Setting> = args
        .settings
        .iter()
        .map(|s| {
            Setting::parse(s)
                .with_context(|| format!("--settings: `{s}` is not force, no-force or a number"))
        })
        .collect::<anyhow::Result<_>>()?;
    let default_pose = profile.action_offset_rad.clone();
    let make_policy: Box<dyn Fn() -> Box<dyn Policy> + Sync> = match args.policy.as_str() {
        "hold" => Box::new(|| Box::new(HoldPolicy) as Box<dyn Policy>),
        "replay" => {
            Box::new(move || Box::new(ReplayPolicy::new(default_pose.clone())) as Box<dyn Policy>)
        }
        other => bail!("unknown policy `{other}` (built-in: hold, replay)"),
    };
    let ds = Dataset::open(&args.dataset, &robot)?;
    let sequences = ds.load_all()?;
    let workers = args
        .workers
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let name = args
        .dataset
        .file_name()
        .and_then(|s| s.to_str())
        .unwrap_or("dataset");
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("results").join(format!("{}-{name}", args.policy)));
    std::fs::create_dir_all(&out).with_context(|| format!("creating {}", out.display()))?;
    let episodes_path = out.join("episodes.jsonl");
    let file = std::fs::File::create(&episodes_path)
        .with_context(|| format!("creating {}", episodes_path.display()))?;
    let writer = Mutex::new((
        std::io::BufWriter::new(file),
        0usize,
        None::<std::io::Error>,
    ));
    let total = sequences.len() * settings.len();
    let plan = EvalPlan {
        robot: &robot,
        profile: &profile,
        keypoints: &args.keypoints,
        termination: TerminationRule::default(),
        settings,
        workers,
    };
    eprintln!(
        "evaluating `{}` on {} ({} sequences × {} settings, {workers} workers)",
        args.policy,
        ds.dir.display(),
        sequences.len(),
        plan.settings.len()
    );
    let records = run_eval(&plan, &sequences, make_policy.as_ref(), &|r| {
        let mut w = writer.lock().expect("writer");
        if let Err(e) = write_record(&mut w.0, r) {
            w.2.get_or_insert(e);
        }
        w.1 += 1;
        eprint!("\r{}/{} episodes", w.1, total);
    });
    eprintln!();
    if let Some(e) = writer.into_inner().expect("writer").2 {
        return Err(e).with_context(|| format!("writing {}", episodes_path.display()));
    }
    let thresholds = task_thresholds(&sequences, profile.control_dt_s);
    let results = summarize(&records, &thresholds);
    let header = format!(
        "ThorArena {} — policy `{}`, profile `{}`, dataset {} (content sha256 {}), keypoints `{}`, termination: torso height error > {} m or tilt error > {} rad",
        env!("CARGO_PKG_VERSION"),
        args.policy,
        profile.name,
        ds.dir.display(),
        &ds.content_hash()[..16],
        args.keypoints,
        plan.termination.max_torso_height_error_m,
        plan.termination.max_torso_tilt_error_rad
    );
    let tables = format!(
        "{header}\n\n## Task-level FATS\n\n{}\n## Diagnostics (averaged over tasks)\n\n{}",
        task_fats_table(&results),
        diagnostics_table(&results)
    );
    println!("{tables}");
    std::fs::write(out.join("tables.md"), &tables)?;
    let summary = serde_json::json!({
        "version": env!("CARGO_PKG_VERSION"),
        "policy": args.policy,
        "profile": profile.name,
        "dataset": ds.dir,
        "dataset_sha256": ds.content_hash(),
        "keypoints": args.keypoints,
        "termination": plan.termination,
        "thresholds": thresholds,
        "settings": results.iter().map(|(k, (tasks, overall))| (k.clone(), serde_json::json!({"tasks": tasks, "average": overall}))).collect::<serde_json::Map<_, _>>(),
    });
    std::fs::write(
        out.join("summary.json"),
        serde_json::to_string_pretty(&summary)? + "\n",
    )?;
    eprintln!(
        "wrote {}/{{episodes.jsonl, summary.json, tables.md}}",
        out.display()
    );
    Ok(())
}
