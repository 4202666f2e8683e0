//! The physics backends against analytic results and against themselves: momentum under a
//! known force, an analytic PD step response, determinism, standing, kinematic
//! consistency, and one test per rapier multibody pitfall of ARCHITECTURE.md, rapier pitfalls.
//!
//! Every test goes through the `Physics` trait via `backend`; the same suite
//! (`physics_conformance/suite.rs`) runs once per backend: rapier, and MuJoCo on the MJCF
//! generated from the robot model (with the cargo feature `mujoco`).

use nalgebra::{Isometry3, Point3, Vector3};
use std::sync::Arc;
use thorarena::sim::physics::{
    legged_gym_gains, standing_default_pose, standing_gains, ContactMode, ExternalForce, PdForm,
    PdGains, Physics, PhysicsSettings, PhysicsState, PointMass, ResetState, RootState,
};
use thorarena::sim::robot::{self, RobotModel};

mod rapier {
    use super::*;

    /// Which engine this module tests (for the known differences of `friction.rs`).
    const ENGINE: &str = "rapier";

    /// The backend under test.
    fn backend(
        model: &Arc<RobotModel>,
        settings: PhysicsSettings,
        gains: PdGains,
    ) -> Box<dyn Physics> {
        Box::new(thorarena::sim::physics::RapierPhysics::new(
            model.clone(),
            settings,
            gains,
        ))
    }

    include!("physics_conformance/suite.rs");
    include!("physics_conformance/friction.rs");
}

#[cfg(feature = "mujoco")]
mod mujoco {
    use super::*;

    /// Which engine this module tests (for the known differences of `friction.rs`).
    const ENGINE: &str = "mujoco";

    /// The backend under test: MuJoCo on the MJCF generated from the robot model.
    fn backend(
        model: &Arc<RobotModel>,
        settings: PhysicsSettings,
        gains: PdGains,
    ) -> Box<dyn Physics> {
        thorarena::sim::physics::make_physics(
            &thorarena::sim::physics::Engine::mujoco_on(None).unwrap(),
            model.clone(),
            settings,
            gains,
        )
        .unwrap()
    }

    include!("physics_conformance/suite.rs");
    include!("physics_conformance/friction.rs");
}
