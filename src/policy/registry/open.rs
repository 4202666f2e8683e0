//! A policy argument made into a policy a run can step: built in process, or — for a
//! session (`ipc:NAME`) — served and waited for until a policy process connects: how
//! `eval` (and so every sweep task) and `serve` reach their policy. Callers that run only
//! in process (`crosscheck`, `policy check`, the leaderboard) load a `PolicyArg` directly.

use super::{PolicyArg, PolicyChoice, RegistryError};
use crate::policy::{Policy, RemoteError, RemotePolicy, SessionOptions};
use crate::sim::profile::Profile;
use crate::sim::robot::RobotModel;

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
}

/// What a run needs to reach its policy: the robot and profile it runs under, how a
/// policy process is served, and how many environment slots each batch holds.
pub struct PolicyTarget<'a> {
    /// The robot simulated.
    pub robot: &'a RobotModel,
    /// The dynamics profile (default pose, action mapping, control period).
    pub profile: &'a Profile,
    /// How a policy process is served (ignored in process).
    pub session: &'a SessionOptions,
    /// Environment slots per batch.
    pub envs: usize,
}

/// The policy `spec` names, made for `target`; a policy process (`ipc:`) must also pass
/// `vet` in its handshake — what the run requires of it, told to it when it fails — and
/// the session's news (serving, connected) goes to `note`.
pub fn open_policy(
    spec: &str,
    target: &PolicyTarget,
    vet: &mut dyn FnMut(&str) -> Result<(), String>,
    note: &mut dyn FnMut(&str),
) -> Result<Box<dyn Policy>, OpenPolicyError> {
    let arg = PolicyArg::parse(spec)?;
    match arg.load(target.robot, target.profile)? {
        PolicyChoice::InProcess(policy) => Ok(policy),
        PolicyChoice::Session(session) => Ok(Box::new(serve_session(session, target, vet, note)?)),
    }
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
        target.session,
        target.envs,
        vet,
        note,
    )
    .map_err(|source| OpenPolicyError::Serve {
        session: session.to_string(),
        source,
    })
}
