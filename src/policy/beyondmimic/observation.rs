//! The BeyondMimic family's observation: a list of terms, each built here from the
//! benchmark's signals — the one place both the 160-term (mjlab, whole_body_tracking) and
//! the 154-term (holosoma: no anchor position, no base linear velocity) layouts are made.
//!
//! Terms (policy joint order, float32, no scaling):
//!
//! ```text
//! command              reference joint positions ++ joint velocities          2n
//! motion_anchor_pos_b  reference anchor body position in the robot anchor frame 3
//! motion_anchor_ori_b  reference anchor orientation in the robot anchor frame:
//!                      first two columns of the rotation, row by row          6
//! base_lin_vel         root linear velocity, root frame                       3
//! base_ang_vel         root angular velocity, root frame                      3
//! joint_pos            q − the policy's default pose                          n
//! joint_vel            q̇                                                      n
//! actions              the policy's last raw action (0 at an episode's start)  n
//! ```
//!
//! Sources: mjlab `src/mjlab/tasks/tracking/mdp/observations.py` (anchor terms as
//! `subtract_frame_transforms(robot_anchor, reference_anchor)`, `mat[..., :2]`), holosoma
//! `inference/policies/wbt.py:262-293` (the same terms under the names `motion_command`,
//! `motion_ref_ori_b`, `dof_pos`, `dof_vel`, concatenated in alphabetical order of those
//! names). The order of the terms is the file's or the profile's; nothing here sorts. The anchor body's pose comes from forward
//! kinematics of the robot model, for the robot from its root pose and q, for the reference
//! from its root pose and joint positions.

use crate::motion::ReferenceFrame;
use crate::policy::Observation;
use crate::robot::{forward_kinematics, frame_pose, RobotModel};
use nalgebra::{Isometry3, Matrix3};

/// One observation term.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Term {
    /// Reference joint positions ++ velocities.
    Command,
    /// Reference anchor position in the robot anchor frame.
    AnchorPos,
    /// Reference anchor orientation in the robot anchor frame (6).
    AnchorOri,
    /// Root linear velocity in the root frame.
    BaseLinVel,
    /// Root angular velocity in the root frame.
    BaseAngVel,
    /// Joint positions relative to the policy's default pose.
    JointPos,
    /// Joint velocities.
    JointVel,
    /// The policy's last raw action.
    Actions,
}

/// mjlab's and whole_body_tracking's G1 tracking observation (160 for 29 joints).
pub const LAYOUT_160: [Term; 8] = [
    Term::Command,
    Term::AnchorPos,
    Term::AnchorOri,
    Term::BaseLinVel,
    Term::BaseAngVel,
    Term::JointPos,
    Term::JointVel,
    Term::Actions,
];

/// holosoma's `wbt` observation (154 for 29 joints): its terms (`actions`,
/// `base_ang_vel`, `dof_pos`, `dof_vel`, `motion_command`, `motion_ref_ori_b`) in
/// alphabetical order of their names, as holosoma concatenates every observation group.
pub const LAYOUT_154: [Term; 6] = [
    Term::Actions,
    Term::BaseAngVel,
    Term::JointPos,
    Term::JointVel,
    Term::Command,
    Term::AnchorOri,
];

/// mjlab's G1 tracking observation without state estimation (154 for 29 joints): the
/// 160-term layout less the anchor position and the base linear velocity, in the same
/// order (mjlab `src/mjlab/tasks/tracking/config/g1/env_cfgs.py`, the variant without
/// state estimation; Unitree's mimic exports use this order too).
pub const LAYOUT_154_MJLAB: [Term; 6] = [
    Term::Command,
    Term::AnchorOri,
    Term::BaseAngVel,
    Term::JointPos,
    Term::JointVel,
    Term::Actions,
];

/// Every layout a network without `observation_names` might have been trained with,
/// named for the error that lists them. Two of them are 154 wide for 29 joints, so a
/// width alone never picks one: the file's metadata or the profile must say.
pub const KNOWN_LAYOUTS: [(&str, &[Term]); 3] = [
    ("mjlab / whole_body_tracking", &LAYOUT_160),
    ("holosoma wbt (terms sorted by name)", &LAYOUT_154),
    ("mjlab without state estimation", &LAYOUT_154_MJLAB),
];

impl Term {
    /// The term a name in `observation_names` (mjlab's, whole_body_tracking's or
    /// holosoma's spelling) stands for.
    pub fn parse(name: &str) -> Option<Self> {
        Some(match name.trim() {
            "command" | "motion_command" => Self::Command,
            "motion_anchor_pos_b" | "motion_ref_pos_b" => Self::AnchorPos,
            "motion_anchor_ori_b" | "motion_ref_ori_b" => Self::AnchorOri,
            "base_lin_vel" => Self::BaseLinVel,
            "base_ang_vel" => Self::BaseAngVel,
            "joint_pos" | "dof_pos" => Self::JointPos,
            "joint_vel" | "dof_vel" => Self::JointVel,
            "actions" | "last_action" => Self::Actions,
            _ => return None,
        })
    }

