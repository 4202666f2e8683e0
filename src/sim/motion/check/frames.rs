//! One sequence frame by frame, as the check sees it: the sole points and which touch, the
//! support they span, the centre of mass, and the ground's wrench with the recorded hand
//! forces and without them. The check pools these ([`super::check_sequence`]); synthesis
//! reads the centre of pressure against the support to move the body until it balances.

use super::derivatives::SmoothedMotion;
use super::support::{convex_hull, SolePoints, SoleSample};
use super::{CheckError, CheckOptions};
use crate::sim::motion::{heading_rad, ForceFrame, Sequence, LEFT, RIGHT};
use crate::sim::robot::{
    center_of_mass, forward_kinematics, inverse_dynamics, MotionState, RobotModel,
};
use nalgebra::{Isometry3, Point2, Point3, Quaternion, UnitQuaternion, Vector3};

/// A wrench on the robot: force and moment about the world origin, world frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wrench {
    /// Force, N.
    pub force: Vector3<f64>,
    /// Moment about the world origin, N·m.
    pub moment_o: Vector3<f64>,
}

impl Wrench {
    /// Its centre of pressure on the ground z = 0, or `None` when the ground would have to
    /// pull (normal force ≤ 0).
    pub fn centre_of_pressure(&self) -> Option<Point2<f64>> {
        (self.force.z > 0.0).then(|| {
            Point2::new(
                -self.moment_o.y / self.force.z,
                self.moment_o.x / self.force.z,
            )
        })
    }
}

/// One frame of a sequence.
#[derive(Debug, Clone)]
pub struct FrameState {
    /// Frame index in the sequence.
    pub frame: usize,
    /// Every sole point's lowest point.
    pub soles: Vec<SoleSample>,
    /// Per sole point: whether it touches the ground.
    pub touching: Vec<bool>,
    /// Convex hull of the touching sole points (empty: no stance).
    pub support: Vec<Point2<f64>>,
    /// Root position, m.
    pub root_w: Vector3<f64>,
    /// Root heading: the yaw of its x axis about the world z axis, rad.
    pub root_heading_rad: f64,
    /// Whole-body centre of mass, m.
    pub com_w: Point3<f64>,
    /// What the ground must supply with the recorded hand forces acting.
    pub ground_with_force: Wrench,
    /// What the ground must supply with no hand force.
    pub ground_without_force: Wrench,
    /// Magnitude of each recorded hand force, N.
    pub hand_force_n: [f64; 2],
    /// Each recorded hand force in the world, through the reference's hand pose, N.
    pub hand_force_w: [Vector3<f64>; 2],
    /// The root's horizontal speed, m/s.
    pub root_speed_xy_m_s: f64,
}

/// The sequence's frames `1..n−1` (the ends have no acceleration). The sequence must hold
/// the robot's canonical joints and at least 5 frames.
pub fn frame_states(
    seq: &Sequence,
    robot: &RobotModel,
    soles: &SolePoints,
    opts: &CheckOptions,
) -> Result<Vec<FrameState>, CheckError> {
    checkable(seq, robot)?;
    let motion = SmoothedMotion::of(seq, opts.cutoff_hz);
    let gravity = Vector3::from(opts.gravity_w);
    let hand_from_sensor = hands_from_sensor(seq);
    let n = seq.n_frames();
    let mut poses = Vec::new();
    let mut out = Vec::with_capacity(n - 2);
    for k in 1..n - 1 {
        let state = MotionState {
            world_from_root: motion.world_from_root[k],
            root_lin_vel_w: motion.root_lin_vel_w[k],
            root_ang_vel_w: motion.root_ang_vel_w[k],
            root_lin_acc_w: motion.root_lin_acc_w[k],
            root_ang_acc_w: motion.root_ang_acc_w[k],
            q: &motion.q[k],
            qd: &motion.qd[k],
            qdd: &motion.qdd[k],
        };
        let id = inverse_dynamics(robot, &state, &gravity, &[], &mut poses);
        let samples = soles.sample(&poses);
        let touching: Vec<bool> = samples
            .iter()
            .map(|s| s.bottom_w.z <= opts.contact_height_m)
            .collect();
        let points: Vec<Point2<f64>> = samples
            .iter()
            .zip(&touching)
            .filter(|(_, t)| **t)
            .map(|(s, _)| Point2::new(s.bottom_w.x, s.bottom_w.y))
            .collect();
        // The recorded hand forces, in the world through the reference's hand poses.
        let mut hands = Wrench {
            force: Vector3::zeros(),
            moment_o: Vector3::zeros(),
        };
        let mut hand_force_n = [0.0; 2];
        let mut hand_force_w = [Vector3::zeros(); 2];
        for s in [LEFT, RIGHT] {
            let (f_w, at) = hand_force(seq, robot, &poses, &hand_from_sensor, s, k);
            hands.force += f_w;
            hands.moment_o += at.coords.cross(&f_w);
            hand_force_n[s] = Vector3::from(seq.force_sensor[s][k]).norm();
            hand_force_w[s] = f_w;
        }
        let alone = Wrench {
            force: id.root_force_w,
            moment_o: id.root_moment_about_origin_w(),
        };
        out.push(FrameState {
            frame: k,
            soles: samples,
            touching,
            support: convex_hull(&points),
            root_w: motion.world_from_root[k].translation.vector,
            root_heading_rad: heading_rad(&motion.world_from_root[k].rotation),
            com_w: center_of_mass(robot, &poses),
            ground_with_force: Wrench {
                force: alone.force - hands.force,
                moment_o: alone.moment_o - hands.moment_o,
            },
            ground_without_force: alone,
            hand_force_n,
            hand_force_w,
            root_speed_xy_m_s: motion.root_lin_vel_w[k].xy().norm(),
        });
    }
    Ok(out)
}

