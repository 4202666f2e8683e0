//! A built-in policy, named as a run names it, run as its own policy process (`thorarena
//! client`): the session joined under the robot's joint names, the policy made from what
//! the session says, `echo` for the latency benchmark (action = q).

use super::{builtin_policy, RegistryError};
use crate::policy::client_process::{
    run_client_process, ClientError, ClientFaults, ClientObserver, MadePolicy,
};
use std::time::Duration;
use thorarena_ipc::{PolicyConfig, SessionInfo, WaitPolicy};

/// A client process's settings.
#[derive(Debug, Clone)]
pub struct ClientRequest {
    /// The session to join.
    pub session: String,
    /// A built-in policy (`balance`, `replay`, `hold`) or `echo`.
    pub policy: String,
    /// The name it gives in the handshake [default: the policy's].
    pub name: Option<String>,
    /// The bundled profile declared at connect (`None`: none declared).
    pub profile: Option<String>,
    /// The robot.
    pub robot: String,
    /// Seconds to wait for the session.
    pub connect_timeout_s: f64,
    /// Busy-poll this many µs for each observation before blocking.
    pub spin_us: u64,
    /// The pid announced in the handshake instead of its own (tests of a lying client).
    pub announced_pid: Option<u32>,
    /// Faults to inject.
    pub faults: ClientFaults,
}

/// Why a client process ended in error.
#[derive(Debug, thiserror::Error)]
pub enum NamedClientError {
    /// The robot is not known.
    #[error(transparent)]
    Registry(#[from] RegistryError),
    /// A timeout outside what [`crate::policy::check_wait_s`] takes.
    #[error("`option.connect_timeout` {0}")]
    ConnectTimeout(String),
    /// The session failed.
    #[error("session `{session}`")]
    Client {
        /// The session.
        session: String,
        /// Why.
        #[source]
        source: ClientError,
    },
}

/// Runs `request` until the session ends; returns the steps answered.
pub fn run_named_client(
    request: &ClientRequest,
    observer: &mut dyn ClientObserver,
) -> Result<u64, NamedClientError> {
    let robot = super::robot(&request.robot)?;
    let joint_names: Vec<String> = robot.joints.iter().map(|j| j.name.clone()).collect();
    let name = request.name.as_deref().unwrap_or(&request.policy);
    let mut config = PolicyConfig::new(&request.session, name, joint_names, vec![0.0]);
    if let Some(pid) = request.announced_pid {
        config.announced_pid = pid;
    }
    config.profile = request
        .profile
        .clone()
        .map(thorarena_ipc::DeclaredProfile::Named);
    config.wait = WaitPolicy {
        spin: Duration::from_micros(request.spin_us),
        ..WaitPolicy::default()
    };
    let timeout = crate::policy::check_wait_s(request.connect_timeout_s, false)
        .map_err(NamedClientError::ConnectTimeout)?
        .unwrap_or(crate::policy::MAX_WAIT); // never forever: 0 was refused

    let mut make = |info: &SessionInfo| -> MadePolicy {
        match request.policy.as_str() {
            "echo" => Ok(None),
            name => match builtin_policy(name, &robot, &info.action_offset_rad) {
                Some(policy) => policy.map(Some).map_err(|e| e.to_string()),
                None => Err(format!(
                    "unknown policy `{name}` (balance, replay, hold, echo)"
                )),
            },
        }
    };
    run_client_process(&config, timeout, &mut make, &request.faults, observer).map_err(|source| {
        NamedClientError::Client {
            session: request.session.clone(),
            source,
        }
    })
}
