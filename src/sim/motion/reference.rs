//! Reference processing: a sequence resampled onto a fixed clock (linear for positions,
//! joints and forces, slerp for rotations) with velocities, keypoints by forward
//! kinematics, and the ground check.
//!
//! Velocities are central finite differences at the source frame rate (one-sided at the
//! ends, as numpy's `gradient`), then interpolated like the positions. No further
//! smoothing is applied: the central difference already averages two forward differences,
//! and smoothing more would lag the reference behind the motion it describes.

use super::sequence::{Sequence, LEFT, RIGHT};
use crate::sim::robot::{
    forward_kinematics, keypoint_positions, lowest_sole_point_z, KeypointSet, RobotModel,
};
use nalgebra::{Isometry3, Point3, Quaternion, Translation3, UnitQuaternion, Vector3};

/// The heading of a root orientation: the yaw of its x axis in the ground plane, rad
/// (counter-clockwise from world +x). Unlike the z of the z-y-x angles it ignores roll.
pub fn heading_rad(world_from_root: &UnitQuaternion<f64>) -> f64 {
    let x = world_from_root * Vector3::x();
    x.y.atan2(x.x)
}

/// One instant of a reference.
#[derive(Debug, Clone, PartialEq)]
pub struct ReferenceFrame {
    /// Root pose in the world.
    pub world_from_root: Isometry3<f64>,
    /// Root linear velocity, world frame, m/s.
    pub root_lin_vel_w: Vector3<f64>,
    /// Root angular velocity, world frame, rad/s.
    pub root_ang_vel_w: Vector3<f64>,
    /// Joint angles, rad.
    pub joint_pos: Vec<f64>,
    /// Joint velocities, rad/s.
    pub joint_vel: Vec<f64>,
    /// Left and right hand force, sensor frame, N.
    pub force_sensor: [Vector3<f64>; 2],
}

/// A sequence with velocities, sampled at any time by interpolation.
#[derive(Debug, Clone)]
pub struct Reference {
    fps: f64,
    root_pos: Vec<Vector3<f64>>,
    root_rot: Vec<UnitQuaternion<f64>>,
    joint_pos: Vec<Vec<f64>>,
    root_lin_vel: Vec<Vector3<f64>>,
    root_ang_vel: Vec<Vector3<f64>>,
    joint_vel: Vec<Vec<f64>>,
    force: [Vec<Vector3<f64>>; 2],
}

impl Reference {
    /// Prepares a validated sequence (velocities by finite differences unless stored).
    pub fn new(seq: &Sequence) -> Self {
        let dt = 1.0 / seq.fps;
        let root_pos: Vec<Vector3<f64>> = seq.root_pos.iter().map(|p| Vector3::from(*p)).collect();
        let root_rot: Vec<UnitQuaternion<f64>> = seq
            .root_quat_wxyz
            .iter()
            .map(|q| UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3])))
            .collect();
        let t = root_pos.len();
        let root_lin_vel = (0..t)
            .map(|i| {
                let (a, b) = neighbours(i, t);
                (root_pos[b] - root_pos[a]) / ((b - a) as f64 * dt)
            })
            .collect();
        let root_ang_vel = (0..t)
            .map(|i| {
                let (a, b) = neighbours(i, t);
                (root_rot[b] * root_rot[a].inverse()).scaled_axis() / ((b - a) as f64 * dt)
            })
            .collect();
        let joint_vel = match &seq.joint_vel {
            Some(v) => v.clone(),
            None => (0..t)
                .map(|i| {
                    let (a, b) = neighbours(i, t);
                    let span = (b - a) as f64 * dt;
                    seq.joint_pos[b]
                        .iter()
                        .zip(&seq.joint_pos[a])
                        .map(|(x1, x0)| (x1 - x0) / span)
                        .collect()
                })
                .collect(),
        };
        let force = [LEFT, RIGHT].map(|s| {
            seq.force_sensor[s]
                .iter()
                .map(|f| Vector3::from(*f))
                .collect()
        });
        Self {
            fps: seq.fps,
            root_pos,
            root_rot,
            joint_pos: seq.joint_pos.clone(),
            root_lin_vel,
            root_ang_vel,
            joint_vel,
            force,
        }
    }

    /// Duration from first to last frame, s (the reference horizon T_ref).
    pub fn duration_s(&self) -> f64 {
        (self.root_pos.len() - 1) as f64 / self.fps
    }

    /// The reference at time `t_s`, clamped to `[0, duration]`.
    pub fn sample(&self, t_s: f64) -> ReferenceFrame {
        let n = self.root_pos.len();
        let x = (t_s * self.fps).clamp(0.0, (n - 1) as f64);
        let i = (x.floor() as usize).min(n - 1);
        let j = (i + 1).min(n - 1);
        let a = x - i as f64;
        let lerp3 = |v: &[Vector3<f64>]| v[i] * (1.0 - a) + v[j] * a;
        let lerpn = |v: &[Vec<f64>]| {
            v[i].iter()
                .zip(&v[j])
                .map(|(p, q)| p * (1.0 - a) + q * a)
                .collect()
        };
        ReferenceFrame {
            world_from_root: Isometry3::from_parts(
                Translation3::from(lerp3(&self.root_pos)),
                self.root_rot[i]
                    .try_slerp(&self.root_rot[j], a, 1e-9)
                    .unwrap_or(self.root_rot[i]),
            ),
            root_lin_vel_w: lerp3(&self.root_lin_vel),
            root_ang_vel_w: lerp3(&self.root_ang_vel),
            joint_pos: lerpn(&self.joint_pos),
            joint_vel: lerpn(&self.joint_vel),
            force_sensor: [lerp3(&self.force[LEFT]), lerp3(&self.force[RIGHT])],
        }
    }

    /// Frames on a uniform clock `0, dt, 2·dt, …` up to the duration (the control rate).
    pub fn resample(&self, dt_s: f64) -> Vec<ReferenceFrame> {
        let n = (self.duration_s() / dt_s + 1e-9).floor() as usize + 1;
        (0..n).map(|k| self.sample(k as f64 * dt_s)).collect()
    }
}

