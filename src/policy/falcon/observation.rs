//! FALCON's 575-float observation: five frames of 115, oldest first, each frame its terms
//! in alphabetical order times their scales — the deploy sorts the term names
//! (`sim2real/rl_policy/base_policy.py:279-282`), the history shifts one frame per step
//! (`base_policy.py:291-300`). An episode's history starts as its first frame repeated:
//! the deploy zeroes its buffer once, at process start (`base_policy.py:106-109`), then
//! runs the network on every loop while the robot stands in its start posture
//! (`loco_manip.py`: `rl_inference` before the ready/policy branch), so by the first step
//! it acts on, the history holds frames of that posture; training never clears it
//! between commands either. Zeros would show the network four frames of zero gravity
//! and a zero height command, a state neither ever produced.
//!
//! ```text
//! offset  term                 width  scale (cfg:278-293)
//!   0     actions                29   1     previous raw network output, clipped ±100
//!  29     base_ang_vel            3   0.25  root angular velocity, root frame, rad/s
//!  32     command_ang_vel         1   1     yaw rate, rad/s
//!  33     command_base_height     1   2     pelvis height, m
//!  34     command_lin_vel         2   1     (v_x, v_y), m/s
//!  36     command_stand           1   1     1 walk, 0 stance
//!  37     command_waist_dofs      3   1     waist yaw, roll, pitch, rad
//!  40     dof_pos                29   1     q − default pose, rad
//!  69     dof_vel                29   0.05  q̇, rad/s
//!  98     projected_gravity       3   1     gravity direction in the root frame
//! 101     ref_upper_dof_pos      14   1     arm joint references, rad (absolute)
//! ```
//!
//! The network's joints are the canonical order (index for index; ARCHITECTURE, "FALCON's
//! joint order"). No clipping or normalisation: the deploy has none, and the ONNX graph is
//! Gemm and ELU only.

use super::commands::Commands;
use crate::policy::Observation;

/// Floats per frame.
pub const FRAME_LEN: usize = 115;
/// Frames in the observation.
pub const HISTORY: usize = 5;
/// Floats of the whole observation.
pub const OBS_LEN: usize = FRAME_LEN * HISTORY;
/// Joints of the network.
pub const N_JOINTS: usize = 29;
/// `base_ang_vel`'s scale.
const ANG_VEL_SCALE: f64 = 0.25;
/// `command_base_height`'s scale.
const HEIGHT_SCALE: f64 = 2.0;
/// `dof_vel`'s scale.
const DOF_VEL_SCALE: f64 = 0.05;

/// One frame of one environment: what it observes now, in network order and scale.
pub fn frame(
    obs: &Observation,
    default_pose: &[f64],
    last_raw_action: &[f64],
    commands: &Commands,
) -> [f64; FRAME_LEN] {
    let mut f = [0.0; FRAME_LEN];
    f[..29].copy_from_slice(last_raw_action);
    let w = obs.root.ang_vel_b() * ANG_VEL_SCALE;
    f[29..32].copy_from_slice(&[w.x, w.y, w.z]);
    f[32] = commands.ang_vel;
    f[33] = commands.base_height_m * HEIGHT_SCALE;
    f[34..36].copy_from_slice(&commands.lin_vel);
    f[36] = commands.stand;
    f[37..40].copy_from_slice(&commands.waist);
    for ((o, q), d) in f[40..69].iter_mut().zip(&obs.q).zip(default_pose) {
        *o = q - d;
    }
    for (o, qd) in f[69..98].iter_mut().zip(&obs.qd) {
        *o = qd * DOF_VEL_SCALE;
    }
    let g = obs.root.projected_gravity_b();
    f[98..101].copy_from_slice(&[g.x, g.y, g.z]);
    f[101..115].copy_from_slice(&commands.upper);
    f
}

/// One environment's observation history, oldest frame first.
#[derive(Debug, Clone)]
pub struct History {
    frames: Vec<[f64; FRAME_LEN]>,
}

impl Default for History {
    fn default() -> Self {
        Self {
            frames: vec![[0.0; FRAME_LEN]; HISTORY],
        }
    }
}

impl History {
    /// Drops the oldest frame, appends `frame`, and writes the observation into `out`
    /// ([`OBS_LEN`] floats). An episode's first step fills every frame with `frame` (the
    /// module's doc says why).
    pub fn push_into(&mut self, frame: [f64; FRAME_LEN], episode_starts: bool, out: &mut [f32]) {
        if episode_starts {
            self.frames.iter_mut().for_each(|f| *f = frame);
        } else {
            self.frames.rotate_left(1);
            self.frames[HISTORY - 1] = frame;
        }
        for (row, f) in out.chunks_exact_mut(FRAME_LEN).zip(&self.frames) {
            for (o, v) in row.iter_mut().zip(f) {
                *o = *v as f32;
            }
        }
    }
}
