//! Dynamics profiles (`data/profiles/*.toml`): the fixed deployment settings a policy is
//! evaluated under — robot, control and physics steps, action mapping, delay, PD gains and
//! torque limits — resolved against the robot model and validated on load.

use crate::files::log_text::short_number as short;
use crate::sim::physics::PdGains;
use crate::sim::robot::RobotModel;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Why a profile could not be loaded. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum ProfileError {
    /// The file could not be read.
    #[error("cannot read {path}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// Not valid TOML, or not the schema.
    #[error("{path}: {message}")]
    Toml {
        /// The file.
        path: PathBuf,
        /// The parser's message (with line and column).
        message: String,
    },
    /// A field contradicts the robot or the rules of a profile.
    #[error("{path}: field `{field}`: {reason}")]
    BadField {
        /// The file.
        path: PathBuf,
        /// The field.
        field: String,
        /// What is wrong.
        reason: String,
    },
}

/// A value per joint: keyed by the full joint name (`left_shoulder_roll_joint`), by its
/// group — the name without side prefix and `_joint` suffix (`hip_pitch`, `knee`,
/// `waist_yaw`, …) — or `default`; the most specific key wins.
type PerGroup = BTreeMap<String, f64>;

/// The profile file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct ProfileFile {
    name: String,
    robot: String,
    control_dt_s: f64,
    physics_dt_s: f64,
    #[serde(default)]
    action_delay_steps: usize,
    action_clip: Option<f64>,
    action_scale: PerGroup,
    #[serde(default)]
    action_offset_rad: Option<PerGroup>,
    kp: PerGroup,
    kd: PerGroup,
    #[serde(default)]
    effort_limit_nm: PerGroup,
    #[serde(default)]
    source: String,
    #[serde(default)]
    beyondmimic: Option<BeyondMimicProfile>,
}

/// `[beyondmimic]`: what a `beyondmimic:` policy is fed when its file does not say
/// (holosoma's exports carry no observation metadata).
#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BeyondMimicProfile {
    /// Observation terms in order (names as in `observation_names` metadata).
    #[serde(default)]
    pub observation_names: Vec<String>,
    /// The body whose pose anchors the reference (`torso_link` in every G1 export known).
    #[serde(default = "torso_link")]
    pub anchor_body: String,
    /// How the network's action becomes a joint target, when the file does not say.
    #[serde(default)]
    pub action_mode: Option<ActionMode>,
    /// The network's joint order, when the file does not say (bare exports, e.g. in Isaac
    /// Lab's breadth-first order); empty: the file's `joint_names`, else the robot's order.
    #[serde(default)]
    pub joint_names: Vec<String>,
}

/// How a BeyondMimic-family network's action becomes a joint target (wbc-mjlab's
/// `action_mode`, wbc-g1-deploy `src/wbc_tracking_params.cpp`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ActionMode {
    /// target = default pose + scale · action (mjlab's `JointPositionAction`).
    #[default]
    DefaultRelative,
    /// target = the reference's joint position at this step + scale · action (wbc-mjlab's
    /// `ReferenceJointPositionAction`): the network learns a residual on the reference.
    ReferenceResidual,
}

impl ActionMode {
    /// Every mode, for parsing and for errors.
    pub const ALL: [ActionMode; 2] = [Self::DefaultRelative, Self::ReferenceResidual];

    /// Its name, as the metadata and the profile spell it.
    pub fn name(self) -> &'static str {
        match self {
            Self::DefaultRelative => "default_relative",
            Self::ReferenceResidual => "reference_residual",
        }
    }

    /// The mode `name` spells.
    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.name() == name.trim())
    }
}

fn torso_link() -> String {
    "torso_link".into()
}

/// A resolved profile: every per-joint quantity in the robot's canonical order.
#[derive(Debug, Clone, PartialEq)]
pub struct Profile {
    /// Profile name.
    pub name: String,
    /// Robot name.
    pub robot: String,
    /// Policy period, s.
    pub control_dt_s: f64,
    /// Physics step, s.
    pub physics_dt_s: f64,
    /// Physics steps per control step.
    pub substeps: usize,
    /// Control steps between a policy output and its effect.
    pub action_delay_steps: usize,
    /// Raw actions are clipped to ±this before scaling (no clip when `None`).
    pub action_clip: Option<f64>,
    /// Target = offset + scale · action, per joint.
    pub action_scale: Vec<f64>,
    /// The action offset (the policy's default pose; the robot's unless the profile gives
    /// one), rad.
    pub action_offset_rad: Vec<f64>,
    /// PD gains and torque limits.
    pub gains: PdGains,
    /// Where the numbers come from.
    pub source: String,
    /// Defaults for `beyondmimic:` policies.
    pub beyondmimic: Option<BeyondMimicProfile>,
}

