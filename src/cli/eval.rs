//! `thorarena eval`: the benchmark — every sequence of a dataset with and without force,
//! scored with FATS and the diagnostics; results streamed to a run directory that can be
//! resumed after a crash, or sharded across machines and merged.

use super::policy_arg::{make_policy_vetted, PolicyIoArgs};
use anyhow::{bail, Context};
use std::collections::HashSet;
use std::io::Write;
use std::path::PathBuf;
use thorarena::episode::EpisodeTrace;
use thorarena::evaluation::{EpisodeRecord, Setting, Termination, TerminationRule};
use thorarena::motion::{Dataset, Sequence};
use thorarena::policy::Policy;
use thorarena::profile::{bundled_profile_path, load_profile, Profile};
use thorarena::results::{
    read_header, sort_records, write_header, write_record, write_results, EpisodeLog,
    PlannedSequence, PolicyIoReport, RunHeader, RESULTS_VERSION,
};
use thorarena::robot::RobotModel;
use thorarena::runner::{run_eval, task_thresholds, EvalPlan};

/// Arguments of `eval`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Built-in policy: `balance` (reference PD + tilt feedback), `replay` (reference
    /// joints, open loop) or `hold` (default pose); `twist2:<file.onnx>` for the TWIST2
    /// network in process (with `--profile twist2`); `beyondmimic:<file.onnx>` for a
    /// BeyondMimic-style tracking network (mjlab, whole_body_tracking, holosoma; e.g. with
    /// `--profile holosoma-wbt`); or `ipc:<session>` to serve a session
    /// and evaluate whichever policy process connects to it (Python, C++, Rust clients).
    #[arg(long, default_value = "balance")]
    pub policy: String,
    /// Run directory (default: results/<policy>-<dataset name>).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Everything else of the run.
    #[command(flatten)]
    pub run: RunArgs,
}

