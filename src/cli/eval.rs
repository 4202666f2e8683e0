//! `thorarena eval`: the benchmark — every sequence of a dataset with and without force,
//! scored with FATS and the diagnostics; results streamed to a run directory that can be
//! resumed after a crash, or sharded across machines and merged.

use super::run_output::{read_header, sort_records, write_header, write_results};
use crate::episode::TerminationRule;
use crate::motion::Dataset;
use crate::policy::{BalanceGains, BalancePolicy, HoldPolicy, Policy, ReplayPolicy};
use crate::profile::{bundled_profile_path, load_profile};
use crate::runner::{read_records, run_eval, schedule, write_record, EvalPlan, RunHeader, Setting};
use anyhow::{bail, Context};
use std::collections::HashSet;
use std::io::Write;
use std::path::PathBuf;
use std::sync::Mutex;

/// Arguments of `eval`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Dataset directory (canonical format) [default: the bundled data/sample].
    #[arg(long)]
    pub dataset: Option<PathBuf>,
    /// Built-in policy: `balance` (reference PD + tilt feedback), `replay` (reference
    /// joints, open loop) or `hold` (default pose).
    #[arg(long, default_value = "balance")]
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
    /// Continue the run in `--out`: keep its finished episodes, run the rest.
    #[arg(long)]
    pub resume: bool,
    /// Run only shard I of N of the schedule (`I/N`, 0-based); merge shards with `thorarena merge`.
    #[arg(long, value_parser = parse_shard)]
    pub shard: Option<(usize, usize)>,
    /// Termination: torso height off its reference by more than this, m.
    #[arg(long, default_value_t = TerminationRule::default().max_torso_height_error_m)]
    pub max_torso_height_error: f64,
    /// Termination: torso tilt off its reference by more than this, rad.
    #[arg(long, default_value_t = TerminationRule::default().max_torso_tilt_error_rad)]
    pub max_torso_tilt_error: f64,
    /// Write a rollout trace (per control step: root, joints, targets, hand forces,
    /// robot and reference keypoints) of these sequences, as `TASK/SEQUENCE_ID`, to
    /// `<out>/traces/`.
    #[arg(long, value_delimiter = ',')]
    pub trace: Vec<String>,
    /// Robot.
    #[arg(long, default_value = "g1_29dof")]
    pub robot: String,
}

fn parse_shard(s: &str) -> Result<(usize, usize), String> {
    let (i, n) = s.split_once('/').ok_or("expected I/N, e.g. 0/4")?;
    let (i, n): (usize, usize) = (
        i.parse().map_err(|_| "I is not a number")?,
        n.parse().map_err(|_| "N is not a number")?,
    );
    if n == 0 || i >= n {
        return Err(format!("shard {i}/{n}: need 0 <= I < N"));
    }
    Ok((i, n))
}

