//! FALCON's commands derived from a reference motion, step by step: what a teleoperator's
//! joystick gives the released deploy (`sim2real/rl_policy/base_policy.py:379-387`,
//! `loco_manip.py`), here read off the motion the benchmark asks the robot to follow.
//!
//! The network was trained on commands resampled every 10 s (piecewise constant) while the
//! pelvis of a walking human sways inside each gait cycle, so the velocities are averaged
//! over the reference's next gait period ([`WINDOW_OFFSETS_S`], FALCON's `GAIT_PERIOD:
//! 0.9` s, `cfg:35`): the command says where the motion is going, not how the pelvis
//! wobbles. Every other choice keeps the commands inside the training distribution
//! (LeCAR-Lab/FALCON, `decoupled_locomotion_stand_height_waist_wbc_ma.py`
//! `_resample_commands`):
//!
//! | command | from the reference | training range |
//! |---|---|---|
//! | `command_lin_vel` | mean root velocity over the window, in the **robot's** heading frame | ±1 m/s per axis |
//! | `command_ang_vel` | mean yaw rate + 0.5 · wrapped heading error (training's heading mode) | ±1 rad/s |
//! | `command_stand` | 1 (walk) when the window moves, with hysteresis ([`STAND_HYSTERESIS`]) | 1 = walk, 0 = stance |
//! | `command_base_height` | 0.75 m walking; the reference pelvis height standing | 0.75; 0.50–0.75 |
//! | `command_waist_dofs` | (0, 0, 0) walking; (reference waist yaw, 0, 0) standing | yaw ±1 in stance only; roll, pitch 0 |
//! | `ref_upper_dof_pos` | the reference's 14 arm joints one control step ahead, wrists included | retargeted AMASS arms |
//!
//! The wrists: training passes the retargeted motion's wrist angles; the deploy zeroes the
//! six wrist references only when its own upper-body IK controller writes the arms
//! (`loco_manip.py:104-121`, a teleoperation mode the benchmark has no use for). A
//! reference motion has wrists, so the adapter passes them as training does.
//!
//! In stance the velocities are zero, as training multiplies them by the stand flag.

use crate::sim::motion::ReferenceFrame;
use crate::sim::physics::RootState;
use nalgebra::{UnitQuaternion, Vector3};

/// Arm joints (canonical indices 15..29) the `ref_upper_dof_pos` term and the residual
/// action cover (`cfg:105-110`): the waist is the lower-body actor's.
pub const UPPER: std::ops::Range<usize> = 15..29;
/// Waist yaw, roll, pitch (canonical indices), `command_waist_dofs`' order.
pub const WAIST: [usize; 3] = [12, 13, 14];
/// The reference frames the commands read: index 0 at t + one control step (the arm
/// references, training's `(episode_length_buf + 1) · dt`), then the velocity window.
pub const REF_AHEAD_S: f64 = 0.02;
/// The velocity window: ten frames over one gait period ahead (0.0 … 0.9 s).
pub const WINDOW_OFFSETS_S: [f64; 10] = [0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9];
/// Walking base height, m (`DESIRED_BASE_HEIGHT`, `cfg:36`).
pub const WALK_HEIGHT_M: f64 = 0.75;
/// Lowest stance height training sampled, m (0.75 + U[−0.25, 0]).
pub const MIN_HEIGHT_M: f64 = 0.50;
/// Command ranges of training, m/s and rad/s.
pub const MAX_LIN_VEL: f64 = 1.0;
/// Yaw-rate range of training, rad/s.
pub const MAX_YAW_RATE: f64 = 1.0;
/// Gain of training's heading mode: yaw rate = 0.5 · wrap(heading target − heading).
pub const HEADING_GAIN: f64 = 0.5;
/// The stand flag turns to walk above (speed m/s, |yaw rate| rad/s) and back to stance
/// below both of the second pair: a motion that pauses briefly does not flicker.
pub const STAND_HYSTERESIS: [(f64, f64); 2] = [(0.15, 0.3), (0.08, 0.15)];

/// One step's commands.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Commands {
    /// (v_x, v_y) in the robot's heading frame, m/s.
    pub lin_vel: [f64; 2],
    /// Yaw rate, rad/s.
    pub ang_vel: f64,
    /// 1 walking, 0 standing.
    pub stand: f64,
    /// Pelvis height, m.
    pub base_height_m: f64,
    /// Waist yaw, roll, pitch, rad.
    pub waist: [f64; 3],
    /// The 14 arm joints' references, rad (absolute).
    pub upper: [f64; 14],
}

/// Yaw of a rotation (z of its z-y-x angles).
fn yaw(q: &UnitQuaternion<f64>) -> f64 {
    q.euler_angles().2
}

/// `angle` wrapped into (−π, π].
fn wrap_to_pi(angle: f64) -> f64 {
    let a = (angle + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU);
    a - std::f64::consts::PI
}

