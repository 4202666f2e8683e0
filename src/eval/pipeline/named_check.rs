//! `policy check`'s run: the sanity check (`crate::eval::sanity`) of a policy named as a run
//! names it, under its profile (given, or the one it would run under), on one sequence of
//! a dataset — the one named, else the walk the check picks.

use crate::eval::sanity::{
    check_policy, walking_sequence, SanityError, SanityOptions, SanityReport,
};
use crate::eval::EngineChoice;
use crate::policy::registry::{self, OpenPolicyError, PolicySource, RegistryError};
use crate::sim::motion::{DataError, Dataset};
use crate::sim::physics::{Engine, EngineError};
use std::path::PathBuf;

/// What to check.
#[derive(Debug, Clone)]
pub struct PolicyCheckRequest {
    /// The policy, as a run names it (in process, or `ipc:SESSION`: the check serves the
    /// session and checks the process that joins it).
    pub policy: PolicySource,
    /// Its profile [default: the one a run would choose].
    pub profile: Option<String>,
    /// The dataset [default: the bundled sample].
    pub dataset: Option<PathBuf>,
    /// The sequence tracked [default: the dataset's walk].
    pub sequence: Option<String>,
    /// Seconds tracked.
    pub track_s: f64,
    /// The largest keypoint RMS error that passes, mm.
    pub max_kp_rms_mm: f64,
    /// The robot.
    pub robot: String,
    /// The engine.
    pub engine: EngineChoice,
    /// MuJoCo's model [default: generated from the robot].
    pub mjcf: Option<PathBuf>,
}

/// Why the check could not run (a failed check is a report, not an error).
#[derive(Debug, thiserror::Error)]
pub enum PolicyCheckError {
    /// The policy, robot or profile is not usable.
    #[error(transparent)]
    Registry(#[from] RegistryError),
    /// An engine that cannot run.
    #[error(transparent)]
    Engine(#[from] EngineError),
    /// A model for the wrong engine.
    #[error("`option.mjcf` is for `option.engine` mujoco")]
    MjcfWithoutMujoco,
    /// The dataset could not be read.
    #[error(transparent)]
    Data(#[from] DataError),
    /// The sequence named is not in the dataset.
    #[error("{} has no sequence `{id}`", .dataset.display())]
    NoSuchSequence {
        /// The dataset.
        dataset: PathBuf,
        /// The sequence asked for.
        id: String,
    },
    /// An empty dataset.
    #[error("{} has no sequences", .0.display())]
    NoSequences(PathBuf),
    /// A policy the run starts itself (a command): the check serves a session
    /// (`ipc:SESSION`) for a process started by hand.
    #[error("policy check serves a session for a policy process (`ipc:SESSION`, then start the process); `{0}` is a command a run starts")]
    PolicyProcess(String),
    /// The policy process could not be served, or did not connect.
    #[error(transparent)]
    Open(Box<OpenPolicyError>),
    /// A profile the policy's family contradicts: a run would refuse it, so the check does
    /// not judge the policy under it.
    #[error("`{policy}`: {why}; a run refuses this profile, so the check does not judge the policy under it (leave out `option.profile` for the family's)")]
    ProfileContradicts {
        /// The policy argument.
        policy: String,
        /// Why the family refuses the profile.
        why: String,
    },
    /// The check itself failed to run.
    #[error(transparent)]
    Sanity(#[from] SanityError),
}

/// Runs the check `request` describes, saying what it does as it goes (the check's
/// announcements are logged).
pub fn check_named_policy(request: &PolicyCheckRequest) -> Result<SanityReport, PolicyCheckError> {
    let robot = registry::robot(&request.robot)?;
    let arg = &request.policy;
    let profile_name = request
        .profile
        .clone()
        .unwrap_or_else(|| arg.default_profile().to_string());
    let profile = registry::profile(&profile_name, &robot)?;
    // Judged only as a run would run it: `eval` refuses a profile the family contradicts.
    arg.check_profile(&profile)
        .map_err(|why| PolicyCheckError::ProfileContradicts {
            policy: request.policy.to_string(),
            why,
        })?;
    let engine = match (request.engine, &request.mjcf) {
        (EngineChoice::Rapier, None) => Engine::Rapier,
        (EngineChoice::Rapier, Some(_)) => return Err(PolicyCheckError::MjcfWithoutMujoco),
        (EngineChoice::Mujoco, mjcf) => Engine::mujoco_on(mjcf.clone())?,
    };
    let dataset_dir = request
        .dataset
        .clone()
        .unwrap_or_else(|| crate::data_dir().join("sample"));
    let sequences = Dataset::open(&dataset_dir, &robot)?.load_all()?;
    let index = match &request.sequence {
        Some(id) => sequences
            .iter()
            .position(|s| &s.sequence_id == id)
            .ok_or_else(|| PolicyCheckError::NoSuchSequence {
                dataset: dataset_dir.clone(),
                id: id.clone(),
            })?,
        None => walking_sequence(&sequences, request.track_s)
            .ok_or_else(|| PolicyCheckError::NoSequences(dataset_dir.clone()))?,
    };
    let (mut policy, profile) = if arg.in_process() {
        match registry::open_in_process(arg, &robot, &profile) {
            Ok(policy) => (policy, profile),
            Err(OpenPolicyError::Registry(e)) => return Err(e.into()),
            Err(e) => return Err(PolicyCheckError::Open(Box::new(e))),
        }
    } else {
        open_process(request, &robot, profile)?
    };
    let options = SanityOptions {
        track_s: request.track_s,
        max_kp_rms_mm: request.max_kp_rms_mm,
        engine,
        announce: true,
        ..SanityOptions::default()
    };
    Ok(check_policy(
        &mut *policy,
        &robot,
        &profile,
        &sequences[index],
        &options,
    )?)
}

/// How long `policy check` waits for a policy process to connect to its session.
const PROCESS_CONNECT_TIMEOUT: std::time::Duration = std::time::Duration::from_secs(120);

/// Serves the session of `request.policy` (`ipc:SESSION`) and waits for its process: the
/// policy and the profile it is checked under — the one it declared when no profile is
/// named (as a run takes it), else the one named, which the declaration must not
/// contradict (as a run refuses it).
fn open_process(
    request: &PolicyCheckRequest,
    robot: &crate::sim::robot::RobotModel,
    named: crate::sim::profile::Profile,
) -> Result<(Box<dyn crate::policy::Policy>, crate::sim::profile::Profile), PolicyCheckError> {
    use crate::policy::declared_profile::ProcessProfile;
    let Some(session) = request.policy.session() else {
        return Err(PolicyCheckError::PolicyProcess(request.policy.to_string()));
    };
    let options = crate::policy::SessionOptions {
        connect_timeout: Some(PROCESS_CONNECT_TIMEOUT),
        ..crate::policy::SessionOptions::LAUNCHED
    };
    let target = registry::PolicyTarget {
        robot,
        profile: &named,
        process_profile: match request.profile {
            Some(_) => ProcessProfile::Named { mismatch_ok: false },
            None => ProcessProfile::Declared,
        },
        session: &options,
        envs: 1,
        launch_log: None,
    };
    let policy = registry::serve_session(session, &target, &mut |_| Ok(()), &mut |note| {
        log::info!("{note}")
    })
    .map_err(|e| PolicyCheckError::Open(Box::new(e)))?;
    let profile = match crate::policy::Policy::profile_declaration(&policy) {
        Some(d) if d.adopted => d.declared.clone().unwrap_or(named),
        _ => named,
    };
    Ok((Box::new(policy), profile))
}
