//! The `robot.toml` schema: everything about a robot that a URDF cannot say.

use serde::Deserialize;
use std::collections::BTreeMap;

/// Contents of `data/robots/<name>/robot.toml`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotConfig {
    /// Robot name; must equal the directory name.
    pub name: String,
    /// URDF file name, relative to the robot directory.
    pub urdf: String,
    /// Name of the URDF link that is the floating root.
    pub root_body: String,
    /// Collision elements with this `name` attribute are the soles used for ground contact
    /// in the default contact mode.
    #[serde(default = "default_sole_collision")]
    pub sole_collision: String,
    /// Actuated joints in canonical order (the order of every joint vector in ThorArena).
    pub joints: Vec<JointConfig>,
    /// Extra named points rigidly attached to a link (e.g. TWIST's `head_mocap`).
    #[serde(default)]
    pub frames: BTreeMap<String, FrameConfig>,
    /// Keypoint sets for the tracking metrics; `default` is required.
    pub keypoints: BTreeMap<String, KeypointSetConfig>,
    /// The two hands on which interaction forces are replayed.
    pub hands: HandsConfig,
}

fn default_sole_collision() -> String {
    "sole".to_string()
}

/// One actuated joint.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointConfig {
    /// URDF joint name.
    pub name: String,
    /// Actuator torque limit, N·m (symmetric).
    pub effort_nm: f64,
    /// Velocity limit, rad/s.
    pub velocity_rad_s: f64,
    /// Reflected rotor inertia added on the joint's diagonal, kg·m².
    pub armature_kgm2: f64,
    /// Joint angle of the default (nominal standing) pose, rad.
    pub default_rad: f64,
}

/// A named point on a link.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrameConfig {
    /// URDF link the frame is attached to.
    pub parent: String,
    /// Position in the parent link frame, m.
    pub xyz: [f64; 3],
    /// Orientation in the parent link frame (URDF roll-pitch-yaw), rad.
    #[serde(default)]
    pub rpy: [f64; 3],
}

/// A keypoint set split into its upper- and lower-body parts (for Upper/Lower KP).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KeypointSetConfig {
    /// Upper-body frames (URDF links or `frames` entries).
    pub upper: Vec<String>,
    /// Lower-body frames.
    pub lower: Vec<String>,
}

/// Left and right hand.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HandsConfig {
    /// Left hand.
    pub left: HandConfig,
    /// Right hand.
    pub right: HandConfig,
}

/// Where a replayed force acts and how the force sensor is mounted.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HandConfig {
    /// The hand frame (URDF link or `frames` entry).
    pub frame: String,
    /// Force application point in the hand frame, m.
    pub point_xyz: [f64; 3],
    /// Default rotation from the force-sensor frame to the hand frame (roll-pitch-yaw, rad);
    /// a dataset may override it per sequence.
    pub hand_from_sensor_rpy: [f64; 3],
}