    /// Its name in mjlab's spelling (what a profile's `observation_names` may say).
    pub fn name(self) -> &'static str {
        match self {
            Self::Command => "command",
            Self::AnchorPos => "motion_anchor_pos_b",
            Self::AnchorOri => "motion_anchor_ori_b",
            Self::BaseLinVel => "base_lin_vel",
            Self::BaseAngVel => "base_ang_vel",
            Self::JointPos => "joint_pos",
            Self::JointVel => "joint_vel",
            Self::Actions => "actions",
        }
    }

    /// Width for `n` joints.
    pub fn width(self, n: usize) -> usize {
        match self {
            Self::Command => 2 * n,
            Self::AnchorPos | Self::BaseLinVel | Self::BaseAngVel => 3,
            Self::AnchorOri => 6,
            Self::JointPos | Self::JointVel | Self::Actions => n,
        }
    }
}

/// Width of a layout for `n` joints.
pub fn layout_width(terms: &[Term], n: usize) -> usize {
    terms.iter().map(|t| t.width(n)).sum()
}

/// Everything the observation needs besides one environment's signals.
#[derive(Debug, Clone)]
pub struct ObservationSpec {
    /// Terms in order.
    pub terms: Vec<Term>,
    /// Canonical index of each policy joint (`canonical[to_canonical[i]]` is policy joint i).
    pub to_canonical: Vec<usize>,
    /// The policy's default pose, policy order, rad (zero of `joint_pos`).
    pub default_pos: Vec<f64>,
    /// Frame index of the anchor body in the robot model.
    pub anchor_frame: usize,
}

/// Reused buffers for forward kinematics.
#[derive(Debug, Default, Clone)]
pub struct Scratch {
    robot: Vec<Isometry3<f64>>,
    reference: Vec<Isometry3<f64>>,
}

/// The reference anchor's pose in the robot anchor's frame: position (m) and rotation.
pub fn reference_anchor_in_robot_anchor(
    robot: &RobotModel,
    anchor_frame: usize,
    obs: &Observation,
    reference: &ReferenceFrame,
    scratch: &mut Scratch,
) -> Isometry3<f64> {
    forward_kinematics(robot, &obs.root.world_from_root, &obs.q, &mut scratch.robot);
    forward_kinematics(
        robot,
        &reference.world_from_root,
        &reference.joint_pos,
        &mut scratch.reference,
    );
    let robot_anchor = frame_pose(robot, &scratch.robot, anchor_frame);
    let reference_anchor = frame_pose(robot, &scratch.reference, anchor_frame);
    robot_anchor.inverse() * reference_anchor
}

/// Builds the observation of one environment into `out` (cleared first). `last_action`
/// is the policy's last raw action in its own order; `reference` is the reference frame
/// at the current step.
pub fn build_observation(
    spec: &ObservationSpec,
    robot: &RobotModel,
    obs: &Observation,
    reference: &ReferenceFrame,
    last_action: &[f64],
    scratch: &mut Scratch,
    out: &mut Vec<f32>,
) {
    out.clear();
    let p = &spec.to_canonical;
    let mut anchor: Option<Isometry3<f64>> = None;
    let mut anchor_b = |scratch: &mut Scratch| {
        *anchor.get_or_insert_with(|| {
            reference_anchor_in_robot_anchor(robot, spec.anchor_frame, obs, reference, scratch)
        })
    };
    let push = |out: &mut Vec<f32>, v: f64| out.push(v as f32);
    for term in &spec.terms {
        match term {
            Term::Command => {
                p.iter().for_each(|&c| push(out, reference.joint_pos[c]));
                p.iter().for_each(|&c| push(out, reference.joint_vel[c]));
            }
            Term::AnchorPos => {
                let t = anchor_b(scratch).translation.vector;
                t.iter().for_each(|&v| push(out, v));
            }
            Term::AnchorOri => {
                let m: Matrix3<f64> = anchor_b(scratch).rotation.to_rotation_matrix().into_inner();
                for r in 0..3 {
                    push(out, m[(r, 0)]);
                    push(out, m[(r, 1)]);
                }
            }
            Term::BaseLinVel => obs.root.lin_vel_b().iter().for_each(|&v| push(out, v)),
            Term::BaseAngVel => obs.root.ang_vel_b().iter().for_each(|&v| push(out, v)),
            Term::JointPos => p
                .iter()
                .zip(&spec.default_pos)
                .for_each(|(&c, d)| push(out, obs.q[c] - d)),
            Term::JointVel => p.iter().for_each(|&c| push(out, obs.qd[c])),
            Term::Actions => last_action.iter().for_each(|&v| push(out, v)),
        }
    }
}