/// What an evaluation needs besides the policy and where results go (shared with `serve`).
#[derive(Debug, Clone, clap::Args)]
pub struct RunArgs {
    /// Dataset directory (canonical format) [default: the bundled data/sample].
    #[arg(long)]
    pub dataset: Option<PathBuf>,
    /// Dynamics profile (a name under data/profiles or a .toml path) [default: the one the
    /// policy family was trained with: `twist2` for twist2:, `beyondmimic` for
    /// beyondmimic:, else `default`]. One that contradicts the family is an error.
    #[arg(long)]
    pub profile: Option<String>,
    /// Run a policy under a profile its family was not trained with (recorded in
    /// run.json): a TWIST2 network on the default profile scores 2 instead of 86.
    #[arg(long)]
    pub profile_mismatch_ok: bool,
    /// Settings, comma separated: `force`, `no-force`, a replay coefficient, or
    /// `push:<N>` (no replay; a constant world +x push of N newtons on each hand, ramped
    /// in over 1 s — the sensitivity probe of SOURCES.md, TWIST2 in MuJoCo), or `push:<N>@<deg>` with the
    /// push turned by deg from the reference's initial heading (`push:20@90`: from the
    /// robot's right).
    /// [default: force,no-force; no-force alone on a dataset without force logs].
    #[arg(long, value_delimiter = ',')]
    pub settings: Vec<String>,
    /// Run replay settings (`force`, a coefficient) on a dataset whose sequences have no
    /// force logs: they replay zero forces, i.e. run as `no-force` under another name.
    #[arg(long)]
    pub replay_without_force_logs: bool,
    /// Evaluate only these tasks, comma separated (default: every task). The run records
    /// the selection, and its tables say they cover part of the dataset.
    #[arg(long, value_delimiter = ',')]
    pub tasks: Vec<String>,
    /// Evaluate only these sequences, comma separated, each `SEQUENCE_ID` or
    /// `TASK/SEQUENCE_ID` (default: every sequence; with --tasks, those of both).
    #[arg(long, value_delimiter = ',')]
    pub sequences: Vec<String>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub workers: Option<usize>,
    /// Keypoint set of the tracking error.
    #[arg(long, default_value = "default")]
    pub keypoints: String,
    /// Continue the run in `--out`: keep its finished episodes, run the rest.
    #[arg(long, conflicts_with = "overwrite")]
    pub resume: bool,
    /// Replace a run already in `--out` (without it, an existing run is refused).
    #[arg(long)]
    pub overwrite: bool,
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
    /// Physics engine: `rapier` (built in), or `mujoco` (a build with the `mujoco`
    /// feature) on the MJCF given by --mjcf.
    #[arg(long, value_enum, default_value = "rapier")]
    pub engine: super::choices::EngineArg,
    /// A user's MJCF of the robot for `--engine mujoco`, joints and bodies named as in the
    /// robot model (e.g. TWIST2's `g1/g1_sim2sim_29dof.xml` of the reference artifacts);
    /// without it, MuJoCo simulates an MJCF generated from the robot model
    /// (`thorarena robot mjcf` prints it).
    #[arg(long)]
    pub mjcf: Option<PathBuf>,
    /// Physics step, s, instead of the profile's (a whole fraction of its control step).
    #[arg(long)]
    pub physics_dt: Option<f64>,
    /// Policy I/O: slots, latency budget, miss rule, latency mode, session options.
    #[command(flatten)]
    pub io: PolicyIoArgs,
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

/// The bundled profiles' names (`data/profiles/*.toml`), sorted.
fn bundled_profile_names() -> Vec<String> {
    let dir = bundled_profile_path("x")
        .parent()
        .map(std::path::Path::to_path_buf)
        .unwrap_or_default();
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .filter_map(|e| {
            let p = e.path();
            (p.extension()? == "toml").then(|| p.file_stem()?.to_str().map(str::to_string))?
        })
        .collect();
    names.sort();
    names
}

/// `--settings` when none is given (on a dataset with force logs).
const DEFAULT_SETTINGS: [&str; 2] = ["force", "no-force"];

/// Replay settings need recorded forces: on a dataset without force logs the default
/// becomes `no-force` alone, and an explicit replay setting is refused unless
/// `--replay-without-force-logs` (it would print a second `no-force` column under
/// another name). A dataset only partly logged is run as asked, with a warning.
fn fit_settings_to_force_logs(
    settings: Vec<Setting>,
    sequences: &[Sequence],
    defaulted: bool,
    replay_anyway: bool,
    dataset: &std::path::Path,
) -> anyhow::Result<Vec<Setting>> {
    let logged = sequences.iter().filter(|q| q.forces_recorded).count();
    let replaying: Vec<&str> = settings
        .iter()
        .filter(|s| s.coefficient != 0.0)
        .map(|s| s.name.as_str())
        .collect();
    if replaying.is_empty() || logged == sequences.len() {
        return Ok(settings);
    }
    if logged == 0 && defaulted {
        eprintln!(
            "note: no sequence evaluated from {} has force logs (imported without --forces): running `no-force` only (--settings force,... with --replay-without-force-logs to replay zeros anyway)",
            dataset.display()
        );
        return Ok(settings
            .into_iter()
            .filter(|s| s.coefficient == 0.0)
            .collect());
    }
    if logged == 0 && !replay_anyway {
        bail!(
            "--settings {}: replays recorded hand forces, but no sequence evaluated from {} has force logs (imported without --forces), so it would run as `no-force` under another name; use no-force or push:<N>, or --replay-without-force-logs to run it anyway",
            replaying.join(","),
            dataset.display()
        );
    }
    if logged < sequences.len() {
        eprintln!(
            "warning: {} of the {} sequences evaluated from {} have no force logs: under {} they replay zero forces",
            sequences.len() - logged,
            sequences.len(),
            dataset.display(),
            replaying.join(", ")
        );
    }
    Ok(settings)
}

/// Most worker threads a run may ask for.
const MAX_WORKERS: usize = 1024;

/// What an evaluation needs before a policy is chosen: robot, profile, data, settings.
pub(super) struct EvalContext {
    pub robot: RobotModel,
    pub profile: Profile,
    pub engine: thorarena::physics::Engine,
    pub dataset: PathBuf,
    pub dataset_sha256: String,
    pub sequences: Vec<Sequence>,
    /// `--tasks`/`--sequences` and the dataset's size, when they chose part of it.
    pub subset: Option<thorarena::motion::Subset>,
    pub settings: Vec<Setting>,
    pub workers: usize,
    pub envs: usize,
    /// The profile contradicts the policy family and `--profile-mismatch-ok` allowed it.
    pub profile_mismatch: bool,
}

impl EvalContext {
    /// [`Self::load_for`] a policy of no family (a built-in, or a policy process).
    pub fn load(args: &RunArgs) -> anyhow::Result<Self> {
        Self::load_for(args, "")
    }