/// The hand forces of frames `1..n−1` in the world and the root's horizontal speed, as
/// [`frame_states`] gives them, without its dynamics: the hand poses by forward
/// kinematics alone. What a run needs to say which forces a family was trained with.
pub fn hand_forces_w(
    seq: &Sequence,
    robot: &RobotModel,
    opts: &CheckOptions,
) -> Result<Vec<HandForcesAt>, CheckError> {
    checkable(seq, robot)?;
    let motion = SmoothedMotion::of(seq, opts.cutoff_hz);
    let hand_from_sensor = hands_from_sensor(seq);
    let n = seq.n_frames();
    let mut poses = Vec::new();
    let mut out = Vec::with_capacity(n - 2);
    for k in 1..n - 1 {
        forward_kinematics(robot, &motion.world_from_root[k], &motion.q[k], &mut poses);
        let f = [LEFT, RIGHT].map(|s| hand_force(seq, robot, &poses, &hand_from_sensor, s, k).0);
        out.push(HandForcesAt {
            force_w: f,
            root_speed_xy_m_s: motion.root_lin_vel_w[k].xy().norm(),
        });
    }
    Ok(out)
}

/// One frame's recorded hand forces in the world, with the root's horizontal speed.
#[derive(Debug, Clone, Copy)]
pub struct HandForcesAt {
    /// Each hand's force, world frame, N.
    pub force_w: [Vector3<f64>; 2],
    /// The root's horizontal speed, m/s.
    pub root_speed_xy_m_s: f64,
}

/// Each hand's rotation from its force sensor's frame.
fn hands_from_sensor(seq: &Sequence) -> [UnitQuaternion<f64>; 2] {
    [LEFT, RIGHT].map(|s| {
        let q = seq.hand_from_sensor_wxyz[s];
        UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3]))
    })
}

/// Hand `s`'s recorded force at frame `k` in the world, N, and the world point it acts
/// at, through the reference's hand pose among the body poses `poses`.
fn hand_force(
    seq: &Sequence,
    robot: &RobotModel,
    poses: &[Isometry3<f64>],
    hand_from_sensor: &[UnitQuaternion<f64>; 2],
    s: usize,
    k: usize,
) -> (Vector3<f64>, Point3<f64>) {
    let frame = &robot.frames[robot.hands[s].frame];
    let world_from_hand = poses[frame.body] * frame.body_from_frame;
    let f_sensor = Vector3::from(seq.force_sensor[s][k]);
    let f_w = match seq.force_frame {
        ForceFrame::Sensor => world_from_hand.rotation * (hand_from_sensor[s] * f_sensor),
        ForceFrame::World => f_sensor,
    };
    (f_w, world_from_hand * Point3::from(seq.force_point_hand[s]))
}

/// The sequence holds the robot's canonical joints and at least 5 frames.
fn checkable(seq: &Sequence, robot: &RobotModel) -> Result<(), CheckError> {
    let canonical = seq.joint_names.len() == robot.n_joints()
        && seq
            .joint_names
            .iter()
            .zip(&robot.joints)
            .all(|(a, b)| *a == b.name);
    if !canonical {
        return Err(CheckError::Joints {
            task: seq.task.clone(),
            sequence: seq.sequence_id.clone(),
            robot: robot.name.clone(),
        });
    }
    let n = seq.n_frames();
    if n < 5 {
        return Err(CheckError::TooShort {
            task: seq.task.clone(),
            sequence: seq.sequence_id.clone(),
            frames: n,
        });
    }
    Ok(())
}
