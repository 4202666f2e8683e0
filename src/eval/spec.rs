//! [`EvalSpec`]: one evaluation, validated. It is made from plain values
//! ([`EvalRequest`]: what `eval`'s flags or a sweep cell say) before any policy connects,
//! so a typo fails at once, and everything downstream — the run's header, the runner, a
//! sweep's validation of its cells — reads this one shape.

use super::{EngineChoice, EvalRequest, PolicyIoRules, Setting, TerminationRule};
use crate::policy::declared_profile::{ProcessProfile, ProfileDeclaration};
use crate::policy::registry::{self, PolicySource, RegistryError};
use crate::sim::motion::{DataError, Dataset, SelectionError, Sequence, Subset};
use crate::sim::physics::{make_physics, Engine, EngineError, PhysicsSettings};
use crate::sim::profile::Profile;
use crate::sim::robot::RobotModel;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Most worker threads a run may ask for.
pub const MAX_WORKERS: usize = 1024;
/// Most environment slots a run may ask for.
pub const MAX_ENVS: usize = 4096;
/// The deepest slot pipeline: two groups, one stepping while the policy answers the other.
pub const MAX_PIPELINE_DEPTH: usize = 2;
/// The most physics steps per control step a physics step may ask for (0.02 ms at 50 Hz
/// control: far finer than any engine's validated step; 10⁻⁹ s asked for 2·10⁷).
pub const MAX_SUBSTEPS: usize = 1000;
/// Settings when none is given (on a dataset with force logs).
pub const DEFAULT_SETTINGS: [&str; 2] = ["force", "no-force"];

/// Something the caller should tell the user about a valid spec.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Advice {
    /// What the run does that was not asked for in so many words.
    Note(String),
    /// What may not be what the user meant.
    Warning(String),
}

impl std::fmt::Display for Advice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Note(s) => write!(f, "note: {s}"),
            Self::Warning(s) => write!(f, "warning: {s}"),
        }
    }
}

