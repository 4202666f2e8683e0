//! The one door through which a run gets its policy: a [`PolicySource`] made into a policy
//! it can step — built in process, served on its session and waited for until a policy
//! process connects (`ipc:NAME`), or started as a command and then served. `eval` (and so
//! every sweep task), `serve`, the leaderboard and `bench eval` open theirs with
//! [`open_policy`]; the callers that step a policy only in process (`crosscheck`, `policy
//! check`) with [`open_in_process`].

use super::{PolicyChoice, PolicySource, RegistryError};
use crate::policy::launched::{LaunchTarget, LaunchedPolicy, PolicyCommand};
use crate::policy::{Policy, RemoteError, RemotePolicy, SessionOptions};
use crate::sim::profile::Profile;
use crate::sim::robot::RobotModel;
use std::path::Path;

/// Why a policy could not be made.
#[derive(Debug, thiserror::Error)]
pub enum OpenPolicyError {
    /// The argument names no usable policy, or its network could not be built.
    #[error(transparent)]
    Registry(#[from] RegistryError),
    /// The session could not be served, or no policy process connected.
    #[error("serving session `{session}`")]
    Serve {
        /// The session's name.
        session: String,
        /// Why.
        #[source]
        source: RemoteError,
    },
    /// A launched command could not be started, or did not connect.
    #[error("{command}: {why}")]
    Launch {
        /// The command.
        command: String,
        /// Why (quoting the end of its output).
        why: String,
    },
    /// A launched command with nowhere to write its output.
    #[error("{0} is started by the run, which needs a place for its output: run it with a run directory (`option.out`)")]
    LaunchWithoutLog(String),
    /// A policy that is not stepped in this process, where the caller needs one.
    #[error("`{0}` runs in its own process; this command steps a policy in process (a built-in or a network file, e.g. beyondmimic:FILE)")]
    NotInProcess(String),
}

/// What a run needs to reach its policy: the robot and profile it runs under, how a
/// policy process is served, and how many environment slots each batch holds.
pub struct PolicyTarget<'a> {
    /// The robot simulated.
    pub robot: &'a RobotModel,
    /// The dynamics profile (default pose, action mapping, control period).
    pub profile: &'a Profile,
    /// How the run takes the profile a policy process declares (ignored in process).
    pub process_profile: crate::policy::declared_profile::ProcessProfile,
    /// How a policy process is served (ignored in process).
    pub session: &'a SessionOptions,
    /// Environment slots per batch.
    pub envs: usize,
    /// Where a launched command's output goes (`None`: a launched command is refused).
    pub launch_log: Option<&'a Path>,
}

/// The policy `source` names, made for `target`; a policy process (`ipc:`) must also pass
/// `vet` in its handshake — what the run requires of it, told to it when it fails — and
/// the session's news (serving, connected, a command started) goes to `note`.
pub fn open_policy(
    source: &PolicySource,
    target: &PolicyTarget,
    vet: &mut dyn FnMut(&str) -> Result<(), String>,
    note: &mut dyn FnMut(&str),
) -> Result<Box<dyn Policy>, OpenPolicyError> {
    match source.load(target.robot, target.profile)? {
        PolicyChoice::InProcess(policy) => Ok(policy),
        PolicyChoice::Session(session) => Ok(Box::new(serve_session(session, target, vet, note)?)),
        PolicyChoice::Launched(command) => Ok(Box::new(launch(command, target, note)?)),
    }
}

/// The policy `source` names, built in this process for `robot` under `profile`; a policy
/// process is refused ([`OpenPolicyError::NotInProcess`]).
pub fn open_in_process(
    source: &PolicySource,
    robot: &RobotModel,
    profile: &Profile,
) -> Result<Box<dyn Policy>, OpenPolicyError> {
    match source.load(robot, profile)? {
        PolicyChoice::InProcess(policy) => Ok(policy),
        PolicyChoice::Session(_) | PolicyChoice::Launched(_) => {
            Err(OpenPolicyError::NotInProcess(source.to_string()))
        }
    }
}

/// Starts `command` on a session of its own — short whatever the command (a session name
/// has at most 64 characters), unique per log and per process — its output in
/// `target.launch_log`, and waits for it to connect.
pub fn launch(
    command: &PolicyCommand,
    target: &PolicyTarget,
    note: &mut dyn FnMut(&str),
) -> Result<LaunchedPolicy, OpenPolicyError> {
    let log = target
        .launch_log
        .ok_or_else(|| OpenPolicyError::LaunchWithoutLog(command.to_string()))?;
    let session = format!(
        "launched-{}-{}",
        &crate::files::content_hash::sha256_hex(log.to_string_lossy().as_bytes())[..8],
        std::process::id()
    );
    note(&format!(
        "  starting {command} (its output: {})",
        log.display()
    ));
    let launch_target = LaunchTarget {
        robot: target.robot,
        profile: target.profile,
        process_profile: target.process_profile,
        session: target.session,
        envs: target.envs,
    };
    LaunchedPolicy::start(command, &session, &launch_target, log, note).map_err(|why| {
        OpenPolicyError::Launch {
            command: command.to_string(),
            why,
        }
    })
}

/// Serves `session` for `target` and waits for a policy process that passes `vet`.
pub fn serve_session(
    session: &str,
    target: &PolicyTarget,
    vet: &mut dyn FnMut(&str) -> Result<(), String>,
    note: &mut dyn FnMut(&str),
) -> Result<RemotePolicy, OpenPolicyError> {
    RemotePolicy::serve(
        session,
        target.robot,
        target.profile,
        target.process_profile,
        target.session,
        target.envs,
        vet,
        note,
        &mut || false,
    )
    .map_err(|source| OpenPolicyError::Serve {
        session: session.to_string(),
        source,
    })
}
