//! SoftMimic's observations (github.com/Improbable-AI/softmimic, `params/<policy>.env.yaml`
//! `observations.policy`, built as `deploy/deploy_policy_interface.py:455-480` does), in
//! two layouts:
//!
//! ```text
//! 285  (StaticStand-*)   history terms only
//! 1159 (Pour-*, GMTWalkStand-, AMASSPick1-)  history terms, then 20 future reference frames
//!
//! history term (3 frames each, oldest first, term-major)    width  scale
//!   base_ang_vel           root frame, rad/s                  3    0.25
//!   projected_gravity      root frame                         3    1
//!   joint_pos              q − default, Isaac Lab order      29    1
//!   joint_vel              q̇, Isaac Lab order                29    0.05
//!   actions                previous raw output               29    1
//!   reference_dof_pos      (1159 only) reference joints      29    1
//!   reference_xy_vel       (1159) root frame of the reference 2    1
//!   reference_yaw_vel      (1159) root frame of the reference 1    1
//!   reference_root_height  (1159) world z, m                  1    1
//!   reference_gravity      (1159) root frame of the reference 3    1
//!   reference_foot_contact (1159) left, right                 2    1
//!   desired_stiffness_log            ln k, k in N/m           1    1
//!   desired_rotational_stiffness_log ln k_rot, N·m/rad        1    1
//! future terms (no history): the six reference terms at t + {1, 5, 10, …, 95} · 0.02 s,
//!   each term's 20 frames together, frame-major within it
//! ```
//!
//! History starts as three copies of the first frame (`deploy_policy_interface.py:461-463`,
//! as Isaac Lab's buffer refills after a reset). No clips, no normalisation.

use crate::policy::Observation;
use crate::sim::motion::ReferenceFrame;
use nalgebra::Vector3;

/// Joints of the network.
pub const N_JOINTS: usize = 29;
/// Frames of history per term.
pub const HISTORY: usize = 3;
/// `policy[i] = canonical[ISAAC_FROM_CANONICAL[i]]`: Isaac Lab's G1 joint order
/// (`deploy/robots/g1_config.py:9-39`, the motion library's `reindex_mapping`,
/// `deploy/sensors/wholeexo_sensor.py:74`).
pub const ISAAC_FROM_CANONICAL: [usize; N_JOINTS] = [
    0, 6, 12, 1, 7, 13, 2, 8, 14, 3, 9, 15, 22, 4, 10, 16, 23, 5, 11, 17, 24, 18, 25, 19, 26, 20,
    27, 21, 28,
];
/// Future reference frames, in control steps of 0.02 s ahead (`AP:619-639`, the
/// env.yaml's `future_steps`).
pub const FUTURE_STEPS: [usize; 20] = [
    1, 5, 10, 15, 20, 25, 30, 35, 40, 45, 50, 55, 60, 65, 70, 75, 80, 85, 90, 95,
];
/// The future frames' spacing, s (`future_dt`).
pub const FUTURE_DT_S: f64 = 0.02;
/// How far ahead of the robot's clock the deploy samples its reference "now", s: one
/// control step ([`Layout::reference_offsets_s`]).
pub const DEPLOY_LEAD_S: f64 = 0.02;
/// Width of one reference frame's terms: joints, xy velocity, yaw rate, height, gravity,
/// contacts.
const REFERENCE_TERMS: [usize; 6] = [N_JOINTS, 2, 1, 1, 3, 2];
const REFERENCE_LEN: usize = N_JOINTS + 2 + 1 + 1 + 3 + 2;
/// Proprioceptive terms of a frame: angular velocity, gravity, joints, velocities, actions.
const PROPRIO_TERMS: [usize; 5] = [3, 3, N_JOINTS, N_JOINTS, N_JOINTS];
const PROPRIO_LEN: usize = 3 + 3 + 3 * N_JOINTS;

/// Which inputs a network takes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layout {
    /// 285 = 95 × 3: proprioception and the stiffness command (StaticStand-*).
    Stand,
    /// 1159 = 133 × 3 + 760: also the reference now and 20 frames ahead.
    Track,
}

impl Layout {
    /// The layout of a network of `width` inputs.
    pub fn of_width(width: usize) -> Option<Self> {
        [Self::Stand, Self::Track]
            .into_iter()
            .find(|l| l.width() == width)
    }

    /// Its input width.
    pub fn width(self) -> usize {
        self.frame_len() * HISTORY + self.future_len()
    }

    /// Floats of one history frame.
    fn frame_len(self) -> usize {
        PROPRIO_LEN
            + 2
            + if self == Self::Track {
                REFERENCE_LEN
            } else {
                0
            }
    }

    fn future_len(self) -> usize {
        if self == Self::Track {
            FUTURE_STEPS.len() * REFERENCE_LEN
        } else {
            0
        }
    }

