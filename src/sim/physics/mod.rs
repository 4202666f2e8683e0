//! A `Physics` trait (reset, PD targets, hand forces, step, read state) and its rapier
//! multibody backend.
//!
//! Everything engine-specific stays behind the trait, so episodes, force replay and
//! metrics never see rapier types, and another backend can run the same conformance tests.
//! The other backend is MuJoCo (`mujoco.rs`, cargo feature `mujoco`), on an MJCF generated
//! from the robot model (`mjcf.rs`) or a user's. `make_physics` is the one factory, for the
//! run's `Engine` (`engine.rs`); the field's gain sets are `gains.rs`, the physics settings
//! and their defaults `settings.rs`.

mod engine;
mod gains;
mod mjcf;
#[cfg(feature = "mujoco")]
mod mujoco;
mod payload;
mod rapier;
mod settings;
mod state;

pub use engine::{make_physics, Engine, EngineError};
pub use gains::{armature_derived_gains, legged_gym_gains, standing_gains};
pub use mjcf::mjcf_of;
#[cfg(feature = "mujoco")]
pub use mujoco::{MujocoError, MujocoPhysics, MUJOCO_VERSION};
pub use payload::{Inertial, PointMass};
pub use rapier::{standing_default_pose, RapierPhysics};
pub use settings::{ContactMode, PdForm, PhysicsSettings};
pub use state::{ExternalForce, GroundContact, PdGains, PhysicsState, ResetState, RootState};

use crate::sim::robot::RobotModel;

/// A simulated robot that tracks PD targets under gravity, contacts and external forces.
///
/// Stepping never fails; loading and construction do. Joint vectors are in the model's
/// canonical order; body indices are those of [`RobotModel::bodies`].
pub trait Physics {
    /// The robot being simulated.
    fn model(&self) -> &RobotModel;

    /// The settings in force.
    fn settings(&self) -> &PhysicsSettings;

    /// Puts the robot in `state`, clears external forces and resets time to zero.
    /// Nothing of the previous episode (contact caches, warm starts) survives a reset.
    fn reset(&mut self, state: &ResetState);

    /// Sets PD gains and torque limits; they hold until changed (also across resets).
    fn set_gains(&mut self, gains: &PdGains);

    /// Sets the joint position targets of the PD law for the coming steps, rad.
    fn set_targets(&mut self, q_target: &[f64]);

    /// Sets a torque added to each joint's PD torque before its limit clamps it, N·m, for
    /// the coming steps (zero until set; it holds until changed, also across resets). A
    /// robot's motor law `τ = τ_ff + kp (q* − q) + kd (q̇* − q̇)` is the PD law with
    /// `τ_ff + kd q̇*` here: the DDS bridge sets it from each command.
    fn set_feedforward(&mut self, torque_nm: &[f64]);

    /// Holds a world-frame force at a point of a body for the coming steps, replacing any
    /// force previously set at that same point of that body (forces at other points add).
    fn set_external_force(&mut self, force: ExternalForce);

    /// Removes every external force.
    fn clear_external_forces(&mut self);

    /// Sets the point masses the bodies hold (a payload's weight and inertia, nothing
    /// else), replacing any set before; they take effect at the next [`Physics::reset`]
    /// and hold until changed, across resets. A payload on the root body is refused
    /// (panics): its frame is the floating base's.
    fn set_payloads(&mut self, payloads: &[PointMass]);

    /// Advances one physics step.
    fn step(&mut self);

    /// Writes the current state into `out` (reusing its buffers).
    fn read_state(&self, out: &mut PhysicsState);

    /// Simulated time since the last reset, s.
    fn time_s(&self) -> f64;

    /// Number of active contact points in the last step (for diagnostics and benchmarks).
    fn contact_count(&self) -> usize;

    /// Writes into `out` (cleared first) every robot–ground contact that carried force in
    /// the last step, with the ground's normal and friction force on the robot.
    fn ground_contacts(&self, out: &mut Vec<GroundContact>);
}