/// Why a request is not an evaluation that can run.
#[derive(Debug, thiserror::Error)]
pub enum SpecError {
    /// A value out of its domain; the message names the request's field in backticks
    /// (`request.envs`, `request.io.budget_s`) — a command line shows its flag there.
    #[error("{0}")]
    Invalid(String),
    /// The robot or profile named does not resolve.
    #[error(transparent)]
    Registry(#[from] RegistryError),
    /// The engine cannot simulate the robot.
    #[error(transparent)]
    Engine(#[from] EngineError),
    /// The dataset cannot be read.
    #[error(transparent)]
    Data(#[from] DataError),
    /// `selection` chooses nothing usable.
    #[error("{spelled} in {dataset}")]
    Selection {
        /// The selection as given.
        spelled: String,
        /// The dataset.
        dataset: PathBuf,
        /// Why.
        source: SelectionError,
    },
}

fn invalid(message: impl Into<String>) -> SpecError {
    SpecError::Invalid(message.into())
}

/// One evaluation, checked: robot, profile, engine, the sequences and settings, the
/// rules, and how it is spread over threads.
#[derive(Debug, Clone)]
pub struct EvalSpec {
    /// Where the policy comes from (`None`: a policy the registry does not know — a deployment
    /// over DDS names its run so — which runs on the `default` profile, one slot per
    /// worker).
    pub policy: Option<PolicySource>,
    /// The robot.
    pub robot: RobotModel,
    /// The dynamics profile (with the physics step asked for).
    pub profile: Profile,
    /// The profile contradicts the policy family (or the profile a policy process
    /// declared) and the request allowed it.
    pub profile_mismatch: bool,
    /// How the run takes the profile a policy process declares: the request's
    /// (`Named`), or, when it names none for a process, the process's (`Declared`:
    /// `profile` is then a placeholder until [`Self::adopting`]).
    pub process_profile: ProcessProfile,
    /// The physics step the request asked for, s, which a declared profile takes too.
    pub physics_dt_asked_s: Option<f64>,
    /// The name of the profile the policy process declared, when it declared one.
    pub declared_profile: Option<String>,
    /// The policy is scored without its sanity check (`--unchecked`).
    pub unchecked: bool,
    /// The engine (checked: it makes a physics for the robot).
    pub engine: Engine,
    /// Dataset directory.
    pub dataset: PathBuf,
    /// Its content hash.
    pub dataset_sha256: String,
    /// The sequences evaluated, in dataset order.
    pub sequences: Vec<Sequence>,
    /// The selection and the dataset's size, when they chose part of it.
    pub subset: Option<Subset>,
    /// Settings, in the order asked.
    pub settings: Vec<Setting>,
    /// Keypoint set (exists for the robot).
    pub keypoints: String,
    /// When an episode has failed.
    pub termination: TerminationRule,
    /// The rules of the policy's answers.
    pub io: PolicyIoRules,
    /// Only shard i of n.
    pub shard: Option<(usize, usize)>,
    /// Sequences (`TASK/SEQUENCE_ID`, each evaluated) whose rollouts are written as traces.
    pub trace: Vec<String>,
    /// Worker threads.
    pub workers: usize,
    /// Environment slots.
    pub envs: usize,
    /// Slot groups in the pipeline (checked: 1, or 2 under lock-step rules with at least
    /// two slots).
    pub pipeline_depth: usize,
    /// What the caller should tell the user.
    pub advice: Vec<Advice>,
}

impl EvalSpec {
    /// Checks `request` and loads everything it names (its policy was parsed where the
    /// request was made): robot, profile (the
    /// policy family's unless named), engine (a physics is made once, so the run's workers
    /// cannot fail to), dataset and selection, settings, rules, threads.
    pub fn load(request: &EvalRequest) -> Result<Self, SpecError> {
        Self::load_with(request, Some(request.policy.clone()))
    }

    /// [`Self::load`] for a run whose policy the registry does not know — deployment code
    /// driving the robot over DDS, which names its run itself — on the `default` profile
    /// unless one is named, one slot per worker; `request.policy` is not read.
    pub fn load_deployment(request: &EvalRequest) -> Result<Self, SpecError> {
        Self::load_with(request, None)
    }

    fn load_with(request: &EvalRequest, policy: Option<PolicySource>) -> Result<Self, SpecError> {
        let mut advice = Vec::new();
        let dataset = request
            .dataset
            .clone()
            .unwrap_or_else(|| crate::data_dir().join("sample"));
        let robot = registry::robot(&request.robot)?;
        let (profile, profile_mismatch) =
            resolve_profile(request, policy.as_ref(), &robot, &mut advice)?;
        let engine = check_engine(request, &robot, &profile)?;
        let process_profile = match &policy {
            Some(source) if !source.in_process() && request.profile.is_none() => {
                ProcessProfile::Declared
            }
            _ => ProcessProfile::Named {
                mismatch_ok: request.profile_mismatch_ok,
            },
        };
        if robot.keypoint_set(&request.keypoints).is_none() {
            return Err(invalid(format!(
                "unknown keypoint set `{}` for robot {}",
                request.keypoints, robot.name
            )));
        }
        let settings = check_settings(&request.settings)?;
        check_termination(&request.termination)?;
        let in_process = policy
            .as_ref()
            .filter(|source| source.in_process())
            .map(PolicySource::to_string);
        check_io(&request.io, in_process.as_deref())?;
        check_shard(request.shard)?;
        let picked = pick_sequences(request, &dataset, &robot)?;
        let settings = fit_settings_to_force_logs(
            settings,
            &picked.sequences,
            request.settings.is_empty(),
            request.replay_without_force_logs,
            &dataset,
            &mut advice,
        )?;
        check_trace(&request.trace, &picked.sequences, &dataset)?;
        let slots_per_worker = policy.as_ref().map_or(1, PolicySource::slots_per_worker);
        let (workers, envs) = threads(request, slots_per_worker)?;
        check_pipeline(request.pipeline_depth, envs, &request.io)?;
        Ok(Self {
            policy,
            profile_mismatch,
            process_profile,
            physics_dt_asked_s: request.physics_dt_s,
            declared_profile: None,
            unchecked: request.unchecked,
            dataset_sha256: picked.sha256,
            robot,
            profile,
            engine,
            dataset,
            sequences: picked.sequences,
            subset: picked.subset,
            settings,
            keypoints: request.keypoints.clone(),
            termination: request.termination,
            io: request.io,
            shard: request.shard,
            trace: request.trace.clone(),
            workers,
            envs,
            pipeline_depth: request.pipeline_depth,
            advice,
        })
    }

    /// This evaluation as the connected policy process's declaration makes it: under the
    /// profile it declared when the run takes it (with the physics step the request asked
    /// for), marked as a mismatch when it ran anyway against the run's. A run that takes
    /// its profile from the process and got no declaration is refused: its profile was
    /// never said.
    pub fn adopting(&self, declaration: Option<&ProfileDeclaration>) -> Result<Self, SpecError> {
        let mut spec = self.clone();
        let Some(declaration) = declaration else {
            if self.process_profile == ProcessProfile::Declared {
                return Err(invalid(
                    "the policy process declared no profile and `request.profile` names none",
                ));
            }
            return Ok(spec);
        };
        spec.profile_mismatch |= declaration.mismatch;
        spec.declared_profile = declaration.declared.as_ref().map(|p| p.name.clone());
        if let Some(declared) = declaration
            .declared
            .as_ref()
            .filter(|_| declaration.adopted)
        {
            let mut profile = declared.clone();
            if let Some(dt) = self.physics_dt_asked_s {
                set_physics_dt(&mut profile, dt)?;
            }
            check_physics(&spec.engine, &spec.robot, &profile)?;
            spec.profile = profile;
        } else if self.process_profile == ProcessProfile::Declared {
            return Err(invalid(
                "the policy process's profile was not taken though `request.profile` names none",
            ));
        }
        spec.process_profile = ProcessProfile::Named {
            mismatch_ok: declaration.mismatch,
        };
        Ok(spec)
    }

    /// The dataset directory's name, for default output directories.
    pub fn dataset_name(&self) -> &str {
        self.dataset
            .file_name()
            .and_then(|s| s.to_str())
            .unwrap_or("dataset")
    }

    /// Whether the sequence of `task`/`sequence_id` is one whose rollouts are traced.
    pub fn traces(&self, task: &str, sequence_id: &str) -> bool {
        self.trace
            .iter()
            .any(|t| names_sequence(t, task, sequence_id))
    }
}

/// Whether `name`, spelled `TASK/SEQUENCE_ID`, is that sequence.
fn names_sequence(name: &str, task: &str, sequence_id: &str) -> bool {
    name.split_once('/') == Some((task, sequence_id))
}

/// The profile the request names, or its policy family's; one that contradicts the
/// family is refused unless the request allows it (then a warning, and recorded), and the
/// physics step is the request's when it gives one. Also returns the mismatch.
fn resolve_profile(
    request: &EvalRequest,
    policy: Option<&PolicySource>,
    robot: &RobotModel,
    advice: &mut Vec<Advice>,
) -> Result<(Profile, bool), SpecError> {
    let profile_name = request.profile.clone().unwrap_or_else(|| {
        policy
            .map_or("default", PolicySource::default_profile)
            .to_string()
    });
    let mut profile = registry::profile(&profile_name, robot).map_err(|e| match e {
        RegistryError::UnknownProfile { .. } => {
            invalid(format!("`request.profile` {profile_name}: {e}"))
        }
        e => e.into(),
    })?;
    let fits = policy.map_or(Ok(()), |p| p.check_profile(&profile));
    let mismatch = match fits {
        Ok(()) => false,
        Err(why) if request.profile_mismatch_ok => {
            advice.push(Advice::Warning(format!(
                "{why} (`request.profile_mismatch_ok`: run anyway, recorded in run.json)"
            )));
            true
        }
        Err(why) => return Err(invalid(format!("{why}: leave out `request.profile` to use the family's, or give `request.profile_mismatch_ok` to run it anyway"))),
    };
    if let Some(dt) = request.physics_dt_s {
        set_physics_dt(&mut profile, dt)?;
    }
    Ok((profile, mismatch))
}

/// The engine asked for, checked once by making a physics of it for the robot, so that
/// the run's workers cannot fail to.
fn check_engine(
    request: &EvalRequest,
    robot: &RobotModel,
    profile: &Profile,
) -> Result<Engine, SpecError> {
    let engine = match (request.engine, &request.mjcf) {
        (EngineChoice::Rapier, None) => Engine::Rapier,
        (EngineChoice::Rapier, Some(_)) => {
            return Err(invalid(
                "`request.mjcf` is for `request.engine` mujoco (rapier simulates the robot model itself)",
            ))
        }
        (EngineChoice::Mujoco, mjcf) => Engine::mujoco_on(mjcf.clone())?,
    };
    check_physics(&engine, robot, profile)?;
    Ok(engine)
}

/// Makes a physics of `engine` for `robot` under `profile` once, so that the run's
/// workers cannot fail to.
fn check_physics(engine: &Engine, robot: &RobotModel, profile: &Profile) -> Result<(), SpecError> {
    make_physics(
        engine,
        Arc::new(robot.clone()),
        PhysicsSettings {
            dt_s: profile.physics_dt_s,
            ..Default::default()
        },
        profile.gains.clone(),
    )?;
    Ok(())
}

/// The sequences a request evaluates, with the dataset's hash and the subset they are.
struct Picked {
    sequences: Vec<Sequence>,
    subset: Option<Subset>,
    sha256: String,
}

/// Opens the dataset (every file checked against its manifest) and keeps the sequences
/// of the request's selection; an empty dataset is refused.
fn pick_sequences(
    request: &EvalRequest,
    dataset: &Path,
    robot: &RobotModel,
) -> Result<Picked, SpecError> {
    let ds = Dataset::open(dataset, robot)?;
    let all = ds.load_all()?;
    if all.is_empty() {
        return Err(invalid(format!(
            "{} holds no sequence: nothing to evaluate",
            dataset.display()
        )));
    }
    let selection = request.selection.clone();
    let dataset_sequences = all.len();
    let sequences = selection
        .pick(all, |q| (&q.task, &q.sequence_id))
        .map_err(|source| SpecError::Selection {
            spelled: selection.spelled(),
            dataset: dataset.to_path_buf(),
            source,
        })?;
    Ok(Picked {
        sequences,
        subset: (!selection.is_all()).then_some(Subset {
            selection,
            dataset_sequences,
        }),
        sha256: ds.content_hash(),
    })
}

/// Every traced sequence (`TASK/SEQUENCE_ID`) must be one of those evaluated.
fn check_trace(trace: &[String], sequences: &[Sequence], dataset: &Path) -> Result<(), SpecError> {
    for name in trace {
        if !sequences
            .iter()
            .any(|q| names_sequence(name, &q.task, &q.sequence_id))
        {
            return Err(invalid(format!(
                "`request.trace`: no sequence `{name}` among those evaluated from {} (use TASK/SEQUENCE_ID)",
                dataset.display()
            )));
        }
    }
    Ok(())
}

/// Worker threads (default: every core) and environment slots (default: the policy
/// family's `slots_per_worker` for each worker), within their limits.
fn threads(request: &EvalRequest, slots_per_worker: usize) -> Result<(usize, usize), SpecError> {
    let workers = match request.workers {
        Some(0) => return Err(invalid("`request.workers` must be at least 1")),
        Some(n) if n > MAX_WORKERS => {
            return Err(invalid(format!("`request.workers` {n}: at most {MAX_WORKERS} threads (each one simulates its own environment slots)")))
        }
        Some(n) => n,
        None => std::thread::available_parallelism().map_or(1, |n| n.get()),
    };
    let envs = match request.envs {
        Some(0) => return Err(invalid("`request.envs` must be at least 1")),
        Some(n) if n > MAX_ENVS => {
            return Err(invalid(format!(
                "`request.envs` {n}: at most {MAX_ENVS} environment slots (each holds a robot's physics)"
            )))
        }
        Some(n) => n,
        None => (workers.max(1) * slots_per_worker).min(MAX_ENVS),
    };
    Ok((workers, envs))
}

/// A pipeline of `depth` slot groups over `envs` slots: deeper than one, the policy's
/// answer overlaps the physics of the other group, so it shares the cores with it and its
/// measured latency is no longer the one it would have alone — a budget or measured latency
/// would then judge the run's timing, not the policy's, and are refused.
fn check_pipeline(depth: usize, envs: usize, io: &PolicyIoRules) -> Result<(), SpecError> {
    if !(1..=MAX_PIPELINE_DEPTH).contains(&depth) {
        return Err(invalid(format!(
            "`request.pipeline_depth` {depth}: 1 (lock-step) or {MAX_PIPELINE_DEPTH} (the physics of one half of the slots overlaps the policy's answer for the other)"
        )));
    }
    if depth == 1 {
        return Ok(());
    }
    if envs < depth {
        return Err(invalid(format!(
            "`request.pipeline_depth` {depth} needs at least {depth} environment slots (`request.envs` {envs})"
        )));
    }
    if let Some(b) = io.budget_s {
        return Err(invalid(format!(
            "`request.pipeline_depth` {depth} with `request.io.budget_s` {b}s: overlapped with physics, the policy's round trip is not what it would be alone, so a deadline would judge the run, not the policy (use `request.pipeline_depth` 1)"
        )));
    }
    if io.latency_mode == crate::eval::LatencyMode::Measured {
        return Err(invalid(format!(
            "`request.pipeline_depth` {depth} with `request.io.latency_mode` measured: overlapped with physics, the measured latency is not the policy's alone (use `request.pipeline_depth` 1)"
        )));
    }
    Ok(())
}

/// Sets the profile's physics step to `dt` s, which must divide its control step.
fn set_physics_dt(profile: &mut Profile, dt: f64) -> Result<(), SpecError> {
    let ratio = profile.control_dt_s / dt;
    if !(dt.is_finite() && dt > 0.0) || (ratio - ratio.round()).abs() > 1e-6 || ratio < 0.5 {
        return Err(invalid(format!(
            "`request.physics_dt_s` {dt}: must be > 0 and divide the profile's control step {} s",
            profile.control_dt_s
        )));
    }
    if ratio.round() > MAX_SUBSTEPS as f64 {
        return Err(invalid(format!(
            "`request.physics_dt_s` {dt}: {} physics steps per control step of {} s; at most {MAX_SUBSTEPS} (a step of {} s)",
            ratio.round(),
            profile.control_dt_s,
            profile.control_dt_s / MAX_SUBSTEPS as f64
        )));
    }
    profile.physics_dt_s = dt;
    profile.substeps = ratio.round() as usize;
    Ok(())
}

/// The settings asked for (none: [`DEFAULT_SETTINGS`]), refusing two that load the robot
/// the same way: every episode would run and count twice.
pub fn check_settings(asked: &[Setting]) -> Result<Vec<Setting>, SpecError> {
    let settings: Vec<Setting> = if asked.is_empty() {
        vec![Setting::force(), Setting::no_force()]
    } else {
        asked.to_vec()
    };
    for (i, a) in settings.iter().enumerate() {
        if let Some(b) = settings[..i].iter().find(|b| b.same_load(a)) {
            if b.name == a.name {
                return Err(invalid(format!(
                    "`request.settings` lists `{}` twice: every episode would run and count twice",
                    a.name
                )));
            }
            return Err(invalid(format!(
                "`request.settings` lists `{}` and `{}`, which are the same load on the robot: every episode would run and count twice under two names",
                b.spelling(),
                a.spelling()
            )));
        }
    }
    Ok(settings)
}

/// The largest termination bound taken: 100 (m, rad) already never ends an episode, as
/// docs/deployment.md disables termination; past 1000 the number is a slip of the
/// exponent (`1e300`), refused rather than printed in every table's header.
const MAX_TERMINATION_BOUND: f64 = 1000.0;

/// Termination bounds: finite, above 0, at most [`MAX_TERMINATION_BOUND`].
fn check_termination(rule: &TerminationRule) -> Result<(), SpecError> {
    for (flag, v, max, unit) in [
        (
            "`request.termination.max_torso_height_error_m`",
            rule.max_torso_height_error_m,
            MAX_TERMINATION_BOUND,
            "m",
        ),
        (
            "`request.termination.max_torso_tilt_error_rad`",
            rule.max_torso_tilt_error_rad,
            MAX_TERMINATION_BOUND,
            "rad (100 already never ends an episode)",
        ),
    ] {
        if !(v.is_finite() && v > 0.0 && v <= max) {
            return Err(invalid(format!(
                "{flag} must be > 0 and at most {} {unit}, got {}",
                crate::files::log_text::short_number(max),
                crate::files::log_text::short_number(v)
            )));
        }
    }
    Ok(())
}

/// The policy's I/O rules: an action bound > 0, a budget within [`crate::eval::MIN_BUDGET`]
/// and [`crate::eval::MAX_BUDGET`] — and a budget or measured latency only for a policy
/// process (`in_process`: the policy runs in this process, where a call's time is not a
/// round trip and no deadline is applied, so the setting would be recorded and printed
/// but never honoured).
fn check_io(io: &PolicyIoRules, in_process: Option<&str>) -> Result<(), SpecError> {
    if !(io.max_abs_action.is_finite() && io.max_abs_action > 0.0) {
        return Err(invalid(format!(
            "`request.io.max_abs_action` must be > 0, got {}",
            crate::eval::short_number(io.max_abs_action)
        )));
    }
    if let Some(b) = io.budget_s {
        crate::eval::check_budget_s(b)
            .map_err(|why| invalid(format!("`request.io.budget_s`: {why}")))?;
    }
    if let Some(policy) = in_process {
        if io.budget_s.is_some() {
            return Err(invalid(format!(
                "`request.io.budget_s`: `{policy}` runs inside this process, where no deadline applies; a latency budget is for a policy process (`ipc:SESSION`)"
            )));
        }
        if io.latency_mode == crate::eval::LatencyMode::Measured {
            return Err(invalid(format!(
                "`request.io.latency_mode` measured: `{policy}` runs inside this process, whose call time is not a policy's round trip; measured latency is for a policy process (`ipc:SESSION`)"
            )));
        }
    }
    Ok(())
}

/// `request.shard` `(i, n)`: `0 <= i < n`, as `--shard` checks it.
fn check_shard(shard: Option<(usize, usize)>) -> Result<(), SpecError> {
    match shard {
        Some((i, n)) => super::request::check_shard(i, n)
            .map_err(|why| invalid(format!("`request.shard`: {why}"))),
        None => Ok(()),
    }
}

/// Replay settings need recorded forces: on a dataset without force logs the default
/// becomes `no-force` alone, and an explicit replay setting is refused unless
/// `replay_anyway` (it would print a second `no-force` column under another name). A
/// dataset only partly logged is run as asked, with a warning.
fn fit_settings_to_force_logs(
    settings: Vec<Setting>,
    sequences: &[Sequence],
    defaulted: bool,
    replay_anyway: bool,
    dataset: &std::path::Path,
    advice: &mut Vec<Advice>,
) -> Result<Vec<Setting>, SpecError> {
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
        advice.push(Advice::Note(format!(
            "no sequence evaluated from {} has force logs (imported without its forces): running `no-force` only (`request.settings` force,... with `request.replay_without_force_logs` to replay zeros anyway)",
            dataset.display()
        )));
        return Ok(settings
            .into_iter()
            .filter(|s| s.coefficient == 0.0)
            .collect());
    }
    if logged == 0 && !replay_anyway {
        return Err(invalid(format!(
            "`request.settings` {}: replays recorded hand forces, but no sequence evaluated from {} has force logs (imported without its forces), so it would run as `no-force` under another name; use no-force or push:<N>, or `request.replay_without_force_logs` to run it anyway",
            replaying.join(","),
            dataset.display()
        )));
    }
    if logged < sequences.len() {
        advice.push(Advice::Warning(format!(
            "{} of the {} sequences evaluated from {} have no force logs: under {} they replay zero forces",
            sequences.len() - logged,
            sequences.len(),
            dataset.display(),
            replaying.join(", ")
        )));
    }
    Ok(settings)
}
