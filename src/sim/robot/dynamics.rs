//! Inverse dynamics of the floating-base robot, engine-free: recursive Newton–Euler on the
//! model's kinematic tree, in the world frame.
//!
//! Given a state (root pose and velocity, joint angles and velocities) and its
//! accelerations, it returns the wrench the world must apply at the root — with the
//! robot standing, the ground's — and the joint torques that produce the motion, after
//! the external forces given (the replayed hand forces) have done their part. The data
//! check (`sim::motion::check`) reads the root wrench as the ground reaction a reference
//! motion needs; with the `mujoco` feature `tests/inverse_dynamics.rs` checks both against
//! MuJoCo's `mj_inverse` with contacts off.
//!
//! Conventions: every vector in the world frame; a body's frame coincides with its joint's
//! (URDF), so a revolute joint never moves its body's origin; the root's velocity and
//! acceleration are those of the root frame's origin (not its centre of mass). Joint
//! torques include the armature (reflected rotor inertia) times the joint acceleration,
//! as MuJoCo's `dof_armature` does; no damping or friction enters.

use super::kinematics::forward_kinematics;
use super::model::RobotModel;
use nalgebra::{Isometry3, Point3, Vector3};

/// A floating-base state with its accelerations, everything in the world frame.
#[derive(Debug, Clone)]
pub struct MotionState<'a> {
    /// Root pose.
    pub world_from_root: Isometry3<f64>,
    /// Linear velocity of the root frame's origin, m/s.
    pub root_lin_vel_w: Vector3<f64>,
    /// Root angular velocity, rad/s.
    pub root_ang_vel_w: Vector3<f64>,
    /// Linear acceleration of the root frame's origin, m/s².
    pub root_lin_acc_w: Vector3<f64>,
    /// Root angular acceleration, rad/s².
    pub root_ang_acc_w: Vector3<f64>,
    /// Joint angles, canonical order, rad.
    pub q: &'a [f64],
    /// Joint velocities, rad/s.
    pub qd: &'a [f64],
    /// Joint accelerations, rad/s².
    pub qdd: &'a [f64],
}

/// A force applied by the environment at a point of a body, world frame.
#[derive(Debug, Clone, Copy)]
pub struct PointForce {
    /// The body it acts on.
    pub body: usize,
    /// Where it acts, world frame, m.
    pub point_w: Point3<f64>,
    /// The force, N.
    pub force_w: Vector3<f64>,
}

/// What the motion needs beyond the given external forces.
#[derive(Debug, Clone)]
pub struct InverseDynamics {
    /// Force the world must apply on the root, N.
    pub root_force_w: Vector3<f64>,
    /// Moment the world must apply on the root, about the root frame's origin, N·m.
    pub root_moment_w: Vector3<f64>,
    /// Torque each joint must apply (canonical order), N·m.
    pub joint_torque_nm: Vec<f64>,
    /// Root frame origin the moment is taken about, world frame, m.
    pub root_origin_w: Point3<f64>,
}

impl InverseDynamics {
    /// The root wrench's moment about the world origin, N·m: `M_o = M_root + p_root × F`.
    pub fn root_moment_about_origin_w(&self) -> Vector3<f64> {
        self.root_moment_w + self.root_origin_w.coords.cross(&self.root_force_w)
    }
}

