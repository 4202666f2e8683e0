//! The arguments that describe one evaluation, shared by `eval`, `serve` and
//! `crosscheck`, and the [`EvalRequest`] they make; and what a command writing one run to
//! `--out` does with it ([`RunOutArgs`]: `eval`, `crosscheck`).

use super::policy_io_args::PolicyIoArgs;
use std::path::PathBuf;
use thorarena::eval::{parse_shard, EvalRequest, TerminationRule};
use thorarena::policy::registry::PolicySource;
use thorarena::sim::motion::SequenceSelection;

/// The flags a request file replaces (clap's ids: the field names).
pub(super) const REQUEST_CONFLICTS: [&str; 24] = [
    "policy",
    "dataset",
    "profile",
    "profile_mismatch_ok",
    "unchecked",
    "settings",
    "replay_without_force_logs",
    "tasks",
    "sequences",
    "keypoints",
    "shard",
    "max_torso_height_error",
    "max_torso_tilt_error",
    "trace",
    "robot",
    "engine",
    "mjcf",
    "physics_dt",
    "envs",
    "pipeline_depth",
    "budget",
    "miss_rule",
    "latency_mode",
    "max_abs_action",
];

/// What an evaluation needs besides the policy and where results go (shared with `serve`).
#[derive(Debug, Clone, clap::Args)]
pub struct RunArgs {
    /// Dataset directory (canonical format), or a bundled dataset by name: `sample`
    /// (synthetic, six tasks), `real-walks` (TWIST2's ten real walks) [default: sample].
    #[arg(long, value_parser = thorarena::sim::motion::dataset_arg)]
    pub dataset: Option<PathBuf>,
    // Its help says how the registry chooses the default.
    #[arg(long, help = thorarena::policy::registry::profile_help())]
    pub profile: Option<String>,
    /// Run a policy under a profile its family was not trained with (recorded in
    /// run.json): a TWIST2 network on the default profile scores 2 instead of 86.
    #[arg(long)]
    pub profile_mismatch_ok: bool,
    /// Score a network policy without its sanity check (recorded in run.json). Without
    /// it, a network run in process is first checked as
    /// `thorarena policy check` does, on the walk of the dataset evaluated (a single-clip
    /// policy: its clip), and refused if it fails.
    #[arg(long)]
    pub unchecked: bool,
    /// Settings, comma separated: `force`, `no-force`, a replay coefficient, or
    /// `push:<N>` (no replay; a constant world +x push of N newtons on each hand, ramped
    /// in over 1 s — the sensitivity probe of SOURCES.md, TWIST2 in MuJoCo), or `push:<N>@<deg>` with the
    /// push turned by deg from the reference's initial heading (`push:20@90`: from the
    /// robot's right), or a disturbance instead of the recorded forces:
    /// `event:<N>[@<deg>][:hand=..][:up=..][:start=..][:ramp=..][:hold=..][:release=..]`
    /// (a ramp–hold–release on one hand or both, SoftMimic's training shape),
    /// `impulse:<N>-<N>[:on=torso|hands][:dur=..][:every=<s>-<s>][:seed=..]` (seeded random
    /// pushes), `payload:<kg>[:hand=..]` (a mass held at the wrists). docs/forces.md has
    /// every field and default.
    /// [default: force,no-force; no-force alone on a dataset without force logs].
    #[arg(long, value_delimiter = ',', value_parser = super::choices::SettingArg)]
    pub settings: Vec<thorarena::eval::Setting>,
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

impl RunArgs {
    /// The evaluation these arguments ask for, with policy `policy` (whose family picks
    /// the profile when none is named), of shard `shard`.
    pub fn request(&self, policy: PolicySource, shard: Option<(usize, usize)>) -> EvalRequest {
        EvalRequest {
            policy,
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
            shard,
        }
    }
}

/// What a command that writes one run to `--out` does with it: continue it, replace it,
/// or run one shard of it (not `serve`, whose every connection writes a new numbered run).
#[derive(Debug, Clone, clap::Args)]
pub struct RunOutArgs {
    /// Continue the run in `--out`: keep its finished episodes, run the rest.
    #[arg(long, conflicts_with = "overwrite")]
    pub resume: bool,
    /// Replace a run already in `--out` (without it, an existing run is refused).
    #[arg(long)]
    pub overwrite: bool,
    /// Run only shard I of N of the schedule (`I/N`, 0-based); merge shards with `thorarena merge`.
    #[arg(long, value_parser = parse_shard)]
    pub shard: Option<(usize, usize)>,
}