fn neighbours(i: usize, n: usize) -> (usize, usize) {
    (i.saturating_sub(1), (i + 1).min(n - 1))
}

/// World positions of a keypoint set for each frame, by forward kinematics.
pub fn reference_keypoints(
    robot: &RobotModel,
    frames: &[ReferenceFrame],
    set: &KeypointSet,
) -> Vec<Vec<Point3<f64>>> {
    let mut poses = Vec::new();
    frames
        .iter()
        .map(|f| {
            forward_kinematics(robot, &f.world_from_root, &f.joint_pos, &mut poses);
            let mut out = Vec::new();
            keypoint_positions(robot, &poses, set, &mut out);
            out
        })
        .collect()
}

/// Where a motion's feet are relative to the ground.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GroundCheck {
    /// Median over frames of the lowest sole point's height, m: the offset to remove so
    /// that the feet touch z = 0 in stance.
    pub offset_m: f64,
    /// Lowest sole point over the whole motion, m.
    pub min_m: f64,
}

/// Lowest sole point per frame, summarised (the robot must have sole shapes).
pub fn ground_check(robot: &RobotModel, seq: &Sequence) -> Option<GroundCheck> {
    let mut poses = Vec::new();
    let mut lows: Vec<f64> = Vec::with_capacity(seq.n_frames());
    for k in 0..seq.n_frames() {
        let q = seq.root_quat_wxyz[k];
        let root = Isometry3::from_parts(
            Translation3::from(Vector3::from(seq.root_pos[k])),
            UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3])),
        );
        forward_kinematics(robot, &root, &seq.joint_pos[k], &mut poses);
        lows.push(lowest_sole_point_z(robot, &poses)?);
    }
    let min_m = lows.iter().copied().fold(f64::INFINITY, f64::min);
    lows.sort_by(f64::total_cmp);
    let offset_m = if lows.len() % 2 == 1 {
        lows[lows.len() / 2]
    } else {
        0.5 * (lows[lows.len() / 2 - 1] + lows[lows.len() / 2])
    };
    Some(GroundCheck { offset_m, min_m })
}

/// Shifts the root height of every frame (the ground correction).
pub fn shift_root_height(seq: &mut Sequence, dz_m: f64) {
    seq.root_pos.iter_mut().for_each(|p| p[2] += dz_m);
}

/// Key of the ground correction in a sequence's provenance: the root height shift, m.
pub const GROUND_SHIFT_KEY: &str = "ground_shift_m";

/// Moves the root so that the median lowest sole point of `check` sits on the ground, and
/// records the shift in the provenance under [`GROUND_SHIFT_KEY`].
pub fn correct_ground(seq: &mut Sequence, check: &GroundCheck) {
    shift_root_height(seq, -check.offset_m);
    if let Some(p) = seq.provenance.as_object_mut() {
        p.insert(GROUND_SHIFT_KEY.into(), serde_json::json!(-check.offset_m));
    }
}
