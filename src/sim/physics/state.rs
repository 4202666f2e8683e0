//! Plain data exchanged with a physics backend.

use super::settings::PdForm;
use nalgebra::{Isometry3, Point3, Vector3};

/// Pose and velocity of the root body (the pelvis frame, not its centre of mass).
#[derive(Debug, Clone, PartialEq)]
pub struct RootState {
    /// Root frame in the world.
    pub world_from_root: Isometry3<f64>,
    /// Linear velocity of the root frame origin, world frame, m/s.
    pub lin_vel_w: Vector3<f64>,
    /// Angular velocity, world frame, rad/s.
    pub ang_vel_w: Vector3<f64>,
}

impl RootState {
    /// At rest at a pose.
    pub fn at_rest(world_from_root: Isometry3<f64>) -> Self {
        Self {
            world_from_root,
            lin_vel_w: Vector3::zeros(),
            ang_vel_w: Vector3::zeros(),
        }
    }

    /// Linear velocity in the root (base) frame, m/s.
    pub fn lin_vel_b(&self) -> Vector3<f64> {
        self.world_from_root
            .rotation
            .inverse_transform_vector(&self.lin_vel_w)
    }

    /// Angular velocity in the root (base) frame, rad/s — what an IMU on the pelvis reads.
    pub fn ang_vel_b(&self) -> Vector3<f64> {
        self.world_from_root
            .rotation
            .inverse_transform_vector(&self.ang_vel_w)
    }

    /// Gravity direction in the base frame (unit vector), as policies observe it.
    pub fn projected_gravity_b(&self) -> Vector3<f64> {
        self.world_from_root
            .rotation
            .inverse_transform_vector(&-Vector3::z())
    }
}

/// The full state a reset puts the robot in.
#[derive(Debug, Clone, PartialEq)]
pub struct ResetState {
    /// Root pose and velocity.
    pub root: RootState,
    /// Joint angles, canonical order, rad.
    pub q: Vec<f64>,
    /// Joint velocities, canonical order, rad/s.
    pub qd: Vec<f64>,
}

/// PD gains and torque limits, canonical order.
#[derive(Debug, Clone, PartialEq)]
pub struct PdGains {
    /// Stiffness, N·m/rad.
    pub kp: Vec<f64>,
    /// Damping, N·m·s/rad.
    pub kd: Vec<f64>,
    /// Torque limit applied to the PD torque, N·m.
    pub effort_limit_nm: Vec<f64>,
}

impl PdGains {
    /// The benchmark's PD law for joint `j`, the same on every backend: returns the torque
    /// the engine must apply explicitly and the PD torque to report, N·m. With
    /// [`PdForm::Hybrid`] the clamped spring is explicit and `kd` is the engine's implicit
    /// joint damping, reported here all the same. `feedforward` (N·m, constant over the
    /// step) adds to the spring before the clamp.
    pub(super) fn torque_nm(
        &self,
        form: PdForm,
        j: usize,
        (target, feedforward): (f64, f64),
        q: f64,
        qd: f64,
    ) -> (f64, f64) {
        let (kp, kd, limit) = (self.kp[j], self.kd[j], self.effort_limit_nm[j]);
        let spring = kp * (target - q) + feedforward;
        match form {
            PdForm::Explicit => {
                let tau = (spring - kd * qd).clamp(-limit, limit);
                (tau, tau)
            }
            PdForm::Hybrid => {
                let tau = spring.clamp(-limit, limit);
                (tau, tau - kd * qd)
            }
        }
    }
}

/// Everything a backend reports after a step.
#[derive(Debug, Clone, Default)]
pub struct PhysicsState {
    /// Simulated time since reset, s.
    pub time_s: f64,
    /// Root pose and velocity.
    pub root: Option<RootState>,
    /// Joint angles, rad.
    pub q: Vec<f64>,
    /// Joint velocities, rad/s.
    pub qd: Vec<f64>,
    /// World pose of every body of the model.
    pub world_from_body: Vec<Isometry3<f64>>,
    /// Joint torques of the PD law as applied in the last step (including the damping
    /// part), N·m.
    pub applied_torque_nm: Vec<f64>,
}

/// One point where the ground pushed on the robot during the last physics step.
///
/// Both backends report the same quantities, so traces of one episode on two engines can be
/// laid side by side: where the point is on the body (to follow its slip from the body's
/// motion), and the ground's reaction split into its normal and frictional parts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GroundContact {
    /// Robot body touching the ground (index in the robot model).
    pub body: usize,
    /// Contact point in that body's frame, m.
    pub point_b: Point3<f64>,
    /// Normal force of the ground on the body, N (≥ 0).
    pub normal_n: f64,
    /// Friction force of the ground on the body, world frame, N (in the ground plane).
    pub friction_w: Vector3<f64>,
}

/// A force held on a body until changed or cleared.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExternalForce {
    /// Body index in the robot model.
    pub body: usize,
    /// Force, world frame, N.
    pub force_w: Vector3<f64>,
    /// Application point in the body frame, m (it moves with the body).
    pub point_b: Point3<f64>,
}

impl ExternalForce {
    /// Holds `force` in `held`, replacing a force at the same point of the same body (the
    /// rule of [`super::Physics::set_external_force`], shared by the backends).
    pub(crate) fn hold(held: &mut Vec<ExternalForce>, force: ExternalForce) {
        match held
            .iter_mut()
            .find(|f| f.body == force.body && f.point_b == force.point_b)
        {
            Some(f) => *f = force,
            None => held.push(force),
        }
    }
}