impl Profile {
    /// SHA-256 of the resolved profile — every number a run uses (periods, delay, action
    /// clip, scale and offset, gains, torque limits, the `[beyondmimic]` section) and its
    /// name — lowercase hex: the profile's part of a run's identity (`run.json`). It is of
    /// the resolved values, not the file's text, so a comment edited changes nothing and a
    /// gain changed anywhere (a `.toml` path, a `THORARENA_DATA` copy) always shows.
    /// Rust's `Debug` text prints every `f64` exactly (shortest round trip).
    pub fn fingerprint(&self) -> String {
        crate::files::content_hash::sha256_hex(format!("{self:?}").as_bytes())
    }

    /// Joint position targets for a raw policy action (clip, scale, offset).
    pub fn targets_from_action(&self, action: &[f64], targets: &mut [f64]) {
        for (i, t) in targets.iter_mut().enumerate() {
            let a = match self.action_clip {
                Some(c) => action[i].clamp(-c, c),
                None => action[i],
            };
            *t = self.action_offset_rad[i] + self.action_scale[i] * a;
        }
    }
}

/// `data/profiles/<name>.toml` of the bundled profiles.
pub fn bundled_profile_path(name: &str) -> PathBuf {
    crate::data_dir()
        .join("profiles")
        .join(format!("{name}.toml"))
}

/// The largest profile file read, bytes (a bundled one is under 4 KiB).
pub const MAX_PROFILE_BYTES: u64 = crate::files::bounded_read::MIB;