/// Inverse dynamics of `state` under `gravity_w` (m/s², e.g. (0, 0, −9.81)) with the
/// external forces `external` (e.g. the hand forces a motion is recorded with).
///
/// `world_from_body` is scratch space for the body poses, reused to avoid allocation.
pub fn inverse_dynamics(
    model: &RobotModel,
    state: &MotionState<'_>,
    gravity_w: &Vector3<f64>,
    external: &[PointForce],
    world_from_body: &mut Vec<Isometry3<f64>>,
) -> InverseDynamics {
    let n_bodies = model.bodies.len();
    forward_kinematics(model, &state.world_from_root, state.q, world_from_body);
    // Forward pass: each body's angular velocity and acceleration and its origin's linear
    // acceleration; then the wrench about its centre of mass that its own motion needs.
    let mut omega = vec![Vector3::zeros(); n_bodies];
    let mut alpha = vec![Vector3::zeros(); n_bodies];
    let mut acc = vec![Vector3::zeros(); n_bodies];
    // Per body: the force and the moment about the body origin that its subtree needs.
    let mut force = vec![Vector3::zeros(); n_bodies];
    let mut moment = vec![Vector3::zeros(); n_bodies];
    for (i, body) in model.bodies.iter().enumerate() {
        let pose = &world_from_body[i];
        let origin = pose.translation.vector;
        match (body.parent, body.joint) {
            (Some(p), Some(j)) => {
                let r = origin - world_from_body[p].translation.vector;
                let axis_w = pose.rotation * body.axis.into_inner();
                let (wp, ap) = (omega[p], alpha[p]);
                omega[i] = wp + axis_w * state.qd[j];
                alpha[i] = ap + wp.cross(&(axis_w * state.qd[j])) + axis_w * state.qdd[j];
                acc[i] = acc[p] + ap.cross(&r) + wp.cross(&wp.cross(&r));
            }
            _ => {
                omega[i] = state.root_ang_vel_w;
                alpha[i] = state.root_ang_acc_w;
                acc[i] = state.root_lin_acc_w;
            }
        }
        let c = pose.rotation * body.com_b;
        let acc_com = acc[i] + alpha[i].cross(&c) + omega[i].cross(&omega[i].cross(&c));
        let rot = pose.rotation.to_rotation_matrix();
        let inertia_w = rot.matrix() * body.inertia_kgm2 * rot.matrix().transpose();
        let f = body.mass_kg * (acc_com - gravity_w);
        let n = inertia_w * alpha[i] + omega[i].cross(&(inertia_w * omega[i]));
        force[i] = f;
        moment[i] = n + c.cross(&f);
    }
    for e in external {
        let r = e.point_w.coords - world_from_body[e.body].translation.vector;
        force[e.body] -= e.force_w;
        moment[e.body] -= r.cross(&e.force_w);
    }
    // Backward pass: children's wrenches move to their parent's origin.
    let mut joint_torque_nm = vec![0.0; model.n_joints()];
    for i in (0..n_bodies).rev() {
        let body = &model.bodies[i];
        if let (Some(p), Some(j)) = (body.parent, body.joint) {
            let axis_w = world_from_body[i].rotation * body.axis.into_inner();
            joint_torque_nm[j] =
                axis_w.dot(&moment[i]) + model.joints[j].armature_kgm2 * state.qdd[j];
            let r = world_from_body[i].translation.vector - world_from_body[p].translation.vector;
            let (f, m) = (force[i], moment[i]);
            force[p] += f;
            moment[p] += m + r.cross(&f);
        }
    }
    InverseDynamics {
        root_force_w: force[0],
        root_moment_w: moment[0],
        joint_torque_nm,
        root_origin_w: Point3::from(world_from_body[0].translation.vector),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::robot::{center_of_mass, load_bundled};

    const G: Vector3<f64> = Vector3::new(0.0, 0.0, -9.81);

    fn still<'a>(q: &'a [f64], zeros: &'a [f64]) -> MotionState<'a> {
        MotionState {
            world_from_root: Isometry3::translation(0.3, -0.2, 0.79),
            root_lin_vel_w: Vector3::zeros(),
            root_ang_vel_w: Vector3::zeros(),
            root_lin_acc_w: Vector3::zeros(),
            root_ang_acc_w: Vector3::zeros(),
            q,
            qd: zeros,
            qdd: zeros,
        }
    }

    #[test]
    fn a_still_robot_needs_its_weight_under_its_centre_of_mass() {
        let g1 = load_bundled("g1_29dof").unwrap();
        let zeros = vec![0.0; g1.n_joints()];
        let pose = g1.default_pose();
        let state = still(&pose, &zeros);
        let mut poses = Vec::new();
        let id = inverse_dynamics(&g1, &state, &G, &[], &mut poses);
        let weight = g1.total_mass_kg() * 9.81;
        assert!((id.root_force_w - Vector3::new(0.0, 0.0, weight)).norm() < 1e-9);
        // The moment about the origin of a vertical force W at the CoM: (y·W, −x·W, 0).
        let com = center_of_mass(&g1, &poses);
        let m = id.root_moment_about_origin_w();
        assert!((m.x - com.y * weight).abs() < 1e-9, "{m:?} {com:?}");
        assert!((m.y + com.x * weight).abs() < 1e-9, "{m:?} {com:?}");
    }

    #[test]
    fn a_falling_robot_needs_nothing_from_the_ground() {
        let g1 = load_bundled("g1_29dof").unwrap();
        let zeros = vec![0.0; g1.n_joints()];
        let pose = g1.default_pose();
        let mut state = still(&pose, &zeros);
        state.root_lin_acc_w = G;
        let id = inverse_dynamics(&g1, &state, &G, &[], &mut Vec::new());
        assert!(id.root_force_w.norm() < 1e-9);
        assert!(id.root_moment_w.norm() < 1e-9);
        assert!(id.joint_torque_nm.iter().all(|t| t.abs() < 1e-9));
    }

    #[test]
    fn a_hand_force_is_taken_off_the_ground_wrench() {
        let g1 = load_bundled("g1_29dof").unwrap();
        let zeros = vec![0.0; g1.n_joints()];
        let pose = g1.default_pose();
        let state = still(&pose, &zeros);
        let mut poses = Vec::new();
        let alone = inverse_dynamics(&g1, &state, &G, &[], &mut poses);
        let hand = g1.frames[g1.hands[0].frame].body;
        let push = PointForce {
            body: hand,
            point_w: Point3::from(poses[hand].translation.vector),
            force_w: Vector3::new(30.0, 0.0, 20.0),
        };
        let pushed = inverse_dynamics(&g1, &state, &G, &[push], &mut poses);
        assert!((alone.root_force_w - pushed.root_force_w - push.force_w).norm() < 1e-9);
        let dm = alone.root_moment_about_origin_w() - pushed.root_moment_about_origin_w();
        assert!((dm - push.point_w.coords.cross(&push.force_w)).norm() < 1e-9);
        // The arm holds the hand's load: its shoulder pitch torque changes.
        let shoulder = g1.joint_index("left_shoulder_pitch_joint").unwrap();
        assert!((alone.joint_torque_nm[shoulder] - pushed.joint_torque_nm[shoulder]).abs() > 1.0);
    }
}
