//! The BeyondMimic family's observation: a list of terms, each built here from the
//! benchmark's signals — the one place the 160-term (mjlab, whole_body_tracking), the
//! 154-term (holosoma; mjlab without state estimation) and the 132-term (wbc-mjlab's
//! general tracker) layouts are made.
//!
//! Terms (policy joint order, float32, no scaling):
//!
//! ```text
//! command              reference joint positions ++ joint velocities          2n
//! motion_anchor_pos_b  reference anchor body position in the robot anchor frame 3
//! motion_anchor_ori_b  reference anchor orientation in the robot anchor frame:
//!                      first two columns of the rotation, row by row          6
//! ref_base_height      reference anchor height, world z, m                    1
//! ref_base_lin_vel_b   reference anchor linear velocity, reference anchor frame 3
//! ref_base_ang_vel_b   reference anchor angular velocity, reference anchor frame 3
//! ref_gravity_b        gravity direction (0, 0, −1) in the reference anchor frame 3
//! ref_joint_pos        reference joint positions (absolute, rad)              n
//! ref_joint_vel        reference joint velocities                             n
//! base_lin_vel         root linear velocity, root frame                       3
//! base_ang_vel         root angular velocity, root frame                      3
//! projected_gravity    gravity direction in the root frame                    3
//! joint_pos            q − the policy's default pose                          n
//! joint_vel            q̇                                                      n
//! actions              the policy's last raw action (0 at an episode's start)  n
//! ```
//!
//! Sources: mjlab `src/mjlab/tasks/tracking/mdp/observations.py` (anchor terms as
//! `subtract_frame_transforms(robot_anchor, reference_anchor)`, `mat[..., :2]`), holosoma
//! `inference/policies/wbt.py:262-293` (the same terms under the names `motion_command`,
//! `motion_ref_ori_b`, `dof_pos`, `dof_vel`, concatenated in alphabetical order of those
//! names), wbc-mjlab/wbc-g1-deploy at 066ab157 (`src/WbcMotionLoader.cpp`: the `ref_*`
//! terms as the inverse rotation of the reference anchor applied to its world velocities
//! and to (0, 0, −1), the height as the anchor's z less an environment origin of 0;
//! `src/wbc_tracking_params.cpp`: its `joint_pos` is relative to the default pose). The
//! order of the terms is the file's or the profile's; nothing here sorts. The anchor
//! body's pose comes from forward kinematics of the robot model, for the robot from its
//! root pose and q, for the reference from its root pose and joint positions; the
//! reference anchor's velocities from the reference's root and joint velocities through
//! the same chain ([`frame_velocity_w`]).

use crate::policy::Observation;
use crate::sim::motion::ReferenceFrame;
use crate::sim::robot::{forward_kinematics, frame_pose, frame_velocity_w, RobotModel};
use nalgebra::{Isometry3, Matrix3, Vector3};

/// One observation term.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Term {
    /// Reference joint positions ++ velocities.
    Command,
    /// Reference anchor position in the robot anchor frame.
    AnchorPos,
    /// Reference anchor orientation in the robot anchor frame (6).
    AnchorOri,
    /// Reference anchor height above the world's ground, m.
    RefAnchorHeight,
    /// Reference anchor linear velocity in the reference anchor frame.
    RefAnchorLinVel,
    /// Reference anchor angular velocity in the reference anchor frame.
    RefAnchorAngVel,
    /// Gravity direction in the reference anchor frame.
    RefGravity,
    /// Reference joint positions (absolute).
    RefJointPos,
    /// Reference joint velocities.
    RefJointVel,
    /// Root linear velocity in the root frame.
    BaseLinVel,
    /// Root angular velocity in the root frame.
    BaseAngVel,
    /// Gravity direction in the root frame.
    ProjectedGravity,
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

/// wbc-mjlab's general G1 tracker (132 for 29 joints): five reference terms of the
/// `torso_link` anchor, then the robot's (wbc-mjlab/wbc-g1-deploy at 066ab157,
/// `config/policy/wbc/params/config.yaml` `tracking.actor_observation_names`).
pub const LAYOUT_132_WBC: [Term; 10] = [
    Term::RefAnchorHeight,
    Term::RefAnchorLinVel,
    Term::RefAnchorAngVel,
    Term::RefGravity,
    Term::RefJointPos,
    Term::BaseAngVel,
    Term::ProjectedGravity,
    Term::JointPos,
    Term::JointVel,
    Term::Actions,
];

