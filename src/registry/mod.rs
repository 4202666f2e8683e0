//! The names a user gives — on the command line, in a sweep spec — resolved in one place:
//! dynamics profiles (a bundled name or a `.toml` path), robots (a bundled name or a
//! directory with `robot.toml`), and which profile a policy family runs on. A name that
//! matches nothing is an error listing what exists, with the nearest one when it looks
//! like a typo ([`did_you_mean`]).

mod families;
mod networks;
mod policies;
mod suggest;

pub use families::{
    policy_family, policy_file, policy_file_stem, policy_parameters, split_parameters,
    PolicyFamily, Runs, NETWORK_SLOTS_PER_WORKER, POLICY_FAMILIES,
};
pub use networks::{known_network, KnownNetwork, KNOWN_NETWORKS};
pub use policies::{builtin_policy, ipc_session, policy, unknown_policy, PolicyChoice};
pub use suggest::{closest, did_you_mean};

use crate::profile::{bundled_profile_path, load_profile, Profile, ProfileError};
use crate::robot::{RobotError, RobotModel};
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
        crate::robot::load_robot_dir(path)
    } else {
        crate::robot::load_bundled(name_or_dir)
    };
    model.map_err(|source| RegistryError::Robot {
        name: name_or_dir.to_string(),
        source,
    })
}

/// Whether `profile` is one the family of policy argument `policy` was trained with:
/// TWIST2 networks the `twist2` profile, BeyondMimic-style ones `beyondmimic` or a profile
/// with a `[beyondmimic]` section (`holosoma-wbt`); the built-ins and policy processes
/// any. The error says why not.
pub fn profile_fits(policy: &str, profile: &Profile) -> Result<(), String> {
    if policy.starts_with("twist2:") && profile.name != "twist2" {
        return Err(format!(
            "TWIST2 networks are trained for the `twist2` profile (its gains, action scale and 50 Hz); `{}` contradicts it",
            profile.name
        ));
    }
    if policy.starts_with("beyondmimic:")
        && profile.name != "beyondmimic"
        && profile.beyondmimic.is_none()
    {
        return Err(format!(
            "BeyondMimic-style networks run on `beyondmimic` or a profile with a [beyondmimic] section (holosoma-wbt); `{}` is neither",
            profile.name
        ));
    }
    if policy.starts_with("falcon:") && profile.name != "falcon" {
        return Err(format!(
            "FALCON's network runs on the `falcon` profile (its gains, 0.25 action scale, default pose and 50 Hz); `{}` contradicts it",
            profile.name
        ));
    }
    if policy.starts_with("softmimic:") && profile.name != "softmimic" {
        return Err(format!(
            "SoftMimic's networks run on the `softmimic` profile (its gains, 0.5 action scale, default pose and 50 Hz); `{}` contradicts it",
            profile.name
        ));
    }
    if policy.starts_with("wbc-mjlab:") && profile.beyondmimic.is_none() {
        return Err(format!(
            "wbc-mjlab's network runs on the `wbc-mjlab` profile (its gains, residual action scale and torque cap) or another with a [beyondmimic] section; `{}` has none",
            profile.name
        ));
    }
    Ok(())
}

/// Environment slots per worker when a run of `policy` names none (its family's
/// [`PolicyFamily::slots_per_worker`]; 1 for a policy process).
pub fn slots_per_worker(policy: &str) -> usize {
    policy_family(policy).map_or(1, |f| f.slots_per_worker)
}

/// The profile a policy was trained with, used by `eval`, sweeps, `policy check` and the
/// leaderboard when no profile is named: a published network's own ([`KNOWN_NETWORKS`],
/// by the file's content), else its family's (its entry in [`POLICY_FAMILIES`]: `twist2`
/// for `twist2:`, `beyondmimic` for `beyondmimic:`, …), else `default` (the built-ins,
/// policy processes, anything unknown).
pub fn family_profile(policy: &str) -> &'static str {
    if let Some(known) = policy_file(policy).and_then(|(_, file)| known_network(Path::new(file))) {
        return known.profile;
    }
    policy_family(policy).map_or("default", |f| f.profile)
}