/// Loads and resolves a profile file for `robot` (a regular file of at most
/// [`MAX_PROFILE_BYTES`]).
pub fn load_profile(path: &Path, robot: &RobotModel) -> Result<Profile, ProfileError> {
    let text = crate::files::bounded_read::read_to_string(path, "profile", MAX_PROFILE_BYTES)
        .map_err(|source| ProfileError::Io {
            path: path.to_path_buf(),
            source,
        })?;
    let file: ProfileFile = toml::from_str(&text).map_err(|e| ProfileError::Toml {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    resolve_file(file, path, robot)
}

/// A profile given by its numbers, each per joint in `robot`'s canonical order (a policy
/// process declares one so at connect): resolved and checked as a file's would be, its
/// torque limits the robot's. `origin` names it in errors, where a file's path would be.
pub fn profile_from_numbers(
    numbers: ProfileNumbers,
    origin: &str,
    robot: &RobotModel,
) -> Result<Profile, ProfileError> {
    let origin = Path::new(origin);
    let per_joint = |field: &str, values: &[f64]| -> Result<PerGroup, ProfileError> {
        if values.len() != robot.joints.len() {
            return Err(ProfileError::BadField {
                path: origin.to_path_buf(),
                field: field.into(),
                reason: format!(
                    "{} values for the {} joints of {}",
                    values.len(),
                    robot.joints.len(),
                    robot.name
                ),
            });
        }
        Ok(robot
            .joints
            .iter()
            .zip(values)
            .map(|(j, v)| (j.name.clone(), *v))
            .collect())
    };
    let file = ProfileFile {
        robot: robot.name.clone(),
        control_dt_s: numbers.control_dt_s,
        physics_dt_s: numbers.physics_dt_s,
        action_delay_steps: numbers.action_delay_steps,
        action_clip: numbers.action_clip,
        action_scale: per_joint("action_scale", &numbers.action_scale)?,
        action_offset_rad: Some(per_joint("action_offset_rad", &numbers.action_offset_rad)?),
        kp: per_joint("kp", &numbers.kp)?,
        kd: per_joint("kd", &numbers.kd)?,
        effort_limit_nm: PerGroup::new(),
        source: numbers.source,
        beyondmimic: None,
        name: numbers.name,
    };
    resolve_file(file, origin, robot)
}

/// What [`profile_from_numbers`] takes: a profile's name, periods, delay, clip and its
/// per-joint action mapping and gains.
#[derive(Debug, Clone, PartialEq)]
pub struct ProfileNumbers {
    /// Its name.
    pub name: String,
    /// Where the numbers come from (recorded as the profile's `source`).
    pub source: String,
    /// Policy period, s.
    pub control_dt_s: f64,
    /// Physics step, s.
    pub physics_dt_s: f64,
    /// Control steps between a policy output and its effect.
    pub action_delay_steps: usize,
    /// Raw actions are clipped to ±this before scaling (`None`: no clip).
    pub action_clip: Option<f64>,
    /// Target = offset + scale · action, per joint.
    pub action_scale: Vec<f64>,
    /// The action offset, rad, per joint.
    pub action_offset_rad: Vec<f64>,
    /// Stiffness, N·m/rad, per joint.
    pub kp: Vec<f64>,
    /// Damping, N·m·s/rad, per joint.
    pub kd: Vec<f64>,
}

/// A per-joint field of a profile file for `robot`: each joint's own value, else its
/// group's, else `default`, else `fallback`; each finite, within the field's limit, and
/// `>= 0` unless `allow_negative`; a key naming no joint or group is refused.
fn per_joint(
    robot: &RobotModel,
    path: &Path,
    field: &str,
    table: &PerGroup,
    fallback: Option<&dyn Fn(usize) -> f64>,
    allow_negative: bool,
) -> Result<Vec<f64>, ProfileError> {
    let bad = |field: &str, reason: String| ProfileError::BadField {
        path: path.to_path_buf(),
        field: field.into(),
        reason,
    };
    let max = field_limit(field);
    let groups: Vec<String> = robot.joints.iter().map(|j| joint_group(&j.name)).collect();
    for key in table.keys() {
        if key != "default" && !groups.iter().any(|g| g == key) && robot.joint_index(key).is_none()
        {
            return Err(bad(
                &format!("{field}.{key}"),
                format!("no joint of {} is named or grouped `{key}`", robot.name),
            ));
        }
    }
    groups
        .iter()
        .enumerate()
        .map(|(j, g)| {
            let v = table
                .get(&robot.joints[j].name)
                .or_else(|| table.get(g))
                .or_else(|| table.get("default"))
                .copied()
                .or_else(|| fallback.map(|f| f(j)));
            match v {
                Some(v) if v.is_finite() && (allow_negative || v >= 0.0) && v.abs() <= max.0 => {
                    Ok(v)
                }
                Some(v) if v.is_finite() && (allow_negative || v >= 0.0) => Err(bad(
                    &format!("{field}.{g}"),
                    format!(
                        "{} is beyond {} ({}): no actuator of a humanoid this size has it, so it is taken for a mistake",
                        short(v),
                        short(max.0),
                        max.1
                    ),
                )),
                Some(v) => Err(bad(
                    &format!("{field}.{g}"),
                    format!("must be a finite value >= 0, got {}", short(v)),
                )),
                None => Err(bad(
                    field,
                    format!(
                        "no value for joint `{}` (group `{g}`) and no `default`",
                        robot.joints[j].name
                    ),
                )),
            }
        })
        .collect()
}

/// A parsed profile file resolved for `robot` and checked (`path` names it in errors).
fn resolve_file(
    file: ProfileFile,
    path: &Path,
    robot: &RobotModel,
) -> Result<Profile, ProfileError> {
    let bad = |field: &str, reason: String| ProfileError::BadField {
        path: path.to_path_buf(),
        field: field.into(),
        reason,
    };
    if file.robot != robot.name {
        return Err(bad(
            "robot",
            format!("`{}`, but the robot loaded is `{}`", file.robot, robot.name),
        ));
    }
    for (field, v) in [
        ("control_dt_s", file.control_dt_s),
        ("physics_dt_s", file.physics_dt_s),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(bad(field, format!("must be > 0, got {v}")));
        }
    }
    let ratio = file.control_dt_s / file.physics_dt_s;
    let substeps = ratio.round();
    if substeps < 1.0 || (ratio - substeps).abs() > 1e-6 {
        return Err(bad(
            "control_dt_s",
            format!(
                "{} s is not a whole multiple of physics_dt_s {} s",
                file.control_dt_s, file.physics_dt_s
            ),
        ));
    }
    if let Some(c) = file.action_clip {
        if !(c.is_finite() && c > 0.0) {
            return Err(bad("action_clip", format!("must be > 0, got {}", short(c))));
        }
    }
    if file.control_dt_s > MAX_CONTROL_DT_S || substeps > MAX_PROFILE_SUBSTEPS as f64 {
        return Err(bad(
            "control_dt_s",
            format!(
                "{} s of {} s physics steps: give at most {MAX_CONTROL_DT_S} s and {MAX_PROFILE_SUBSTEPS} physics steps a control step",
                short(file.control_dt_s),
                short(file.physics_dt_s)
            ),
        ));
    }
    if file.action_delay_steps > MAX_ACTION_DELAY_STEPS {
        return Err(bad(
            "action_delay_steps",
            format!(
                "{}: give at most {MAX_ACTION_DELAY_STEPS} control steps",
                file.action_delay_steps
            ),
        ));
    }
    let resolve_signed = |field: &str,
                          table: &PerGroup,
                          fallback: Option<&dyn Fn(usize) -> f64>,
                          allow_negative: bool| {
        per_joint(robot, path, field, table, fallback, allow_negative)
    };
    let resolve = |field: &str, table: &PerGroup, fallback: Option<&dyn Fn(usize) -> f64>| {
        resolve_signed(field, table, fallback, false)
    };
    let effort = |j: usize| robot.joints[j].effort_nm;
    let default_pose = |j: usize| robot.joints[j].default_rad;
    let action_offset_rad = match &file.action_offset_rad {
        Some(t) => resolve_signed("action_offset_rad", t, Some(&default_pose), true)?,
        None => robot.default_pose(),
    };
    Ok(Profile {
        name: file.name,
        robot: file.robot,
        control_dt_s: file.control_dt_s,
        physics_dt_s: file.physics_dt_s,
        substeps: substeps as usize,
        action_delay_steps: file.action_delay_steps,
        action_clip: file.action_clip,
        action_scale: resolve("action_scale", &file.action_scale, None)?,
        action_offset_rad,
        gains: PdGains {
            kp: resolve("kp", &file.kp, None)?,
            kd: resolve("kd", &file.kd, None)?,
            effort_limit_nm: resolve("effort_limit_nm", &file.effort_limit_nm, Some(&effort))?,
        },
        source: file.source,
        beyondmimic: file.beyondmimic,
    })
}

/// The longest control period a profile may have, s: a humanoid policy runs at 25 Hz
/// or faster (every bundled profile: 50 Hz), so a period over a second is a slip of units.
const MAX_CONTROL_DT_S: f64 = 1.0;
/// Most physics steps a control step may take (every bundled profile: 4 or 10).
const MAX_PROFILE_SUBSTEPS: usize = 1000;
/// Most control steps an action may wait (every bundled profile: 0; a robot's
/// deployment delay is one or two).
const MAX_ACTION_DELAY_STEPS: usize = 50;

/// The largest magnitude a per-joint field of a profile takes, and its unit. The G1's
/// stiffest bundled gains are FALCON's waist at kp 300 N·m/rad (`data/profiles/falcon.toml`)
/// and its largest motor limit 139 N·m (`data/robots/g1_29dof/robot.toml`, from
/// Unitree's description); these bounds sit two orders of magnitude above them, so
/// no real profile meets them while a slip of the exponent (kp 1e300) is refused before
/// it runs, instead of being simulated and labelled with the profile's name.
fn field_limit(field: &str) -> (f64, &'static str) {
    match field {
        "kp" => (1e5, "N·m/rad"),
        "kd" => (1e4, "N·m·s/rad"),
        "effort_limit_nm" => (1e5, "N·m"),
        "action_scale" => (100.0, "rad per unit of action"),
        _ => (4.0 * std::f64::consts::PI, "rad"),
    }
}

/// `left_hip_pitch_joint` → `hip_pitch`; `waist_yaw_joint` → `waist_yaw`.
pub fn joint_group(joint: &str) -> String {
    let s = joint.strip_suffix("_joint").unwrap_or(joint);
    let s = s
        .strip_prefix("left_")
        .or_else(|| s.strip_prefix("right_"))
        .unwrap_or(s);
    s.to_string()
}
