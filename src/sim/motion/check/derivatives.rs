//! A sequence's motion smoothed and differentiated twice at its own frame rate: the
//! accelerations its inverse dynamics needs.
//!
//! Root position, root orientation (its quaternion made sign-continuous, each component
//! filtered, renormalised) and joint angles pass the zero-phase low-pass of
//! [`super::zero_phase`]; velocities and accelerations are central differences of the
//! smoothed values, so both are defined on frames `1..n−1` only. The root's angular
//! velocity and acceleration come from the rotation increments on either side of a frame
//! (`ω± = log(R(k±1)·R(k)ᵀ)/Δt`, world frame): their mean and their difference over Δt.

use super::zero_phase::low_pass_zero_phase;
use crate::sim::motion::Sequence;
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3};

/// The smoothed motion of a sequence, with first and second derivatives.
#[derive(Debug, Clone)]
pub struct SmoothedMotion {
    /// Frame rate, Hz.
    pub fps: f64,
    /// Root pose per frame.
    pub world_from_root: Vec<Isometry3<f64>>,
    /// Root origin velocity and acceleration, world frame (zero at the two end frames).
    pub root_lin_vel_w: Vec<Vector3<f64>>,
    /// See [`Self::root_lin_vel_w`], m/s².
    pub root_lin_acc_w: Vec<Vector3<f64>>,
    /// Root angular velocity, world frame, rad/s.
    pub root_ang_vel_w: Vec<Vector3<f64>>,
    /// Root angular acceleration, world frame, rad/s².
    pub root_ang_acc_w: Vec<Vector3<f64>>,
    /// Joint angles, rad; one row per frame.
    pub q: Vec<Vec<f64>>,
    /// Joint velocities, rad/s.
    pub qd: Vec<Vec<f64>>,
    /// Joint accelerations, rad/s².
    pub qdd: Vec<Vec<f64>>,
}

/// Filters each column of `rows` (one row per frame).
fn filter_columns(rows: &[Vec<f64>], cutoff_hz: f64, fps: f64) -> Vec<Vec<f64>> {
    let width = rows.first().map_or(0, Vec::len);
    let columns: Vec<Vec<f64>> = (0..width)
        .map(|c| {
            let col: Vec<f64> = rows.iter().map(|r| r[c]).collect();
            low_pass_zero_phase(&col, cutoff_hz, fps)
        })
        .collect();
    (0..rows.len())
        .map(|k| columns.iter().map(|c| c[k]).collect())
        .collect()
}

/// Central first and second differences of `x` at every inner frame (zero at the ends).
fn differentiate(x: &[Vec<f64>], dt: f64) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    let n = x.len();
    let width = x.first().map_or(0, Vec::len);
    let mut v = vec![vec![0.0; width]; n];
    let mut a = vec![vec![0.0; width]; n];
    for k in 1..n.saturating_sub(1) {
        for c in 0..width {
            v[k][c] = (x[k + 1][c] - x[k - 1][c]) / (2.0 * dt);
            a[k][c] = (x[k + 1][c] - 2.0 * x[k][c] + x[k - 1][c]) / (dt * dt);
        }
    }
    (v, a)
}

impl SmoothedMotion {
    /// `seq` low-passed at `cutoff_hz` and differentiated.
    pub fn of(seq: &Sequence, cutoff_hz: f64) -> Self {
        let (fps, n) = (seq.fps, seq.n_frames());
        let dt = 1.0 / fps;
        let root: Vec<Vec<f64>> = seq.root_pos.iter().map(|p| p.to_vec()).collect();
        let root = filter_columns(&root, cutoff_hz, fps);
        // Quaternions on one hemisphere, so that filtering never averages q with −q.
        let mut quats: Vec<Vec<f64>> = Vec::with_capacity(n);
        for q in &seq.root_quat_wxyz {
            let flip = quats
                .last()
                .is_some_and(|p: &Vec<f64>| p.iter().zip(q).map(|(a, b)| a * b).sum::<f64>() < 0.0);
            let s = if flip { -1.0 } else { 1.0 };
            quats.push(q.iter().map(|c| s * c).collect());
        }
        let rotations: Vec<UnitQuaternion<f64>> = filter_columns(&quats, cutoff_hz, fps)
            .iter()
            .map(|q| UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3])))
            .collect();
        let (root_v, root_a) = differentiate(&root, dt);
        let q = filter_columns(&seq.joint_pos, cutoff_hz, fps);
        let (qd, qdd) = differentiate(&q, dt);
        let mut ang_vel = vec![Vector3::zeros(); n];
        let mut ang_acc = vec![Vector3::zeros(); n];
        for k in 1..n.saturating_sub(1) {
            let ahead = (rotations[k + 1] * rotations[k].inverse()).scaled_axis() / dt;
            let behind = (rotations[k] * rotations[k - 1].inverse()).scaled_axis() / dt;
            ang_vel[k] = (ahead + behind) / 2.0;
            ang_acc[k] = (ahead - behind) / dt;
        }
        let v3 = |r: &Vec<f64>| Vector3::new(r[0], r[1], r[2]);
        Self {
            fps,
            world_from_root: root
                .iter()
                .zip(&rotations)
                .map(|(p, r)| Isometry3::from_parts(Translation3::from(v3(p)), *r))
                .collect(),
            root_lin_vel_w: root_v.iter().map(v3).collect(),
            root_lin_acc_w: root_a.iter().map(v3).collect(),
            root_ang_vel_w: ang_vel,
            root_ang_acc_w: ang_acc,
            q,
            qd,
            qdd,
        }
    }

    /// Number of frames.
    pub fn n_frames(&self) -> usize {
        self.q.len()
    }
}