/// Every layout a network without `observation_names` might have been trained with,
/// named for the error that lists them. Two of them are 154 wide for 29 joints, so a
/// width alone never picks one: the file's metadata or the profile must say.
pub const KNOWN_LAYOUTS: [(&str, &[Term]); 4] = [
    ("mjlab / whole_body_tracking", &LAYOUT_160),
    ("holosoma wbt (terms sorted by name)", &LAYOUT_154),
    ("mjlab without state estimation", &LAYOUT_154_MJLAB),
    ("wbc-mjlab general tracker", &LAYOUT_132_WBC),
];

impl Term {
    /// Every term, in the order the module's table lists them.
    pub const ALL: [Term; 15] = [
        Self::Command,
        Self::AnchorPos,
        Self::AnchorOri,
        Self::RefAnchorHeight,
        Self::RefAnchorLinVel,
        Self::RefAnchorAngVel,
        Self::RefGravity,
        Self::RefJointPos,
        Self::RefJointVel,
        Self::BaseLinVel,
        Self::BaseAngVel,
        Self::ProjectedGravity,
        Self::JointPos,
        Self::JointVel,
        Self::Actions,
    ];

    /// The term a name in `observation_names` (mjlab's, whole_body_tracking's or
    /// holosoma's spelling) stands for.
    pub fn parse(name: &str) -> Option<Self> {
        Some(match name.trim() {
            "command" | "motion_command" => Self::Command,
            "motion_anchor_pos_b" | "motion_ref_pos_b" => Self::AnchorPos,
            "motion_anchor_ori_b" | "motion_ref_ori_b" => Self::AnchorOri,
            "ref_base_height" => Self::RefAnchorHeight,
            "ref_base_lin_vel_b" => Self::RefAnchorLinVel,
            "ref_base_ang_vel_b" => Self::RefAnchorAngVel,
            "ref_gravity_b" => Self::RefGravity,
            "ref_joint_pos" => Self::RefJointPos,
            "ref_joint_vel" => Self::RefJointVel,
            "base_lin_vel" => Self::BaseLinVel,
            "base_ang_vel" => Self::BaseAngVel,
            "projected_gravity" => Self::ProjectedGravity,
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
            Self::RefAnchorHeight => "ref_base_height",
            Self::RefAnchorLinVel => "ref_base_lin_vel_b",
            Self::RefAnchorAngVel => "ref_base_ang_vel_b",
            Self::RefGravity => "ref_gravity_b",
            Self::RefJointPos => "ref_joint_pos",
            Self::RefJointVel => "ref_joint_vel",
            Self::BaseLinVel => "base_lin_vel",
            Self::BaseAngVel => "base_ang_vel",
            Self::ProjectedGravity => "projected_gravity",
            Self::JointPos => "joint_pos",
            Self::JointVel => "joint_vel",
            Self::Actions => "actions",
        }
    }

    /// Width for `n` joints.
    pub fn width(self, n: usize) -> usize {
        match self {
            Self::Command => 2 * n,
            Self::RefAnchorHeight => 1,
            Self::AnchorPos
            | Self::RefAnchorLinVel
            | Self::RefAnchorAngVel
            | Self::RefGravity
            | Self::BaseLinVel
            | Self::BaseAngVel
            | Self::ProjectedGravity => 3,
            Self::AnchorOri => 6,
            Self::RefJointPos
            | Self::RefJointVel
            | Self::JointPos
            | Self::JointVel
            | Self::Actions => n,
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

/// The reference anchor as the `ref_*` terms see it: its world pose and its world-frame
/// linear and angular velocity.
#[derive(Debug, Clone, Copy)]
pub struct ReferenceAnchor {
    /// World pose of the anchor frame.
    pub world_from_anchor: Isometry3<f64>,
    /// Linear velocity of its origin, world frame, m/s.
    pub lin_vel_w: Vector3<f64>,
    /// Angular velocity, world frame, rad/s.
    pub ang_vel_w: Vector3<f64>,
}

impl ReferenceAnchor {
    /// The reference anchor at `reference` (forward kinematics into `scratch`).
    pub fn of(
        robot: &RobotModel,
        anchor_frame: usize,
        reference: &ReferenceFrame,
        scratch: &mut Scratch,
    ) -> Self {
        forward_kinematics(
            robot,
            &reference.world_from_root,
            &reference.joint_pos,
            &mut scratch.reference,
        );
        let (lin_vel_w, ang_vel_w) = frame_velocity_w(
            robot,
            &scratch.reference,
            &reference.root_lin_vel_w,
            &reference.root_ang_vel_w,
            &reference.joint_vel,
            anchor_frame,
        );
        Self {
            world_from_anchor: frame_pose(robot, &scratch.reference, anchor_frame),
            lin_vel_w,
            ang_vel_w,
        }
    }

    /// A world vector in the anchor's frame.
    fn in_anchor(&self, v: &Vector3<f64>) -> Vector3<f64> {
        self.world_from_anchor.rotation.inverse_transform_vector(v)
    }
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
    let has = |f: fn(&Term) -> bool| spec.terms.iter().any(f);
    let anchor_b = has(|t| matches!(t, Term::AnchorPos | Term::AnchorOri)).then(|| {
        reference_anchor_in_robot_anchor(robot, spec.anchor_frame, obs, reference, scratch)
    });
    let ref_anchor = has(|t| {
        matches!(
            t,
            Term::RefAnchorHeight
                | Term::RefAnchorLinVel
                | Term::RefAnchorAngVel
                | Term::RefGravity
        )
    })
    .then(|| ReferenceAnchor::of(robot, spec.anchor_frame, reference, scratch));
    let push = |out: &mut Vec<f32>, v: f64| out.push(v as f32);
    let push3 = |out: &mut Vec<f32>, v: Vector3<f64>| v.iter().for_each(|&x| push(out, x));
    for term in &spec.terms {
        match term {
            Term::Command => {
                p.iter().for_each(|&c| push(out, reference.joint_pos[c]));
                p.iter().for_each(|&c| push(out, reference.joint_vel[c]));
            }
            Term::AnchorPos => push3(out, anchor_b.expect("computed").translation.vector),
            Term::AnchorOri => {
                let m: Matrix3<f64> = anchor_b
                    .expect("computed")
                    .rotation
                    .to_rotation_matrix()
                    .into_inner();
                for r in 0..3 {
                    push(out, m[(r, 0)]);
                    push(out, m[(r, 1)]);
                }
            }
            Term::RefAnchorHeight => push(
                out,
                ref_anchor
                    .expect("computed")
                    .world_from_anchor
                    .translation
                    .z,
            ),
            Term::RefAnchorLinVel => {
                let a = ref_anchor.expect("computed");
                push3(out, a.in_anchor(&a.lin_vel_w));
            }
            Term::RefAnchorAngVel => {
                let a = ref_anchor.expect("computed");
                push3(out, a.in_anchor(&a.ang_vel_w));
            }
            Term::RefGravity => push3(out, ref_anchor.expect("computed").in_anchor(&-Vector3::z())),
            Term::RefJointPos => p.iter().for_each(|&c| push(out, reference.joint_pos[c])),
            Term::RefJointVel => p.iter().for_each(|&c| push(out, reference.joint_vel[c])),
            Term::BaseLinVel => push3(out, obs.root.lin_vel_b()),
            Term::BaseAngVel => push3(out, obs.root.ang_vel_b()),
            Term::ProjectedGravity => push3(out, obs.root.projected_gravity_b()),
            Term::JointPos => p
                .iter()
                .zip(&spec.default_pos)
                .for_each(|(&c, d)| push(out, obs.q[c] - d)),
            Term::JointVel => p.iter().for_each(|&c| push(out, obs.qd[c])),
            Term::Actions => last_action.iter().for_each(|&v| push(out, v)),
        }
    }
}
