//! The policies a run can name (`--policy`, a sweep's `policy`): the built-in baselines,
//! the published networks in process (`twist2:FILE`, `beyondmimic:FILE`,
//! `wbc-mjlab:FILE`), and a policy
//! process connecting to a session (`ipc:SESSION`).

use super::{did_you_mean, RegistryError};
use crate::policy::{
    BalanceGains, BalancePolicy, BeyondMimicPolicy, FalconPolicy, HoldPolicy, Policy, ReplayPolicy,
    SoftMimicPolicy, Twist2Policy,
};
use crate::profile::Profile;
use crate::robot::RobotModel;
use std::path::Path;
use std::sync::Arc;

/// What a policy argument names.
pub enum PolicyChoice<'a> {
    /// A policy run in this process, loaded.
    InProcess(Box<dyn Policy>),
    /// A policy process that connects to this session (the caller serves it).
    Session(&'a str),
}

/// The session name of `ipc:<session>`, if the policy argument is one.
pub fn ipc_session(policy: &str) -> Option<&str> {
    policy.strip_prefix("ipc:")
}

/// Loads the policy `spec` names for `robot` under `profile` (its default pose and action
/// mapping), or says which session a policy process should connect to.
pub fn policy<'a>(
    spec: &'a str,
    robot: &RobotModel,
    profile: &Profile,
) -> Result<PolicyChoice<'a>, RegistryError> {
    let default_pose = profile.action_offset_rad.clone();
    if let Some(builtin) = builtin_policy(spec, robot, &default_pose) {
        return Ok(PolicyChoice::InProcess(builtin?));
    }
    let policy: Box<dyn Policy> = match spec {
        other if other.ends_with(':') => {
            return Err(RegistryError::UnknownPolicy(unknown_policy(other)))
        }
        other => {
            if let Some(path) = other.strip_prefix("twist2:") {
                Box::new(Twist2Policy::load(Path::new(path), default_pose)?)
            } else if let Some(path) = other.strip_prefix("beyondmimic:") {
                Box::new(BeyondMimicPolicy::load(
                    Path::new(path),
                    Arc::new(robot.clone()),
                    profile,
                )?)
            } else if let Some(path) = other.strip_prefix("wbc-mjlab:") {
                Box::new(
                    BeyondMimicPolicy::load(Path::new(path), Arc::new(robot.clone()), profile)?
                        .named("wbc-mjlab"),
                )
            } else if let Some(path) = other.strip_prefix("falcon:") {
                Box::new(FalconPolicy::load(Path::new(path), profile)?)
            } else if let Some(rest) = other.strip_prefix("softmimic:") {
                let (path, params) = super::split_parameters(rest);
                let stiffness = crate::policy::softmimic::stiffness_from(params)?;
                Box::new(SoftMimicPolicy::load(
                    Path::new(path),
                    Arc::new(robot.clone()),
                    profile,
                    stiffness,
                )?)
            } else if let Some(session) = ipc_session(other) {
                return Ok(PolicyChoice::Session(session));
            } else {
                return Err(RegistryError::UnknownPolicy(unknown_policy(other)));
            }
        }
    };
    Ok(PolicyChoice::InProcess(policy))
}

/// The built-in policy `name` (`hold`, `replay`, `balance`) around `default_pose` (the
/// profile's, or the session's action offset for a policy process), or `None` when `name`
/// is not a built-in.
pub fn builtin_policy(
    name: &str,
    robot: &RobotModel,
    default_pose: &[f64],
) -> Option<Result<Box<dyn Policy>, RegistryError>> {
    let default_pose = default_pose.to_vec();
    Some(Ok(match name {
        "hold" => Box::new(HoldPolicy),
        "replay" => Box::new(ReplayPolicy::new(default_pose)),
        "balance" => match BalancePolicy::new(robot, default_pose, BalanceGains::default()) {
            Some(p) => Box::new(p),
            None => return Some(Err(RegistryError::BalanceNeedsLegs)),
        },
        _ => return None,
    }))
}

/// Why `spec` names no policy, with what it probably meant.
pub fn unknown_policy(spec: &str) -> String {
    let family = spec.trim_end_matches(':');
    let example = match family {
        "twist2" => Some("twist2_1017_25k.onnx, TWIST2's released checkpoint"),
        "beyondmimic" => Some("policy.onnx, an mjlab or holosoma G1 export"),
        "wbc-mjlab" => Some("wbc_g1_policy.onnx, wbc-mjlab's general G1 tracker"),
        "falcon" => Some("g1_29dof_falcon.onnx, FALCON's released G1 network"),
        "softmimic" => Some(
            "StaticStand-SoftMimic.onnx@stiffness=60, a SoftMimic network and its stiffness in N/m",
        ),
        _ => None,
    };
    if let Some(example) = example {
        return format!("`--policy {spec}` needs the network's file: `{family}:FILE.onnx` (e.g. {family}:{example})");
    }
    if family == "ipc" {
        return "`--policy ipc` needs a session name: `ipc:NAME`, the name the policy process connects to".into();
    }
    let names: Vec<String> = super::POLICY_FAMILIES
        .iter()
        .map(|f| {
            if f.spelling.contains(':') {
                format!("{}:", f.name)
            } else {
                f.name.to_string()
            }
        })
        .collect();
    let hint = did_you_mean(spec, names.iter().map(String::as_str));
    format!("unknown policy `{spec}`{hint}: built-in hold, replay or balance; twist2:FILE.onnx; beyondmimic:FILE.onnx; wbc-mjlab:FILE.onnx; falcon:FILE.onnx; softmimic:FILE.onnx[@stiffness=N]; or ipc:SESSION for a policy process")
}
