//! Turns a task plan into joint angles: per frame, the waist is set directly, each foot is
//! placed by 6-D leg IK relative to the planned pelvis, each hand by 3-D arm IK.

use super::ik::{solve, IkParams, Target};
use super::skeleton::Skeleton;
use super::tasks::Plan;
use super::SynthError;
use crate::sim::robot::{forward_kinematics, frame_pose, RobotModel};
use nalgebra::{Isometry3, UnitQuaternion};

/// A leg that misses its foothold by more than this leaves the sole off the ground or
/// sliding: the validity rules allow 5 mm of ground error and 2 mm of sliding.
pub const FOOT_TOL_M: f64 = 5e-4;
/// Foot orientation tolerance (sole level within a fraction of a degree), rad.
pub const FOOT_TOL_RAD: f64 = 5e-3;
/// Hand targets are clamped into reach first, so a larger miss means joint limits bind.
pub const HAND_TOL_M: f64 = 0.03;

/// IK residual statistics of one sequence.
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct IkStats {
    /// Largest foot position residual, m.
    pub foot_pos_max_m: f64,
    /// Largest foot orientation residual, rad.
    pub foot_rot_max_rad: f64,
    /// Mean hand position residual (after clamping into reach), m.
    pub hand_pos_mean_m: f64,
    /// Largest hand position residual, m.
    pub hand_pos_max_m: f64,
    /// Largest distance a hand target was pulled in to stay within reach, m.
    pub hand_clamp_max_m: f64,
    /// Mean IK iterations per solve.
    pub iterations_mean: f64,
}

/// Joint trajectories of a plan plus the hand orientations the forces are rotated by.
#[derive(Debug, Clone)]
pub struct Solved {
    /// Joint angles per frame, canonical order.
    pub joint_pos: Vec<Vec<f64>>,
    /// World orientation of each hand frame per frame.
    pub hand_rot: [Vec<UnitQuaternion<f64>>; 2],
    /// Residuals.
    pub stats: IkStats,
}

/// Solves every frame, warm-starting each from the previous one.
pub fn realize(
    robot: &RobotModel,
    sk: &Skeleton,
    plan: &Plan,
    task: &str,
    sequence: &str,
) -> Result<Solved, SynthError> {
    let params = IkParams::default();
    let mut q = robot.default_pose();
    let mut poses: Vec<Isometry3<f64>> = Vec::new();
    let mut out = Solved {
        joint_pos: Vec::with_capacity(plan.frames.len()),
        hand_rot: [Vec::new(), Vec::new()],
        stats: IkStats::default(),
    };
    let (mut iters, mut solves, mut hand_sum) = (0usize, 0usize, 0.0);
    let fail = |frame: usize, limb: &str, residual: f64| SynthError::IkFailed {
        task: task.to_string(),
        sequence: sequence.to_string(),
        frame,
        limb: limb.to_string(),
        residual_m: residual,
    };
    for (k, f) in plan.frames.iter().enumerate() {
        // The waist is set, not solved: a style's bend can ask more than its joint allows,
        // so it is held inside the limits with the IK's own margin.
        for (j, v) in sk.waist.iter().zip(f.waist) {
            let joint = &robot.joints[*j];
            let m = params.limit_margin_rad;
            q[*j] = v.clamp(joint.lower_rad + m, joint.upper_rad - m);
        }
        for side in 0..2 {
            let target = Target {
                pos: f.feet[side].translation.vector,
                rot: Some(f.feet[side].rotation),
            };
            let r = solve(
                robot,
                &f.pelvis,
                &mut q,
                &sk.legs[side],
                &target,
                None,
                &params,
                &mut poses,
            );
            if r.pos_m > FOOT_TOL_M || r.rot_rad > FOOT_TOL_RAD {
                return Err(fail(
                    k,
                    ["left leg", "right leg"][side],
                    r.pos_m + r.rot_rad,
                ));
            }
            let st = &mut out.stats;
            st.foot_pos_max_m = st.foot_pos_max_m.max(r.pos_m);
            st.foot_rot_max_rad = st.foot_rot_max_rad.max(r.rot_rad);
            iters += r.iterations;
            solves += 1;
        }
        forward_kinematics(robot, &f.pelvis, &q, &mut poses);
        for side in 0..2 {
            let shoulder = poses[sk.shoulder_body[side]].translation.vector;
            let d = f.hands[side] - shoulder;
            let pos = shoulder + d * (sk.reach_m / d.norm().max(sk.reach_m));
            let clamp = (pos - f.hands[side]).norm();
            let target = Target { pos, rot: None };
            let nominal = Some(sk.arm_nominal[side].as_slice());
            let r = solve(
                robot,
                &f.pelvis,
                &mut q,
                &sk.arms[side],
                &target,
                nominal,
                &params,
                &mut poses,
            );
            if r.pos_m > HAND_TOL_M {
                return Err(fail(k, ["left arm", "right arm"][side], r.pos_m));
            }
            let st = &mut out.stats;
            st.hand_pos_max_m = st.hand_pos_max_m.max(r.pos_m);
            st.hand_clamp_max_m = st.hand_clamp_max_m.max(clamp);
            hand_sum += r.pos_m;
            iters += r.iterations;
            solves += 1;
        }
        forward_kinematics(robot, &f.pelvis, &q, &mut poses);
        for side in 0..2 {
            out.hand_rot[side].push(frame_pose(robot, &poses, robot.hands[side].frame).rotation);
        }
        out.joint_pos.push(q.clone());
    }
    out.stats.hand_pos_mean_m = hand_sum / (2 * plan.frames.len()).max(1) as f64;
    out.stats.iterations_mean = iters as f64 / solves.max(1) as f64;
    Ok(out)
}
