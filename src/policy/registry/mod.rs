//! The names a user gives — on the command line, in a sweep spec — resolved in one place:
//! dynamics profiles (a bundled name or a `.toml` path), robots (a bundled name or a
//! directory with `robot.toml`), and which profile a policy family runs on. A name that
//! matches nothing is an error listing what exists, with the nearest one when it looks
//! like a typo ([`did_you_mean`]).

mod client;
mod families;
mod named_policy;
mod networks;
mod open;
mod parameters;
mod policies;
mod policy_source;
mod suggest;
mod trained_forces;

pub use client::{run_named_client, ClientRequest, NamedClientError};
pub use families::{
    families_text, policy_help, profile_help, Build, PolicyFamily, ProfileRule, Runs, Target,
    NETWORK_SLOTS_PER_WORKER, POLICY_FAMILIES,
};
pub use named_policy::NamedPolicy;
pub use networks::{known_network, KnownNetwork, KNOWN_NETWORKS};
pub use open::{
    launch, open_in_process, open_policy, serve_session, OpenPolicyError, PolicyTarget,
};
pub use parameters::{parse_parameters, Parameter, ParameterValues};
pub use policies::{builtin_policy, PolicyChoice};
pub use policy_source::PolicySource;
pub use suggest::{closest, did_you_mean};
pub use trained_forces::{TrainedForces, FALCON_FORCES, MEASURED_TOLERANCE_N, SOFTMIMIC_FORCES};

use crate::sim::profile::{bundled_profile_path, load_profile, Profile, ProfileError};
use crate::sim::robot::{RobotError, RobotModel};
use std::path::{Path, PathBuf};

/// Why a name resolved to nothing usable.
#[derive(Debug, thiserror::Error)]
pub enum RegistryError {
    /// A profile name that is neither bundled nor a `.toml` path.
    #[error("no such profile `{name}`{hint} (bundled: {}; or the path of a .toml file)", bundled.join(", "))]
    UnknownProfile {
        /// The name given.
        name: String,
        /// ` (did you mean …?)` or nothing.
        hint: String,
        /// The bundled profiles' names.
        bundled: Vec<String>,
    },
    /// The profile exists but cannot be used for the robot.
    #[error(transparent)]
    Profile(#[from] ProfileError),
    /// A policy argument that names no policy (the message says what it probably meant).
    #[error("{0}")]
    UnknownPolicy(String),
    /// Parameters the policy's family does not take as given ([`parse_parameters`]).
    #[error("`{policy}`: {why}")]
    Parameters {
        /// The argument.
        policy: String,
        /// What is wrong, and what the family takes.
        why: String,
    },
    /// `balance` needs the leg joints of a humanoid.
    #[error("the robot lacks the leg joints `balance` needs")]
    BalanceNeedsLegs,
    /// A TWIST2 network that cannot be used.
    #[error(transparent)]
    Twist2(#[from] crate::policy::twist2::Twist2Error),
    /// A FALCON network that cannot be used.
    #[error(transparent)]
    Falcon(#[from] crate::policy::falcon::FalconError),
    /// A SoftMimic network, or its parameters, that cannot be used.
    #[error(transparent)]
    SoftMimic(#[from] crate::policy::softmimic::SoftMimicError),
    /// A BeyondMimic-style network that cannot be used.
    #[error(transparent)]
    BeyondMimic(#[from] crate::policy::beyondmimic::BeyondMimicError),
    /// The robot could not be loaded.
    #[error("loading robot `{name}`")]
    Robot {
        /// The name or directory given.
        name: String,
        /// Why.
        source: RobotError,
    },
}

/// The bundled profiles' names (`data/profiles/*.toml`), sorted.
pub fn bundled_profile_names() -> Vec<String> {
    let dir = bundled_profile_path("x")
        .parent()
        .map(Path::to_path_buf)
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

/// The file of profile `name_or_path`: a path ending in `.toml` as given, else the
/// bundled profile of that name, which must exist.
pub fn profile_path(name_or_path: &str) -> Result<PathBuf, RegistryError> {
    if name_or_path.ends_with(".toml") {
        return Ok(PathBuf::from(name_or_path));
    }
    let path = bundled_profile_path(name_or_path);
    if path.is_file() {
        return Ok(path);
    }
    let bundled = bundled_profile_names();
    Err(RegistryError::UnknownProfile {
        name: name_or_path.to_string(),
        hint: did_you_mean(name_or_path, bundled.iter().map(String::as_str)),
        bundled,
    })
}

/// Profile `name_or_path` ([`profile_path`]) loaded and resolved for `robot`.
pub fn profile(name_or_path: &str, robot: &RobotModel) -> Result<Profile, RegistryError> {
    Ok(load_profile(&profile_path(name_or_path)?, robot)?)
}

/// Robot `name_or_dir`: a directory holding `robot.toml`, else a bundled robot's name.
pub fn robot(name_or_dir: &str) -> Result<RobotModel, RegistryError> {
    let path = Path::new(name_or_dir);
    let model = if path.join("robot.toml").is_file() {
        crate::sim::robot::load_robot_dir(path)
    } else {
        crate::sim::robot::load_bundled(name_or_dir)
    };
    model.map_err(|source| RegistryError::Robot {
        name: name_or_dir.to_string(),
        source,
    })
}