    /// Loads and checks everything the arguments name (before any policy connects, so a
    /// typo fails at once); the profile follows `policy`'s family unless `--profile`
    /// names one.
    pub fn load_for(args: &RunArgs, policy: &str) -> anyhow::Result<Self> {
        let dataset = args
            .dataset
            .clone()
            .unwrap_or_else(|| thorarena::data_dir().join("sample"));
        let robot = super::load_robot(&args.robot)?;
        let profile_name = args
            .profile
            .clone()
            .unwrap_or_else(|| thorarena::profile::family_profile(policy).to_string());
        let profile_path = if profile_name.ends_with(".toml") {
            PathBuf::from(&profile_name)
        } else {
            let path = bundled_profile_path(&profile_name);
            if !path.is_file() {
                let names = bundled_profile_names();
                bail!(
                    "--profile {profile_name}: no such profile{} (bundled: {}; or the path of a .toml file)",
                    super::suggest::did_you_mean(&profile_name, names.iter().map(String::as_str)),
                    names.join(", ")
                );
            }
            path
        };
        let mut profile = load_profile(&profile_path, &robot)?;
        let profile_mismatch = match super::policy_arg::profile_fits(policy, &profile) {
            Ok(()) => false,
            Err(why) if args.profile_mismatch_ok => {
                eprintln!("warning: {why} (--profile-mismatch-ok: run anyway, recorded in run.json)");
                true
            }
            Err(why) => bail!("{why}: leave out --profile to use the family's, or pass --profile-mismatch-ok to run it anyway"),
        };
        if let Some(dt) = args.physics_dt {
            let ratio = profile.control_dt_s / dt;
            if !(dt.is_finite() && dt > 0.0) || (ratio - ratio.round()).abs() > 1e-6 || ratio < 0.5
            {
                bail!(
                    "--physics-dt {dt}: must be > 0 and divide the profile's control step {} s",
                    profile.control_dt_s
                );
            }
            if ratio.round() > MAX_SUBSTEPS as f64 {
                bail!(
                    "--physics-dt {dt}: {} physics steps per control step of {} s; at most {MAX_SUBSTEPS} (a step of {} s)",
                    ratio.round(),
                    profile.control_dt_s,
                    profile.control_dt_s / MAX_SUBSTEPS as f64
                );
            }
            profile.physics_dt_s = dt;
            profile.substeps = ratio.round() as usize;
        }
        let engine = match (args.engine, &args.mjcf) {
            (super::choices::EngineArg::Rapier, None) => thorarena::physics::Engine::Rapier,
            (super::choices::EngineArg::Rapier, Some(_)) => {
                bail!("--mjcf is for --engine mujoco (rapier simulates the robot model itself)")
            }
            (super::choices::EngineArg::Mujoco, mjcf) => {
                thorarena::physics::Engine::mujoco_on(mjcf.clone())?
            }
        };
        // The engine is checked here, once, so that the run's workers cannot fail to make it.
        thorarena::physics::make_physics(
            &engine,
            std::sync::Arc::new(robot.clone()),
            thorarena::physics::PhysicsSettings {
                dt_s: profile.physics_dt_s,
                ..Default::default()
            },
            profile.gains.clone(),
        )?;
        if robot.keypoint_set(&args.keypoints).is_none() {
            bail!(
                "unknown keypoint set `{}` for robot {}",
                args.keypoints,
                robot.name
            );
        }
        let spelled: Vec<String> = if args.settings.is_empty() {
            DEFAULT_SETTINGS.iter().map(|s| s.to_string()).collect()
        } else {
            args.settings.clone()
        };
        let settings: Vec<Setting> = spelled
            .iter()
            .map(|s| {
                Setting::parse(s).with_context(|| {
                    format!(
                        "--settings: `{s}` is not force, no-force, a replay coefficient within ±{} or push:<N>[@<deg>] with |N| ≤ {} and |deg| ≤ 360",
                        Setting::MAX_COEFFICIENT,
                        Setting::MAX_PUSH_N
                    )
                })
            })
            .collect::<anyhow::Result<_>>()?;
        for (i, a) in settings.iter().enumerate() {
            if let Some((j, _)) = settings[..i]
                .iter()
                .enumerate()
                .find(|(_, b)| b.same_load(a))
            {
                let (first, second) = (&spelled[j], &spelled[i]);
                if first == second || settings[j].name == a.name {
                    bail!(
                        "--settings lists `{}` twice: every episode would run and count twice",
                        a.name
                    );
                }
                bail!(
                    "--settings lists `{first}` and `{second}`, which are the same load on the robot: every episode would run and count twice under two names"
                );
            }
        }
        for (flag, v) in [
            ("--max-torso-height-error", args.max_torso_height_error),
            ("--max-torso-tilt-error", args.max_torso_tilt_error),
        ] {
            if !(v.is_finite() && v > 0.0) {
                bail!("{flag} must be > 0, got {v}");
            }
        }
        args.io.rules()?;
        let ds = Dataset::open(&dataset, &robot)?;
        let all = ds.load_all()?;
        if all.is_empty() {
            bail!(
                "{} holds no sequence: nothing to evaluate",
                dataset.display()
            );
        }
        let selection = thorarena::motion::SequenceSelection {
            tasks: args.tasks.clone(),
            sequences: args.sequences.clone(),
        };
        let dataset_sequences = all.len();
        let sequences = selection
            .pick(all, |q| (&q.task, &q.sequence_id))
            .with_context(|| format!("{} in {}", selection.flags(), dataset.display()))?;
        let subset = (!selection.is_all()).then_some(thorarena::motion::Subset {
            selection,
            dataset_sequences,
        });
        let settings = fit_settings_to_force_logs(
            settings,
            &sequences,
            args.settings.is_empty(),
            args.replay_without_force_logs,
            &dataset,
        )?;
        for name in &args.trace {
            if !sequences
                .iter()
                .any(|q| format!("{}/{}", q.task, q.sequence_id) == *name)
            {
                bail!(
                    "--trace: no sequence `{name}` among those evaluated from {} (use TASK/SEQUENCE_ID)",
                    ds.dir.display()
                );
            }
        }
        let workers = match args.workers {
            Some(0) => bail!("--workers must be at least 1"),
            Some(n) if n > MAX_WORKERS => {
                bail!("--workers {n}: at most {MAX_WORKERS} threads (each one simulates its own environment slots)")
            }
            Some(n) => n,
            None => std::thread::available_parallelism().map_or(1, |n| n.get()),
        };
        let envs = args.io.envs(workers)?;
        Ok(Self {
            profile_mismatch,
            dataset_sha256: ds.content_hash(),
            robot,
            profile,
            engine,
            dataset,
            sequences,
            subset,
            settings,
            workers,
            envs,
        })
    }

