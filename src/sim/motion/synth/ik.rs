//! Damped-least-squares inverse kinematics on the robot model.
//!
//! Engine-free like forward kinematics: the Jacobian comes from the body poses of
//! [`forward_kinematics`]. For a revolute joint with world axis `a` at world position `p`
//! the column is `[a × (p_end − p); a]`. Each frame is warm-started from the previous
//! one, so a handful of Gauss–Newton steps suffice and consecutive frames stay on the same
//! branch of the solution (no elbow or knee flips between frames).

use crate::sim::robot::{forward_kinematics, frame_pose, RobotModel};
use nalgebra::{DMatrix, DVector, Isometry3, UnitQuaternion, Vector3};

/// A kinematic chain: the joints IK may move and the frame it places.
#[derive(Debug, Clone)]
pub struct Chain {
    /// Canonical joint indices, root side first.
    pub joints: Vec<usize>,
    /// The end frame (`RobotModel::frames` index).
    pub frame: usize,
}

/// What the chain's end frame should reach, world frame.
#[derive(Debug, Clone, Copy)]
pub struct Target {
    /// Position of the end frame's origin, m.
    pub pos: Vector3<f64>,
    /// Orientation of the end frame; `None` for a 3-D position target.
    pub rot: Option<UnitQuaternion<f64>>,
}

/// Solver settings.
#[derive(Debug, Clone, Copy)]
pub struct IkParams {
    /// Damping λ of `Jᵀ(JJᵀ + λ²I)⁻¹`; keeps steps bounded near singularities
    /// (a stretched knee or elbow), m.
    pub damping: f64,
    /// Iteration cap per solve.
    pub max_iter: usize,
    /// Stop when the position error is below this, m.
    pub tol_pos_m: f64,
    /// Stop when the orientation error is below this, rad.
    pub tol_rot_rad: f64,
    /// Joints are kept this far inside their URDF limits, rad (the validity rule asks for
    /// ≥ 0.02 rad; a little more survives the float32 storage and interpolation).
    pub limit_margin_rad: f64,
    /// Gain of the null-space pull toward a nominal posture (redundant arms only).
    pub null_gain: f64,
}

impl Default for IkParams {
    fn default() -> Self {
        Self {
            damping: 0.01,
            max_iter: 60,
            tol_pos_m: 2e-5,
            tol_rot_rad: 2e-5,
            limit_margin_rad: 0.03,
            null_gain: 0.1,
        }
    }
}

/// Remaining error after a solve.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Residual {
    /// Position error, m.
    pub pos_m: f64,
    /// Orientation error (0 for position targets), rad.
    pub rot_rad: f64,
    /// Iterations used.
    pub iterations: usize,
}

/// Moves `q[chain.joints]` so that the chain's end frame reaches `target`, with the root
/// fixed at `root` and every other joint unchanged. `nominal` (one value per chain joint)
/// is a posture the redundant directions drift toward. `poses` is FK scratch space.
#[allow(clippy::too_many_arguments)] // one call site per limb; a struct would only rename them
pub fn solve(
    robot: &RobotModel,
    root: &Isometry3<f64>,
    q: &mut [f64],
    chain: &Chain,
    target: &Target,
    nominal: Option<&[f64]>,
    params: &IkParams,
    poses: &mut Vec<Isometry3<f64>>,
) -> Residual {
    let n = chain.joints.len();
    let m = if target.rot.is_some() { 6 } else { 3 };
    let mut res = Residual::default();
    for it in 0..=params.max_iter {
        forward_kinematics(robot, root, q, poses);
        let end = frame_pose(robot, poses, chain.frame);
        let p_end = end.translation.vector;
        let e_pos = target.pos - p_end;
        let e_rot = target.rot.map_or(Vector3::zeros(), |r| {
            (r * end.rotation.inverse()).scaled_axis()
        });
        res = Residual {
            pos_m: e_pos.norm(),
            rot_rad: e_rot.norm(),
            iterations: it,
        };
        if (res.pos_m < params.tol_pos_m && res.rot_rad < params.tol_rot_rad)
            || it == params.max_iter
        {
            break;
        }
        let mut jac = DMatrix::<f64>::zeros(m, n);
        for (c, &j) in chain.joints.iter().enumerate() {
            let body = &poses[robot.joints[j].body];
            let axis = body.rotation * robot.bodies[robot.joints[j].body].axis.into_inner();
            let lin = axis.cross(&(p_end - body.translation.vector));
            jac.fixed_view_mut::<3, 1>(0, c).copy_from(&lin);
            if m == 6 {
                jac.fixed_view_mut::<3, 1>(3, c).copy_from(&axis);
            }
        }
        // Bounded steps: a far target is approached in pieces, which keeps the
        // linearisation honest.
        let mut err = DVector::<f64>::zeros(m);
        err.fixed_rows_mut::<3>(0)
            .copy_from(&(e_pos * (0.05 / res.pos_m.max(0.05))));
        if m == 6 {
            err.fixed_rows_mut::<3>(3)
                .copy_from(&(e_rot * (0.3 / res.rot_rad.max(0.3))));
        }
        let jjt = &jac * jac.transpose()
            + DMatrix::<f64>::identity(m, m) * (params.damping * params.damping);
        let Some(inv) = jjt.try_inverse() else { break };
        let pinv = jac.transpose() * inv;
        let mut dq = &pinv * err;
        if let Some(nom) = nominal {
            let pull = DVector::from_iterator(
                n,
                chain
                    .joints
                    .iter()
                    .zip(nom)
                    .map(|(&j, v)| params.null_gain * (v - q[j])),
            );
            let null = DMatrix::<f64>::identity(n, n) - &pinv * &jac;
            dq += null * pull;
        }
        for (c, &j) in chain.joints.iter().enumerate() {
            let joint = &robot.joints[j];
            q[j] = (q[j] + dq[c]).clamp(
                joint.lower_rad + params.limit_margin_rad,
                joint.upper_rad - params.limit_margin_rad,
            );
        }
    }
    res
}

/// The joints between a frame and the root, root side first, minus those `exclude` keeps.
pub fn chain_to_root(robot: &RobotModel, frame: usize, exclude: impl Fn(usize) -> bool) -> Chain {
    let mut joints = Vec::new();
    let mut body = Some(robot.frames[frame].body);
    while let Some(b) = body {
        if let Some(j) = robot.bodies[b].joint {
            if !exclude(j) {
                joints.push(j);
            }
        }
        body = robot.bodies[b].parent;
    }
    joints.reverse();
    Chain { joints, frame }
}
