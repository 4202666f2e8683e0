//! What the generator needs to know about the robot, measured once by forward kinematics
//! on the default pose: chains, standing height, foot and hand placement, arm reach.

use super::ik::{chain_to_root, Chain};
use super::SynthError;
use crate::sim::robot::{forward_kinematics, frame_pose, lowest_sole_point_z, RobotModel};
use nalgebra::{Isometry3, UnitQuaternion, Vector3};

/// Measured layout of the robot.
#[derive(Debug, Clone)]
pub struct Skeleton {
    /// Leg chains (hip pitch … ankle roll) ending at the ankle-roll frame, left then right.
    pub legs: [Chain; 2],
    /// Arm chains (shoulder … wrist) ending at the hand frame, left then right.
    pub arms: [Chain; 2],
    /// Canonical indices of waist yaw, roll and pitch.
    pub waist: [usize; 3],
    /// Pelvis height with the default pose standing on flat soles, m.
    pub stand_height_m: f64,
    /// Height of the ankle-roll frame above the lowest sole point with a flat foot, m.
    pub ankle_height_m: f64,
    /// Ankle-roll frame orientation relative to a level pelvis in the default pose (the
    /// flat-foot orientation before yaw).
    pub foot_rot: UnitQuaternion<f64>,
    /// Ankle-roll frame lateral offset from the pelvis in the default pose, m (left > 0).
    pub foot_y_m: f64,
    /// Ankle-roll frame forward offset from the pelvis in the default pose, m.
    pub foot_x_m: f64,
    /// Centre of the front sole points (the toe's edge) in the ankle-roll frame, m: a
    /// foot rolling off its toe pitches about the line across the foot through it.
    pub toe_m: Vector3<f64>,
    /// Hand positions in the pelvis frame in the default pose, m.
    pub hand_default: [Vector3<f64>; 2],
    /// Body whose origin is the shoulder centre (shoulder-pitch link), per side.
    pub shoulder_body: [usize; 2],
    /// Farthest a hand may be placed from its shoulder: the summed link offsets of the
    /// default arm shortened to 90 %, so targets stay off the stretched singularity, m.
    pub reach_m: f64,
    /// Nominal arm posture for the null-space pull, per side, one value per chain joint.
    pub arm_nominal: [Vec<f64>; 2],
}

fn frame(robot: &RobotModel, name: &str) -> Result<usize, SynthError> {
    robot
        .frame_index(name)
        .ok_or_else(|| SynthError::Robot(format!("no frame `{name}`")))
}

fn joint(robot: &RobotModel, name: &str) -> Result<usize, SynthError> {
    robot
        .joint_index(name)
        .ok_or_else(|| SynthError::Robot(format!("no joint `{name}`")))
}

impl Skeleton {
    /// Measures a G1-like robot (URDF link and joint names of the Unitree description).
    pub fn new(robot: &RobotModel) -> Result<Self, SynthError> {
        let waist = [
            joint(robot, "waist_yaw_joint")?,
            joint(robot, "waist_roll_joint")?,
            joint(robot, "waist_pitch_joint")?,
        ];
        let mut poses = Vec::new();
        let q0 = robot.default_pose();
        forward_kinematics(robot, &Isometry3::identity(), &q0, &mut poses);
        let low = lowest_sole_point_z(robot, &poses)
            .ok_or_else(|| SynthError::Robot("the robot has no sole shapes".into()))?;
        let ankles = [
            frame(robot, "left_ankle_roll_link")?,
            frame(robot, "right_ankle_roll_link")?,
        ];
        let ankle = frame_pose(robot, &poses, ankles[0]);
        let legs = ankles.map(|f| chain_to_root(robot, f, |j| waist.contains(&j)));
        let toe_m = toe_edge(robot, &poses, ankles[0], &ankle)?;
        let hands = [robot.hands[0].frame, robot.hands[1].frame];
        let arms = hands.map(|f| chain_to_root(robot, f, |j| waist.contains(&j)));
        if legs.iter().chain(&arms).any(|c| c.joints.len() < 4) {
            return Err(SynthError::Robot(
                "a leg or arm has fewer than 4 joints".into(),
            ));
        }
        let shoulder_body = [
            robot.joints[arms[0].joints[0]].body,
            robot.joints[arms[1].joints[0]].body,
        ];
        let hand_default = hands.map(|f| frame_pose(robot, &poses, f).translation.vector);
        // Upper bound of the arm length: the sum of joint-to-joint offsets.
        let mut reach = 0.0;
        let mut prev = poses[shoulder_body[0]].translation.vector;
        for &j in &arms[0].joints[1..] {
            let p = poses[robot.joints[j].body].translation.vector;
            reach += (p - prev).norm();
            prev = p;
        }
        reach += (hand_default[0] - prev).norm();
        // Nominal arms: forearm forward and slightly out, wrists neutral.
        let arm_nominal = [0, 1].map(|s| {
            let sign = if s == 0 { 1.0 } else { -1.0 };
            arms[s]
                .joints
                .iter()
                .map(|&j| {
                    let name = robot.joints[j].name.as_str();
                    if name.contains("shoulder_pitch") {
                        -0.5
                    } else if name.contains("shoulder_roll") {
                        0.15 * sign
                    } else if name.contains("elbow") {
                        0.6
                    } else {
                        0.0
                    }
                })
                .collect()
        });
        Ok(Self {
            legs,
            arms,
            waist,
            stand_height_m: -low,
            ankle_height_m: ankle.translation.vector.z - low,
            foot_rot: ankle.rotation,
            foot_y_m: ankle.translation.vector.y.abs(),
            foot_x_m: ankle.translation.vector.x,
            toe_m,
            hand_default,
            shoulder_body,
            reach_m: 0.9 * reach,
            arm_nominal,
        })
    }
}

/// The toe's edge of a foot's sole in its ankle frame `ankle_frame` (posed at `ankle`):
/// the mean centre of the sole shapes ahead of their middle, with y zeroed, so the edge
/// is a line across the foot through that point.
fn toe_edge(
    robot: &RobotModel,
    poses: &[Isometry3<f64>],
    ankle_frame: usize,
    ankle: &Isometry3<f64>,
) -> Result<Vector3<f64>, SynthError> {
    let body = robot.frames[ankle_frame].body;
    let centres: Vec<Vector3<f64>> = robot.bodies[body]
        .shapes
        .iter()
        .filter(|s| s.is_sole)
        .map(|s| {
            let world = poses[body] * (s.body_from_shape * nalgebra::Point3::origin());
            (ankle.inverse() * world).coords
        })
        .collect();
    let (lo, hi) = centres
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), c| {
            (lo.min(c.x), hi.max(c.x))
        });
    if centres.len() < 2 || hi - lo < 0.05 {
        return Err(SynthError::Robot(
            "the ankle's foot has no sole points spanning toe and heel".into(),
        ));
    }
    let front: Vec<_> = centres.iter().filter(|c| c.x > 0.5 * (lo + hi)).collect();
    let mut toe = front.iter().fold(Vector3::zeros(), |a, c| a + *c) / front.len() as f64;
    toe.y = 0.0;
    Ok(toe)
}