    /// The dataset directory's name, for default output directories.
    pub fn dataset_name(&self) -> &str {
        self.dataset
            .file_name()
            .and_then(|s| s.to_str())
            .unwrap_or("dataset")
    }
}

pub(super) fn run(args: &Args) -> anyhow::Result<()> {
    let ctx = EvalContext::load_for(&args.run, &args.policy)?;
    // An unusable --out is found before a policy process is made to connect.
    if let Some(out) = &args.out {
        check_out(out, &args.run)?;
    }
    // What the run requires of a policy process's name, asked in its handshake: a free
    // default output directory, and the policy a resumed run was made with.
    let mut vet = |name: &str| -> Result<(), String> {
        let out = match &args.out {
            Some(out) => out.clone(),
            None => {
                let out = PathBuf::from("results").join(format!("{name}-{}", ctx.dataset_name()));
                check_out(&out, &args.run).map_err(|e| format!("{e:#}"))?;
                out
            }
        };
        if args.run.resume && out.join("run.json").exists() {
            let previous = read_header(&out).map_err(|e| format!("{e:#}"))?;
            if previous.policy != name {
                return Err(format!(
                    "--resume: {} is a run of policy `{}`, not `{name}`",
                    out.display(),
                    previous.policy
                ));
            }
        }
        Ok(())
    };
    let mut policy = make_policy_vetted(
        &args.policy,
        &ctx.robot,
        &ctx.profile,
        &args.run.io,
        ctx.envs,
        &mut vet,
    )?;
    let out = match &args.out {
        Some(out) => out.clone(),
        None => {
            thorarena::names::check_name("policy name", policy.name())?;
            let out =
                PathBuf::from("results").join(format!("{}-{}", policy.name(), ctx.dataset_name()));
            check_out(&out, &args.run)?;
            out
        }
    };
    evaluate(&args.run, &ctx, policy.as_mut(), &out, None)
}

/// Refuses to replace a finished or started run unless `--resume` or `--overwrite` says
/// what to do with it, and checks that the directory can be written.
pub(super) fn check_out(out: &std::path::Path, args: &RunArgs) -> anyhow::Result<()> {
    if out.join("run.json").exists() && !args.resume && !args.overwrite {
        bail!(
            "{} already holds a run: pass --resume to continue it, --overwrite to replace it, or choose another --out",
            out.display()
        );
    }
    let existed = out.exists();
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let probe = out.join(format!(".write-test-{}", std::process::id()));
    std::fs::write(&probe, b"").with_context(|| format!("{} is not writable", out.display()))?;
    let _ = std::fs::remove_file(probe);
    // The run makes it again when it starts: a policy that fails to load leaves nothing.
    if !existed {
        let _ = std::fs::remove_dir(out);
    }
    Ok(())
}

/// The most physics steps per control step `--physics-dt` may ask for (0.02 ms at 50 Hz
/// control: far finer than any engine's validated step; 10⁻⁹ s asked for 2·10⁷).
const MAX_SUBSTEPS: usize = 1000;

/// Hands the trace of every episode's first seconds to a caller (`crosscheck`).
pub(super) struct FirstSeconds<'a> {
    /// How many seconds of each episode.
    pub seconds: f64,
    /// Called once per episode run, with its record, those steps and the feet's slip
    /// over the whole episode.
    pub sink: &'a mut dyn FnMut(&EpisodeRecord, &EpisodeTrace),
}