pub(super) fn run(args: &Args) -> anyhow::Result<()> {
    let dataset = args
        .dataset
        .clone()
        .unwrap_or_else(|| crate::data_dir().join("sample"));
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
        "balance" => {
            let gains = BalanceGains::default();
            let robot = robot.clone();
            BalancePolicy::new(&robot, default_pose.clone(), gains)
                .context("the robot lacks the leg joints `balance` needs")?;
            Box::new(move || {
                Box::new(
                    BalancePolicy::new(&robot, default_pose.clone(), gains).expect("checked above"),
                ) as Box<dyn Policy>
            })
        }
        other => bail!("unknown policy `{other}` (built-in: hold, replay, balance)"),
    };
    for (flag, v) in [
        ("--max-torso-height-error", args.max_torso_height_error),
        ("--max-torso-tilt-error", args.max_torso_tilt_error),
    ] {
        if !(v.is_finite() && v > 0.0) {
            bail!("{flag} must be > 0, got {v}");
        }
    }
    let ds = Dataset::open(&dataset, &robot)?;
    let sequences = ds.load_all()?;
    let header = RunHeader {
        version: env!("CARGO_PKG_VERSION").into(),
        policy: args.policy.clone(),
        profile: profile.name.clone(),
        control_dt_s: profile.control_dt_s,
        dataset: dataset.display().to_string(),
        dataset_sha256: ds.content_hash(),
        keypoints: args.keypoints.clone(),
        termination: TerminationRule {
            max_torso_height_error_m: args.max_torso_height_error,
            max_torso_tilt_error_rad: args.max_torso_tilt_error,
        },
        settings,
        shard: args.shard,
    };
    let name = dataset
        .file_name()
        .and_then(|s| s.to_str())
        .unwrap_or("dataset");
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("results").join(format!("{}-{name}", args.policy)));
    std::fs::create_dir_all(&out).with_context(|| format!("creating {}", out.display()))?;
    let episodes_path = out.join("episodes.jsonl");

    // Resume: keep what a previous run of the same configuration finished.
    let mut done = Vec::new();
    if args.resume && out.join("run.json").exists() {
        let previous = read_header(&out)?;
        if previous != header {
            bail!("--resume: {} was started with another configuration ({previous:?}); use another --out", out.display());
        }
        let (records, good_end) = read_records(&episodes_path)
            .with_context(|| format!("reading {}", episodes_path.display()))?;
        let file = std::fs::OpenOptions::new()
            .write(true)
            .open(&episodes_path)?;
        file.set_len(good_end)?; // drop a torn last line
        done = records;
    } else if args.resume {
        eprintln!(
            "--resume: nothing to resume in {}, starting afresh",
            out.display()
        );
    }
    if !args.resume {
        std::fs::File::create(&episodes_path)
            .with_context(|| format!("creating {}", episodes_path.display()))?;
    }
    write_header(&out, &header)?;
    let finished: HashSet<(String, String, String)> = done
        .iter()
        .map(|r| (r.task.clone(), r.sequence_id.clone(), r.setting.clone()))
        .collect();
    let jobs: Vec<(usize, usize)> = schedule(sequences.len(), header.settings.len(), header.shard)
        .into_iter()
        .filter(|&(q, s)| {
            let key = (
                sequences[q].task.clone(),
                sequences[q].sequence_id.clone(),
                header.settings[s].name.clone(),
            );
            !finished.contains(&key)
        })
        .collect();

    let workers = args
        .workers
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let plan = EvalPlan {
        robot: &robot,
        profile: &profile,
        keypoints: &args.keypoints,
        termination: header.termination,
        settings: header.settings.clone(),
        workers,
        trace: args.trace.clone(),
    };
    for name in &args.trace {
        if !sequences
            .iter()
            .any(|q| format!("{}/{}", q.task, q.sequence_id) == *name)
        {
            bail!(
                "--trace: no sequence `{name}` in {} (use TASK/SEQUENCE_ID)",
                ds.dir.display()
            );
        }
    }
    let traces_dir = out.join("traces");
    if !args.trace.is_empty() {
        std::fs::create_dir_all(&traces_dir)?;
    }
    eprintln!(
        "evaluating `{}` on {}: {} episodes to run ({} already done), {workers} workers",
        args.policy,
        ds.dir.display(),
        jobs.len(),
        done.len()
    );
    let file = std::fs::OpenOptions::new()
        .append(true)
        .open(&episodes_path)?;
    let writer = Mutex::new((std::io::BufWriter::new(file), None::<std::io::Error>));
    let bar = indicatif::ProgressBar::new(jobs.len() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{bar:40} {pos}/{len} episodes  {elapsed} elapsed, ~{eta} left  {msg}",
        )
        .expect("valid template"),
    );
    let new = run_eval(
        &plan,
        &sequences,
        &jobs,
        make_policy.as_ref(),
        &|r, trace| {
            let mut w = writer.lock().expect("writer");
            if let Err(e) = write_record(&mut w.0, r) {
                w.1.get_or_insert(e);
            }
            if let Some(trace) = trace {
                let path =
                    traces_dir.join(format!("{}-{}-{}.json", r.task, r.sequence_id, r.setting));
                let written = serde_json::to_vec(trace)
                    .map_err(std::io::Error::other)
                    .and_then(|b| std::fs::write(&path, b));
                if let Err(e) = written {
                    w.1.get_or_insert(e);
                }
            }
            bar.set_message(format!("{}/{} ({})", r.task, r.sequence_id, r.setting));
            bar.inc(1);
        },
    );
    bar.finish_and_clear();
    let (mut w, err) = writer.into_inner().expect("writer");
    w.flush()?;
    if let Some(e) = err {
        return Err(e).with_context(|| format!("writing {}", episodes_path.display()));
    }
    let mut records = done;
    records.extend(new);
    sort_records(&mut records, &header, &sequences);
    let tables = write_results(&out, &header, &records, &sequences)?;
    println!("{tables}");
    eprintln!(
        "wrote {}/{{run.json, episodes.jsonl, summary.json, tables.md}}",
        out.display()
    );
    Ok(())
}
