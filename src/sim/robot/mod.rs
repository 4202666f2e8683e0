//! The robot model: joints in canonical order, bodies, keypoints and hands, loaded from
//! `data/robots/<name>/` (a URDF plus `robot.toml`), forward kinematics and inverse dynamics
//! (`dynamics.rs`, recursive Newton–Euler) on it, and the
//! model as a table for people (`describe`, printed by `thorarena robot`).

mod config;
mod describe;
mod dynamics;
mod error;
mod kinematics;
mod load;
mod model;

pub use config::{
    FrameConfig, HandConfig, HandsConfig, JointConfig, KeypointSetConfig, RobotConfig,
};
pub use describe::describe;
pub use dynamics::{inverse_dynamics, InverseDynamics, MotionState, PointForce};
pub use error::RobotError;
pub use kinematics::{
    center_of_mass, forward_kinematics, frame_pose, frame_velocity_w, keypoint_positions,
    lowest_sole_point_z, lowest_sole_point_z_of,
};
pub use load::{build_model, bundled_robot_dir, load_robot_dir};
pub use model::{Body, Frame, Geometry, Hand, Joint, KeypointSet, RobotModel, Shape};

/// Loads a robot shipped in `data/robots/<name>`.
pub fn load_bundled(name: &str) -> Result<RobotModel, RobotError> {
    load_robot_dir(&bundled_robot_dir(name))
}
