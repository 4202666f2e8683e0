//! A force event: a force on one hand or both that ramps up, holds and releases — the
//! shape of SoftMimic's training pushes (arXiv:2510.17792; robodreamer/softmimic,
//! `compliant_motion_augmentation/force_profile.py`: one wrist at a time, ramped over
//! 0.1–2 s, held 0.5–1.0 s).

use super::Hands;
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// A force event's specification. The force has the same magnitude and world direction on
/// every hand it acts on.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ForceEvent {
    /// Magnitude per hand once ramped up, N.
    pub force_n: f64,
    /// Direction about z, degrees counter-clockwise from the reference's initial heading
    /// (0: pushes the robot forward; 90: towards its left, i.e. a push from its right).
    pub heading_deg: f64,
    /// Elevation of the direction above the horizontal, degrees (−90: straight down).
    pub up_deg: f64,
    /// The hands it acts on.
    pub hands: Hands,
    /// When the ramp starts, s from the episode's start.
    pub start_s: f64,
    /// Ramp from zero to `force_n`, s (0: a step).
    pub ramp_s: f64,
    /// Hold at `force_n`, s.
    pub hold_s: f64,
    /// Release from `force_n` to zero, s (0: a step).
    pub release_s: f64,
}

impl ForceEvent {
    /// The magnitude at `t_s`, N: zero before the start, linear up over the ramp, held,
    /// linear down over the release, zero after.
    pub fn magnitude_at(&self, t_s: f64) -> f64 {
        let t = t_s - self.start_s;
        let hold_end = self.ramp_s + self.hold_s;
        let shape = if t < 0.0 {
            0.0
        } else if t < self.ramp_s {
            t / self.ramp_s
        } else if t < hold_end {
            1.0
        } else if t < hold_end + self.release_s {
            1.0 - (t - hold_end) / self.release_s
        } else {
            0.0
        };
        self.force_n * shape
    }

    /// When the force is zero again, s from the episode's start.
    pub fn end_s(&self) -> f64 {
        self.start_s + self.ramp_s + self.hold_s + self.release_s
    }

    /// The world-frame unit direction for a reference starting at heading
    /// `initial_heading_rad` (yaw of the root's x axis).
    pub fn direction_w(&self, initial_heading_rad: f64) -> Vector3<f64> {
        let yaw = initial_heading_rad + self.heading_deg.to_radians();
        let up = self.up_deg.to_radians();
        Vector3::new(yaw.cos() * up.cos(), yaw.sin() * up.cos(), up.sin())
    }
}