/// The commands for a robot at `root` following `reference` (the frames at
/// [`REF_AHEAD_S`] and then [`WINDOW_OFFSETS_S`]), given the stand flag of the step before
/// (`None` at an episode's first step).
pub fn commands(
    root: &RootState,
    reference: &[ReferenceFrame],
    walking_before: Option<bool>,
) -> Commands {
    let ahead = &reference[0];
    let window = &reference[1..];
    let n = window.len() as f64;
    let mean_v: Vector3<f64> = window
        .iter()
        .map(|f| f.root_lin_vel_w)
        .sum::<Vector3<f64>>()
        / n;
    let mean_yaw_rate = window.iter().map(|f| f.root_ang_vel_w.z).sum::<f64>() / n;
    let robot_yaw = yaw(&root.world_from_root.rotation);
    let heading = UnitQuaternion::from_euler_angles(0.0, 0.0, robot_yaw);
    let v = heading.inverse_transform_vector(&Vector3::new(mean_v.x, mean_v.y, 0.0));
    let speed = v.xy().norm();
    let [(on_speed, on_yaw), (off_speed, off_yaw)] = STAND_HYSTERESIS;
    let walking = match walking_before {
        Some(true) => speed >= off_speed || mean_yaw_rate.abs() >= off_yaw,
        _ => speed > on_speed || mean_yaw_rate.abs() > on_yaw,
    };
    let mut upper = [0.0; 14];
    upper.copy_from_slice(&ahead.joint_pos[UPPER]);
    if !walking {
        return Commands {
            lin_vel: [0.0; 2],
            ang_vel: 0.0,
            stand: 0.0,
            base_height_m: ahead
                .world_from_root
                .translation
                .z
                .clamp(MIN_HEIGHT_M, WALK_HEIGHT_M),
            waist: [ahead.joint_pos[WAIST[0]].clamp(-1.0, 1.0), 0.0, 0.0],
            upper,
        };
    }
    let heading_error = wrap_to_pi(yaw(&ahead.world_from_root.rotation) - robot_yaw);
    Commands {
        lin_vel: [
            v.x.clamp(-MAX_LIN_VEL, MAX_LIN_VEL),
            v.y.clamp(-MAX_LIN_VEL, MAX_LIN_VEL),
        ],
        ang_vel: (mean_yaw_rate + HEADING_GAIN * heading_error).clamp(-MAX_YAW_RATE, MAX_YAW_RATE),
        stand: 1.0,
        base_height_m: WALK_HEIGHT_M,
        waist: [0.0; 3],
        upper,
    }
}

/// The reference offsets a FALCON policy asks for, in [`commands`]' order.
pub fn reference_offsets_s() -> Vec<f64> {
    std::iter::once(REF_AHEAD_S)
        .chain(WINDOW_OFFSETS_S)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Isometry3, Translation3};

    fn frame(yaw: f64, v: [f64; 3], yaw_rate: f64, z: f64) -> ReferenceFrame {
        let mut joint_pos = vec![0.0; 29];
        joint_pos[12] = 0.4;
        joint_pos[15] = 0.3;
        ReferenceFrame {
            world_from_root: Isometry3::from_parts(
                Translation3::new(0.0, 0.0, z),
                UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
            ),
            root_lin_vel_w: Vector3::from(v),
            root_ang_vel_w: Vector3::new(0.0, 0.0, yaw_rate),
            joint_pos,
            joint_vel: vec![0.0; 29],
            force_sensor: [Vector3::zeros(); 2],
        }
    }

    fn robot(yaw: f64) -> RootState {
        RootState::at_rest(Isometry3::from_parts(
            Translation3::new(0.0, 0.0, 0.78),
            UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
        ))
    }

    #[test]
    fn a_walk_is_commanded_in_the_robots_heading_frame_with_heading_feedback() {
        // The reference walks +x at 0.5 m/s facing +x; the robot faces 90° left of it.
        let refs = vec![frame(0.0, [0.5, 0.0, 0.0], 0.0, 0.78); 11];
        let c = commands(&robot(std::f64::consts::FRAC_PI_2), &refs, None);
        assert_eq!(c.stand, 1.0);
        assert!((c.lin_vel[0]).abs() < 1e-12 && (c.lin_vel[1] + 0.5).abs() < 1e-12);
        // Turn right: 0.5 · (0 − π/2), clipped to −1.
        assert!((c.ang_vel + 0.5 * std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert_eq!(c.base_height_m, WALK_HEIGHT_M);
        assert_eq!(c.waist, [0.0; 3]);
        assert_eq!(c.upper[0], 0.3);
    }

    #[test]
    fn standing_zeroes_the_velocities_and_passes_height_and_waist_yaw() {
        let refs = vec![frame(0.0, [0.01, 0.0, 0.0], 0.0, 0.62); 11];
        let c = commands(&robot(0.0), &refs, None);
        assert_eq!(c.stand, 0.0);
        assert_eq!((c.lin_vel, c.ang_vel), ([0.0; 2], 0.0));
        assert_eq!(c.base_height_m, 0.62);
        assert_eq!(c.waist, [0.4, 0.0, 0.0]);
        let tall = vec![frame(0.0, [0.0; 3], 0.0, 0.8); 11];
        assert_eq!(commands(&robot(0.0), &tall, None).base_height_m, 0.75);
    }

    #[test]
    fn the_stand_flag_has_hysteresis() {
        let slow = vec![frame(0.0, [0.1, 0.0, 0.0], 0.0, 0.78); 11];
        assert_eq!(commands(&robot(0.0), &slow, None).stand, 0.0);
        assert_eq!(commands(&robot(0.0), &slow, Some(false)).stand, 0.0);
        assert_eq!(commands(&robot(0.0), &slow, Some(true)).stand, 1.0);
        let still = vec![frame(0.0, [0.05, 0.0, 0.0], 0.1, 0.78); 11];
        assert_eq!(commands(&robot(0.0), &still, Some(true)).stand, 0.0);
    }

    #[test]
    fn wrap_to_pi_wraps() {
        assert!(
            (wrap_to_pi(3.0 * std::f64::consts::PI / 2.0) + std::f64::consts::FRAC_PI_2).abs()
                < 1e-12
        );
        assert!((wrap_to_pi(-0.3) + 0.3).abs() < 1e-12);
    }
}
