//! What a command-following policy is asked to follow, measured over one episode of the
//! sanity check (`crate::eval::sanity`): FALCON's legs follow a velocity, a yaw rate and a base
//! height derived from the reference, not the reference's joints, so its world keypoint
//! error includes the drift its commands leave uncorrected and says little about its
//! wiring. A follower is judged instead by how its root moves against the reference's
//! (velocity over one-second windows, heading, height) and by its upper-body keypoints in
//! its own root frame — the arms it is asked to place.

use crate::sim::motion::{Reference, Sequence};
use crate::sim::physics::RootState;
use crate::sim::robot::{forward_kinematics, keypoint_positions, KeypointSet, RobotModel};
use nalgebra::{Isometry3, Point3, Vector2};
use serde::{Deserialize, Serialize};
use std::collections::VecDeque;

/// The window the velocities are averaged over, s: about one gait cycle, so a step's sway
/// is not counted as a velocity error.
pub const VELOCITY_WINDOW_S: f64 = 1.0;
/// Largest RMS error of the windowed root velocity, m/s.
pub const MAX_VELOCITY_RMS_M_PER_S: f64 = 0.2;
/// Largest RMS heading error, degrees.
pub const MAX_HEADING_RMS_DEG: f64 = 15.0;
/// Largest RMS base-height error, mm.
pub const MAX_HEIGHT_RMS_MM: f64 = 60.0;

/// How well an episode followed what it was asked.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Following {
    /// RMS of |robot − reference| root velocity over [`VELOCITY_WINDOW_S`] windows, m/s.
    pub velocity_rms_m_per_s: f64,
    /// RMS heading error, degrees.
    pub heading_rms_deg: f64,
    /// RMS root height error, mm.
    pub height_rms_mm: f64,
    /// RMS error of the upper-body keypoints in the root frame, mm.
    pub upper_kp_rms_mm: f64,
}

impl Following {
    /// Which limits it exceeds, as sentences; empty when it follows.
    pub fn problems(&self, max_upper_kp_mm: f64) -> Vec<String> {
        let mut out = Vec::new();
        let mut check = |value: f64, max: f64, what: &str, unit: &str| {
            // NaN (never measured) fails too.
            if value.partial_cmp(&max) != Some(std::cmp::Ordering::Less) {
                out.push(format!(
                    "{what} {value:.2} {unit} (must be under {max} {unit})"
                ));
            }
        };
        check(
            self.velocity_rms_m_per_s,
            MAX_VELOCITY_RMS_M_PER_S,
            "root velocity error",
            "m/s",
        );
        check(
            self.heading_rms_deg,
            MAX_HEADING_RMS_DEG,
            "heading error",
            "°",
        );
        check(self.height_rms_mm, MAX_HEIGHT_RMS_MM, "height error", "mm");
        check(
            self.upper_kp_rms_mm,
            max_upper_kp_mm,
            "upper-body keypoint error",
            "mm",
        );
        out
    }
}

/// Accumulates [`Following`] step by step.
pub struct FollowingMeter<'a> {
    robot: &'a RobotModel,
    keypoints: &'a KeypointSet,
    reference: Reference,
    window_steps: usize,
    /// Recent (robot, reference) root xy positions, oldest first.
    recent: VecDeque<(Vector2<f64>, Vector2<f64>)>,
    sums: [f64; 4],
    counts: [usize; 4],
    poses: Vec<Isometry3<f64>>,
    points: [Vec<Point3<f64>>; 2],
}

fn yaw(r: &nalgebra::UnitQuaternion<f64>) -> f64 {
    r.euler_angles().2
}

impl<'a> FollowingMeter<'a> {
    /// A meter for an episode of `seq` at control period `control_dt_s`.
    pub fn new(
        robot: &'a RobotModel,
        keypoints: &'a KeypointSet,
        seq: &Sequence,
        control_dt_s: f64,
    ) -> Self {
        Self {
            robot,
            keypoints,
            reference: Reference::new(seq),
            window_steps: (VELOCITY_WINDOW_S / control_dt_s).round().max(1.0) as usize,
            recent: VecDeque::new(),
            sums: [0.0; 4],
            counts: [0; 4],
            poses: Vec::new(),
            points: [Vec::new(), Vec::new()],
        }
    }

    /// The robot at `time_s` with joints `q`.
    pub fn step(&mut self, time_s: f64, root: &RootState, q: &[f64]) {
        let r = self.reference.sample(time_s);
        let robot_xy = root.world_from_root.translation.vector.xy();
        let ref_xy = r.world_from_root.translation.vector.xy();
        self.recent.push_back((robot_xy, ref_xy));
        if self.recent.len() > self.window_steps {
            let (robot_then, ref_then) = self.recent.pop_front().unwrap_or_default();
            let v_robot = (robot_xy - robot_then) / VELOCITY_WINDOW_S;
            let v_ref = (ref_xy - ref_then) / VELOCITY_WINDOW_S;
            self.add(0, (v_robot - v_ref).norm_squared());
        }
        let heading = (yaw(&root.world_from_root.rotation) - yaw(&r.world_from_root.rotation))
            .sin()
            .atan2((yaw(&root.world_from_root.rotation) - yaw(&r.world_from_root.rotation)).cos());
        self.add(1, heading.to_degrees().powi(2));
        let dz = root.world_from_root.translation.z - r.world_from_root.translation.z;
        self.add(2, (1e3 * dz).powi(2));
        for (points, joints) in self.points.iter_mut().zip([q, &r.joint_pos[..]]) {
            forward_kinematics(self.robot, &Isometry3::identity(), joints, &mut self.poses);
            keypoint_positions(self.robot, &self.poses, self.keypoints, points);
        }
        let upper = self.keypoints.n_upper;
        for (a, b) in self.points[0][..upper].iter().zip(&self.points[1][..upper]) {
            let e = 1e3 * (a - b).norm();
            self.sums[3] += e * e;
            self.counts[3] += 1;
        }
    }

    fn add(&mut self, k: usize, squared: f64) {
        self.sums[k] += squared;
        self.counts[k] += 1;
    }

    /// The RMS errors so far (NaN for a quantity never measured: an episode shorter than
    /// the velocity window).
    pub fn finish(&self) -> Following {
        let rms = |k: usize| {
            if self.counts[k] == 0 {
                f64::NAN
            } else {
                (self.sums[k] / self.counts[k] as f64).sqrt()
            }
        };
        Following {
            velocity_rms_m_per_s: rms(0),
            heading_rms_deg: rms(1),
            height_rms_mm: rms(2),
            upper_kp_rms_mm: rms(3),
        }
    }
}