    /// The widths of a history frame's terms, in order.
    fn terms(self) -> Vec<usize> {
        let mut t = PROPRIO_TERMS.to_vec();
        if self == Self::Track {
            t.extend(REFERENCE_TERMS);
        }
        t.extend([1, 1]);
        t
    }

    /// The reference offsets it reads, s: the deploy's "now", then the future frames
    /// (none for [`Layout::Stand`], which observes no reference). The deploy's "now" is
    /// one control step ahead of the robot's clock: its motion sensor advances its counter
    /// before it samples (`deploy/sensors/wholeexo_sensor.py:206-237`), once per
    /// observation, so at the n-th step it acts on it reads the motion at (n + 1) · 0.02 s.
    pub fn reference_offsets_s(self) -> Vec<f64> {
        match self {
            Self::Stand => vec![0.0],
            Self::Track => std::iter::once(0.0)
                .chain(FUTURE_STEPS.iter().map(|&k| k as f64 * FUTURE_DT_S))
                .map(|offset| DEPLOY_LEAD_S + offset)
                .collect(),
        }
    }
}

/// The stiffness command: linear N/m, rotational N·m/rad.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stiffness {
    /// Linear stiffness, N/m.
    pub linear: f64,
    /// Rotational stiffness, N·m/rad.
    pub rotational: f64,
}

/// A reference frame's terms: joints (Isaac order), xy velocity and yaw rate in its root
/// frame, root height, gravity in its root frame, and the foot contacts given.
pub fn reference_terms(frame: &ReferenceFrame, contacts: [f64; 2], out: &mut Vec<f64>) {
    out.extend(ISAAC_FROM_CANONICAL.iter().map(|&c| frame.joint_pos[c]));
    let r = &frame.world_from_root.rotation;
    let v = r.inverse_transform_vector(&frame.root_lin_vel_w);
    let w = r.inverse_transform_vector(&frame.root_ang_vel_w);
    let g = r.inverse_transform_vector(&Vector3::new(0.0, 0.0, -1.0));
    out.extend([
        v.x,
        v.y,
        w.z,
        frame.world_from_root.translation.z,
        g.x,
        g.y,
        g.z,
    ]);
    out.extend(contacts);
}

/// One history frame of `obs`: proprioception, then (for [`Layout::Track`]) the reference
/// now with `contacts_now`, then the stiffness logs.
pub fn frame(
    layout: Layout,
    obs: &Observation,
    default_pose: &[f64],
    last_raw_isaac: &[f64],
    contacts_now: [f64; 2],
    stiffness: Stiffness,
) -> Vec<f64> {
    let mut f = Vec::with_capacity(layout.frame_len());
    let w = obs.root.ang_vel_b() * 0.25;
    let g = obs.root.projected_gravity_b();
    f.extend([w.x, w.y, w.z, g.x, g.y, g.z]);
    f.extend(
        ISAAC_FROM_CANONICAL
            .iter()
            .map(|&c| obs.q[c] - default_pose[c]),
    );
    f.extend(ISAAC_FROM_CANONICAL.iter().map(|&c| obs.qd[c] * 0.05));
    f.extend_from_slice(last_raw_isaac);
    if layout == Layout::Track {
        reference_terms(&obs.reference[0], contacts_now, &mut f);
    }
    f.extend([stiffness.linear.ln(), stiffness.rotational.ln()]);
    f
}

/// One environment's history frames, oldest first.
#[derive(Debug, Clone, Default)]
pub struct History {
    frames: Vec<Vec<f64>>,
}

impl History {
    /// Appends `frame` (three copies of it at an episode's start) and writes the whole
    /// observation into `out`: each term's three frames together, then `future` (the
    /// future frames' terms, one frame after another).
    pub fn push_into(
        &mut self,
        layout: Layout,
        frame: Vec<f64>,
        episode_starts: bool,
        future: &[Vec<f64>],
        out: &mut [f32],
    ) {
        if episode_starts || self.frames.len() != HISTORY {
            self.frames = vec![frame; HISTORY];
        } else {
            self.frames.rotate_left(1);
            self.frames[HISTORY - 1] = frame;
        }
        let mut at = 0;
        let mut start = 0;
        for width in layout.terms() {
            for f in &self.frames {
                for (o, v) in out[at..at + width].iter_mut().zip(&f[start..start + width]) {
                    *o = *v as f32;
                }
                at += width;
            }
            start += width;
        }
        let mut start = 0;
        for width in REFERENCE_TERMS
            .iter()
            .take(if future.is_empty() { 0 } else { 6 })
        {
            for f in future {
                for (o, v) in out[at..at + width].iter_mut().zip(&f[start..start + width]) {
                    *o = *v as f32;
                }
                at += width;
            }
            start += width;
        }
        debug_assert_eq!(at, layout.width());
    }
}
