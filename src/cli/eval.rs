//! `thorarena eval`: the benchmark — every sequence of a dataset with and without force,
//! scored with FATS and the diagnostics; results streamed to a run directory that can be
//! resumed after a crash, or sharded across machines and merged.

use super::policy_arg::{make_policy_vetted, PolicyIoArgs};
use anyhow::bail;
use std::path::{Path, PathBuf};
use thorarena::evaluation::{EvalRequest, EvalSpec, TerminationRule};
use thorarena::motion::SequenceSelection;
use thorarena::results::RunDir;

/// Arguments of `eval`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Built-in policy: `balance` (reference PD + tilt feedback), `replay` (reference
    /// joints, open loop) or `hold` (default pose); `twist2:<file.onnx>` for the TWIST2
    /// network in process (with `--profile twist2`); `beyondmimic:<file.onnx>` for a
    /// BeyondMimic-style tracking network (mjlab, whole_body_tracking, holosoma; e.g. with
    /// `--profile holosoma-wbt`); `wbc-mjlab:<file.onnx>` for wbc-mjlab's general tracker;
    /// or `ipc:<session>` to serve a session
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
    /// beyondmimic:, `wbc-mjlab` for wbc-mjlab:, else `default`; `thorarena policies`
    /// lists them]. One that contradicts the family is an error.
    #[arg(long)]
    pub profile: Option<String>,
    /// Run a policy under a profile its family was not trained with (recorded in
    /// run.json): a TWIST2 network on the default profile scores 2 instead of 86.
    #[arg(long)]
    pub profile_mismatch_ok: bool,
    /// Score a network policy without its sanity check (recorded in run.json). Without
    /// it, a policy run in process (twist2:, beyondmimic:, wbc-mjlab:) is first checked as
    /// `thorarena policy check` does, on the walk of the dataset evaluated (a single-clip
    /// policy: its clip), and refused if it fails.
    #[arg(long)]
    pub unchecked: bool,
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

impl RunArgs {
    /// The evaluation these arguments ask for, with policy argument `policy` (whose
    /// family picks the profile when none is named).
    pub fn request(&self, policy: &str) -> EvalRequest {
        EvalRequest {
            policy: policy.to_string(),
            dataset: self.dataset.clone(),
            robot: self.robot.clone(),
            profile: self.profile.clone(),
            profile_mismatch_ok: self.profile_mismatch_ok,
            unchecked: self.unchecked,
            settings: self.settings.clone(),
            replay_without_force_logs: self.replay_without_force_logs,
            selection: SequenceSelection {
                tasks: self.tasks.clone(),
                sequences: self.sequences.clone(),
            },
            workers: self.workers,
            envs: self.io.envs,
            pipeline_depth: self.io.pipeline_depth,
            keypoints: self.keypoints.clone(),
            termination: TerminationRule {
                max_torso_height_error_m: self.max_torso_height_error,
                max_torso_tilt_error_rad: self.max_torso_tilt_error,
            },
            trace: self.trace.clone(),
            engine: self.engine.into(),
            mjcf: self.mjcf.clone(),
            physics_dt_s: self.physics_dt,
            io: self.io.rules(),
            shard: self.shard,
        }
    }
}

/// The checked evaluation `args` ask for with `policy`; its advice is printed.
pub(super) fn load_spec(args: &RunArgs, policy: &str) -> anyhow::Result<EvalSpec> {
    let spec = EvalSpec::load(&args.request(policy))?;
    for advice in &spec.advice {
        eprintln!("{advice}");
    }
    Ok(spec)
}

pub(super) fn run(args: &Args) -> anyhow::Result<()> {
    let spec = load_spec(&args.run, &args.policy)?;
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
                let out = default_out(name, &spec);
                check_out(&out, &args.run).map_err(|e| format!("{e:#}"))?;
                out
            }
        };
        let run = RunDir::new(out);
        if args.run.resume && run.holds_run() {
            let previous = run.read_header().map_err(|e| e.to_string())?;
            if previous.policy != name {
                return Err(format!(
                    "--resume: {} is a run of policy `{}`, not `{name}`",
                    run.path().display(),
                    previous.policy
                ));
            }
        }
        Ok(())
    };
    let mut policy = make_policy_vetted(
        &args.policy,
        &spec.robot,
        &spec.profile,
        &args.run.io,
        spec.envs,
        &mut vet,
    )?;
    let out = match &args.out {
        Some(out) => out.clone(),
        None => {
            thorarena::names::check_name("policy name", policy.name())?;
            let out = default_out(policy.name(), &spec);
            check_out(&out, &args.run)?;
            out
        }
    };
    super::eval_run::evaluate(&args.run, &spec, policy.as_mut(), &out, None)
}

/// `results/<policy>-<dataset name>`.
fn default_out(policy: &str, spec: &EvalSpec) -> PathBuf {
    PathBuf::from("results").join(format!("{policy}-{}", spec.dataset_name()))
}

/// Refuses to replace a finished or started run unless `--resume` or `--overwrite` says
/// what to do with it, and checks that the directory can be written.
pub(super) fn check_out(out: &Path, args: &RunArgs) -> anyhow::Result<()> {
    thorarena::results::check_run_dir(out, true, args.dataset.as_deref())?;
    let run = RunDir::new(out);
    if run.holds_run() && !args.resume && !args.overwrite {
        bail!(
            "{} already holds a run: pass --resume to continue it, --overwrite to replace it, or choose another --out",
            out.display()
        );
    }
    // The run makes it again when it starts: a policy that fails to load leaves nothing.
    run.check_writable()?;
    Ok(())
}