/// Runs the benchmark for one connected policy into `out`.
pub(super) fn evaluate(
    args: &RunArgs,
    ctx: &EvalContext,
    policy: &mut dyn Policy,
    out: &std::path::Path,
    mut first_seconds: Option<FirstSeconds>,
) -> anyhow::Result<()> {
    let sequences = &ctx.sequences;
    let header = RunHeader {
        results_version: RESULTS_VERSION,
        version: env!("CARGO_PKG_VERSION").into(),
        policy: policy.name().to_string(),
        profile: ctx.profile.name.clone(),
        profile_mismatch_ok: ctx.profile_mismatch,
        control_dt_s: ctx.profile.control_dt_s,
        physics_dt_s: ctx.profile.physics_dt_s,
        engine: ctx.engine.clone(),
        dataset: ctx.dataset.display().to_string(),
        dataset_sha256: ctx.dataset_sha256.clone(),
        keypoints: args.keypoints.clone(),
        termination: TerminationRule {
            max_torso_height_error_m: args.max_torso_height_error,
            max_torso_tilt_error_rad: args.max_torso_tilt_error,
        },
        settings: ctx.settings.clone(),
        sequences: PlannedSequence::plan(sequences, ctx.profile.control_dt_s),
        subset: ctx.subset.clone(),
        shard: args.shard,
        io: args.io.rules()?,
    };
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let episodes_path = out.join("episodes.jsonl");

    // Resume: keep what a previous run of the same configuration finished. Episodes cut
    // short by a dead policy process run again.
    let mut done = Vec::new();
    if args.resume && out.join("run.json").exists() {
        let previous = read_header(out)?;
        if previous != header {
            bail!(
                "--resume: {} was started with another configuration (it differs in: {}); use another --out, or --overwrite",
                out.display(),
                previous.differences(&header).join(", ")
            );
        }
        let log = EpisodeLog::read(&episodes_path, &header)?;
        if log.torn_tail {
            eprintln!(
                "--resume: {} ended in a line cut short; it is dropped",
                episodes_path.display()
            );
        }
        done = log
            .records
            .into_iter()
            .filter(|r| r.termination != Some(Termination::PolicyFailed))
            .collect();
        // Rewrite without a torn last line or episodes to run again.
        EpisodeLog::rewrite(&episodes_path, &done)?;
    } else if args.resume {
        eprintln!(
            "--resume: nothing to resume in {}, starting afresh",
            out.display()
        );
    }
    if !args.resume || !out.join("run.json").exists() {
        // A fresh run (also `--resume` with nothing to resume: a first attempt).
        std::fs::File::create(&episodes_path)
            .with_context(|| format!("creating {}", episodes_path.display()))?;
    }
    write_header(out, &header)?;
    let finished: HashSet<(String, String, String)> = done
        .iter()
        .map(|r| (r.task.clone(), r.sequence_id.clone(), r.setting.clone()))
        .collect();
    let jobs: Vec<(usize, usize)> = header
        .planned_jobs()
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

    let plan = EvalPlan {
        robot: &ctx.robot,
        profile: &ctx.profile,
        keypoints: &args.keypoints,
        termination: header.termination,
        settings: header.settings.clone(),
        workers: ctx.workers,
        envs: ctx.envs,
        io: header.io,
        trace: args.trace.clone(),
        trace_first_s: first_seconds.as_ref().map(|f| f.seconds),
        engine: ctx.engine.clone(),
    };
    let traces_dir = out.join("traces");
    if !args.trace.is_empty() {
        std::fs::create_dir_all(&traces_dir)?;
    }
    let part = header
        .subset
        .as_ref()
        .map(|s| format!(" (part of it: {})", s.describe(header.sequences.len())))
        .unwrap_or_default();
    eprintln!(
        "evaluating `{}` on {}{part}: {} episodes to run ({} already done), {} environment slots on {} workers",
        policy.name(),
        ctx.dataset.display(),
        jobs.len(),
        done.len(),
        ctx.envs,
        ctx.workers
    );
    let file = std::fs::OpenOptions::new()
        .append(true)
        .open(&episodes_path)?;
    let mut writer = std::io::BufWriter::new(file);
    let mut write_error: Option<std::io::Error> = None;
    let bar = indicatif::ProgressBar::new(jobs.len() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{bar:40} {pos}/{len} episodes  {elapsed} elapsed, ~{eta} left  {msg}",
        )
        .expect("valid template"),
    );
    let outcome = run_eval(&plan, sequences, &jobs, policy, &mut |r, trace| {
        if let Err(e) = write_record(&mut writer, r) {
            write_error.get_or_insert(e);
        }
        if let (Some(trace), Some(f)) = (trace, first_seconds.as_mut()) {
            (f.sink)(r, trace);
        }
        let traced = args
            .trace
            .contains(&format!("{}/{}", r.task, r.sequence_id));
        if let Some(trace) = trace.filter(|_| traced) {
            let path = traces_dir.join(format!("{}-{}-{}.json", r.task, r.sequence_id, r.setting));
            let written = serde_json::to_vec(&trace.steps)
                .map_err(std::io::Error::other)
                .and_then(|b| std::fs::write(&path, b));
            if let Err(e) = written {
                write_error.get_or_insert(e);
            }
        }
        bar.set_message(format!("{}/{} ({})", r.task, r.sequence_id, r.setting));
        bar.inc(1);
    });
    bar.finish_and_clear();
    writer
        .flush()
        .with_context(|| format!("writing {}", episodes_path.display()))?;
    if let Some(e) = write_error {
        return Err(e).with_context(|| format!("writing {}", episodes_path.display()));
    }
    let not_run = outcome.not_run;
    let io_report = PolicyIoReport {
        latency: outcome.latency,
        transport: outcome.transport,
        deadline_misses: outcome
            .records
            .iter()
            .map(|r| r.faults.deadline_misses)
            .sum(),
        invalid_actions: outcome
            .records
            .iter()
            .map(|r| r.faults.invalid_actions)
            .sum(),
    };
    let mut records = done;
    records.extend(outcome.records);
    sort_records(&mut records, &header);
    let thresholds = task_thresholds(sequences, header.control_dt_s);
    let summary = write_results(out, &header, &records, thresholds, Some(io_report))?;
    let tables = thorarena::report::write_run_tables(out, &summary)?;
    println!("{tables}");
    eprintln!(
        "wrote {}/{{run.json, episodes.jsonl, summary.json, tables.md, episodes.csv}}",
        out.display()
    );
    if !args.trace.is_empty() {
        eprintln!(
            "traces of {} in {}/<task>-<sequence>-<setting>.json: look at one with `thorarena view FILE`",
            args.trace.join(", "),
            traces_dir.display()
        );
    }
    // A run whose policy failed is not a result, even when every episode has a record:
    // the records of episodes it cut short say `policy_failed`, and the exit status must
    // say it too (sweeps and scripts go by it).
    let cut_short = records
        .iter()
        .filter(|r| r.termination == Some(Termination::PolicyFailed))
        .count();
    if not_run > 0 || cut_short > 0 {
        bail!(
            "the policy failed: {cut_short} episodes ended `policy_failed`, {not_run} did not run (finished ones are in {}; `--resume` with a working policy runs both again)",
            out.display()
        );
    }
    Ok(())
}
