//! Each family's builder and profile rule, which its entry in
//! [`super::POLICY_FAMILIES`] names: the built-in baselines, the published networks in
//! process, and what a run holds a profile to for each.

use super::{NamedPolicy, RegistryError};
use crate::policy::{
    BalanceGains, BalancePolicy, BeyondMimicPolicy, FalconPolicy, HoldPolicy, Policy, ReplayPolicy,
    SoftMimicPolicy, Twist2Policy,
};
use crate::sim::profile::Profile;
use crate::sim::robot::RobotModel;
use std::sync::Arc;

/// What a parsed argument is built into.
pub enum PolicyChoice<'a> {
    /// A policy run in this process, loaded.
    InProcess(Box<dyn Policy>),
    /// A policy process that connects to this session (the caller serves it).
    Session(&'a str),
    /// A policy process the caller starts with this command, on a session it serves.
    Launched(&'a crate::policy::launched::PolicyCommand),
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

/// The builder of the built-in families (`hold`, `replay`, `balance`), by name.
pub(super) fn builtin(
    arg: &NamedPolicy,
    robot: &RobotModel,
    profile: &Profile,
) -> Result<Box<dyn Policy>, RegistryError> {
    builtin_policy(arg.family().name, robot, &profile.action_offset_rad)
        .expect("the built-in families are the built-ins")
}

/// The network file of a file family's argument (present: [`NamedPolicy::parse`] refuses
/// one without).
fn file(arg: &NamedPolicy) -> &std::path::Path {
    arg.file().expect("a file family's argument names its file")
}

pub(super) fn twist2(
    a: &NamedPolicy,
    _: &RobotModel,
    p: &Profile,
) -> Result<Box<dyn Policy>, RegistryError> {
    Ok(Box::new(Twist2Policy::load(
        file(a),
        p.action_offset_rad.clone(),
    )?))
}

pub(super) fn beyondmimic(
    a: &NamedPolicy,
    r: &RobotModel,
    p: &Profile,
) -> Result<Box<dyn Policy>, RegistryError> {
    Ok(Box::new(BeyondMimicPolicy::load(
        file(a),
        Arc::new(r.clone()),
        p,
    )?))
}

pub(super) fn wbc_mjlab(
    a: &NamedPolicy,
    r: &RobotModel,
    p: &Profile,
) -> Result<Box<dyn Policy>, RegistryError> {
    Ok(Box::new(
        BeyondMimicPolicy::load(file(a), Arc::new(r.clone()), p)?.named("wbc-mjlab"),
    ))
}

pub(super) fn falcon(
    a: &NamedPolicy,
    _: &RobotModel,
    p: &Profile,
) -> Result<Box<dyn Policy>, RegistryError> {
    use crate::policy::falcon::commands::CommandRules;
    let scale = a.parameter("arm_residual").unwrap_or(1.0);
    let b = CommandRules::BENCHMARK;
    let rules = CommandRules {
        min_speed_m_s: a.parameter("min_speed").unwrap_or(b.min_speed_m_s),
        yaw_feedforward: a.parameter("yaw_ff").unwrap_or(b.yaw_feedforward),
        hold_s: a.parameter("hold").unwrap_or(b.hold_s),
    };
    Ok(Box::new(
        FalconPolicy::load(file(a), p)?
            .with_arm_residual_scale(scale)
            .with_command_rules(rules),
    ))
}

pub(super) fn softmimic(
    a: &NamedPolicy,
    r: &RobotModel,
    p: &Profile,
) -> Result<Box<dyn Policy>, RegistryError> {
    let stiffness = crate::policy::softmimic::stiffness_from(
        a.parameter("stiffness"),
        a.parameter("rotational_stiffness"),
    )?;
    Ok(Box::new(SoftMimicPolicy::load(
        file(a),
        Arc::new(r.clone()),
        p,
        stiffness,
    )?))
}

/// The built-ins and policy processes run under any profile.
pub(super) fn any_profile(_: &Profile) -> Result<(), String> {
    Ok(())
}

pub(super) fn twist2_profile(p: &Profile) -> Result<(), String> {
    named(
        p,
        "twist2",
        "TWIST2 networks are trained for the `twist2` profile (its gains, action scale and 50 Hz)",
    )
}

pub(super) fn falcon_profile(p: &Profile) -> Result<(), String> {
    named(p, "falcon", "FALCON's network runs on the `falcon` profile (its gains, 0.25 action scale, default pose and 50 Hz)")
}

pub(super) fn softmimic_profile(p: &Profile) -> Result<(), String> {
    named(p, "softmimic", "SoftMimic's networks run on the `softmimic` profile (its gains, 0.5 action scale, default pose and 50 Hz)")
}

pub(super) fn beyondmimic_profile(p: &Profile) -> Result<(), String> {
    if p.name == "beyondmimic" || p.beyondmimic.is_some() {
        return Ok(());
    }
    Err(format!(
        "BeyondMimic-style networks run on `beyondmimic` or a profile with a [beyondmimic] section (holosoma-wbt); `{}` is neither",
        p.name
    ))
}

pub(super) fn wbc_mjlab_profile(p: &Profile) -> Result<(), String> {
    if p.beyondmimic.is_some() {
        return Ok(());
    }
    Err(format!(
        "wbc-mjlab's network runs on the `wbc-mjlab` profile (its gains, residual action scale and torque cap) or another with a [beyondmimic] section; `{}` has none",
        p.name
    ))
}

/// `profile` must be `name`; `why` says what that profile holds.
fn named(profile: &Profile, name: &str, why: &str) -> Result<(), String> {
    if profile.name == name {
        return Ok(());
    }
    Err(format!("{why}; `{}` contradicts it", profile.name))
}
