//! FALCON's commands derived from a reference motion, step by step: what a teleoperator's
//! joystick gives the released deploy (`sim2real/rl_policy/base_policy.py:379-387`,
//! `loco_manip.py`), here read off the motion the benchmark asks the robot to follow.
//!
//! The network was trained on commands resampled every 10 s (piecewise constant) while the
//! pelvis of a walking human sways inside each gait cycle, so the velocities are averaged
//! over the reference's next gait period ([`WINDOW_OFFSETS_S`], FALCON's `GAIT_PERIOD:
//! 0.9` s, `cfg:35`): the command says where the motion is going, not how the pelvis
//! wobbles. Training's sampler is LeCAR-Lab/FALCON,
//! `decoupled_locomotion_stand_height_waist_wbc_ma.py` (`_resample_commands`,
//! `_update_tasks_callback`):
//!
//! | command | from the reference | training |
//! |---|---|---|
//! | `command_lin_vel` | mean root velocity over the window, in the **robot's** heading frame | ±1 m/s per axis, zeroed when its norm is ≤ 0.2 m/s |
//! | `command_ang_vel` | mean yaw rate over the window + 0.5 · wrapped heading error to the reference's heading | 0.5 · wrapped heading error to a heading target, ±1 rad/s |
//! | `command_stand` | 1 (walk) when the window moves, with hysteresis ([`STAND_HYSTERESIS`]) | 1 = walk, 0 = stance |
//! | `command_base_height` | 0.75 m walking; the reference pelvis height standing | 0.75; 0.50–0.75 |
//! | `command_waist_dofs` | (0, 0, 0) walking; (reference waist yaw, 0, 0) standing | yaw ±1 in stance only; roll, pitch 0 |
//! | `ref_upper_dof_pos` | the reference's 14 arm joints one control step ahead, wrists included | retargeted AMASS arms, every step |
//!
//! **Three exceptions to training's distribution**, each a [`CommandRules`] field so that
//! its cost is measured rather than argued (`falcon:F.onnx@min_speed=0.2,yaw_ff=0,hold=10`;
//! docs/policies.md has the numbers):
//! - speeds under 0.2 m/s are commanded as they are (training zeroes them): the synthetic
//!   gait walks at 0.2–0.35 m/s with slow starts and stops, and a zeroed command leaves
//!   the robot stepping in place while the reference walks away;
//! - the yaw rate has a feed-forward term, the reference's own turning, on top of
//!   training's heading feedback: feedback alone lags a turning motion by its rate / 0.5;
//! - the commands change every step (training holds a sample for 10 s; the deploy's
//!   joystick changes them whenever the operator moves it). A reference motion's
//!   velocity and heading change within seconds; holding them for 10 s would not follow it.
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
/// Training zeroes a sampled velocity command whose norm is at most this, m/s.
pub const TRAINING_MIN_SPEED_M_S: f64 = 0.2;
/// Training holds a command sample this long, s (`locomotion_command_resampling_time`).
pub const TRAINING_HOLD_S: f64 = 10.0;
/// The stand flag turns to walk above (speed m/s, |yaw rate| rad/s) and back to stance
/// below both of the second pair: a motion that pauses briefly does not flicker.
pub const STAND_HYSTERESIS: [(f64, f64); 2] = [(0.15, 0.3), (0.08, 0.15)];

/// How the commands leave or keep training's distribution (the module's three
/// exceptions). [`CommandRules::BENCHMARK`] is FALCON on the board; any other value is
/// an ablation, recorded in `run.json` as the policy's parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CommandRules {
    /// Velocity commands whose norm is at most this are zeroed, m/s (training: 0.2).
    pub min_speed_m_s: f64,
    /// Scale of the reference's yaw rate added to the heading feedback (training: 0).
    pub yaw_feedforward: f64,
    /// A command sample is held this long, s; 0 samples every step (training: 10). The
    /// heading feedback and the arm references still follow every step.
    pub hold_s: f64,
}

impl CommandRules {
    /// The commands the benchmark gives FALCON.
    pub const BENCHMARK: Self = Self {
        min_speed_m_s: 0.0,
        yaw_feedforward: 1.0,
        hold_s: 0.0,
    };
}

impl Default for CommandRules {
    fn default() -> Self {
        Self::BENCHMARK
    }
}

/// One sample of the commands a [`CommandRules::hold_s`] keeps: all but the yaw rate's
/// feedback and the arm references, which follow every step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// (v_x, v_y) in the robot's heading frame at the sample, m/s.
    pub lin_vel: [f64; 2],
    /// The yaw rate's feed-forward, rad/s.
    pub yaw_rate_ff: f64,
    /// The heading the feedback turns toward, rad (world yaw).
    pub heading_target_rad: f64,
    /// Walking (the stand flag 1) or standing.
    pub walking: bool,
    /// Pelvis height, m.
    pub base_height_m: f64,
    /// Waist yaw, roll, pitch, rad.
    pub waist: [f64; 3],
}

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

/// A command sample for a robot at `root` following `reference` (the frames at
/// [`REF_AHEAD_S`] and then [`WINDOW_OFFSETS_S`]), given whether it walked at the step
/// before (`None` at an episode's first step).
pub fn sample(
    root: &RootState,
    reference: &[ReferenceFrame],
    walking_before: Option<bool>,
    rules: &CommandRules,
) -> Sample {
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
    let heading_target_rad = yaw(&ahead.world_from_root.rotation);
    if !walking {
        return Sample {
            lin_vel: [0.0; 2],
            yaw_rate_ff: 0.0,
            heading_target_rad,
            walking,
            base_height_m: ahead
                .world_from_root
                .translation
                .z
                .clamp(MIN_HEIGHT_M, WALK_HEIGHT_M),
            waist: [ahead.joint_pos[WAIST[0]].clamp(-1.0, 1.0), 0.0, 0.0],
        };
    }
    let lin_vel = if speed <= rules.min_speed_m_s {
        [0.0; 2]
    } else {
        [
            v.x.clamp(-MAX_LIN_VEL, MAX_LIN_VEL),
            v.y.clamp(-MAX_LIN_VEL, MAX_LIN_VEL),
        ]
    };
    Sample {
        lin_vel,
        yaw_rate_ff: rules.yaw_feedforward * mean_yaw_rate,
        heading_target_rad,
        walking,
        base_height_m: WALK_HEIGHT_M,
        waist: [0.0; 3],
    }
}

/// One step's commands for a robot at `root` under `sample`: the yaw rate fed back toward
/// the sample's heading from where the robot faces now, the arm joints from `reference`'s
/// first frame.
pub fn commands(root: &RootState, reference: &[ReferenceFrame], sample: &Sample) -> Commands {
    let mut upper = [0.0; 14];
    upper.copy_from_slice(&reference[0].joint_pos[UPPER]);
    let ang_vel = if sample.walking {
        let heading_error =
            wrap_to_pi(sample.heading_target_rad - yaw(&root.world_from_root.rotation));
        (sample.yaw_rate_ff + HEADING_GAIN * heading_error).clamp(-MAX_YAW_RATE, MAX_YAW_RATE)
    } else {
        0.0
    };
    Commands {
        lin_vel: sample.lin_vel,
        ang_vel,
        stand: if sample.walking { 1.0 } else { 0.0 },
        base_height_m: sample.base_height_m,
        waist: sample.waist,
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

    /// The benchmark's commands sampled and applied at the same step.
    fn now(root: &RootState, refs: &[ReferenceFrame], walking: Option<bool>) -> Commands {
        commands(
            root,
            refs,
            &sample(root, refs, walking, &CommandRules::BENCHMARK),
        )
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
        let c = now(&robot(std::f64::consts::FRAC_PI_2), &refs, None);
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
        let c = now(&robot(0.0), &refs, None);
        assert_eq!(c.stand, 0.0);
        assert_eq!((c.lin_vel, c.ang_vel), ([0.0; 2], 0.0));
        assert_eq!(c.base_height_m, 0.62);
        assert_eq!(c.waist, [0.4, 0.0, 0.0]);
        let tall = vec![frame(0.0, [0.0; 3], 0.0, 0.8); 11];
        assert_eq!(now(&robot(0.0), &tall, None).base_height_m, 0.75);
    }

    #[test]
    fn the_stand_flag_has_hysteresis() {
        let slow = vec![frame(0.0, [0.1, 0.0, 0.0], 0.0, 0.78); 11];
        assert_eq!(now(&robot(0.0), &slow, None).stand, 0.0);
        assert_eq!(now(&robot(0.0), &slow, Some(false)).stand, 0.0);
        assert_eq!(now(&robot(0.0), &slow, Some(true)).stand, 1.0);
        let still = vec![frame(0.0, [0.05, 0.0, 0.0], 0.1, 0.78); 11];
        assert_eq!(now(&robot(0.0), &still, Some(true)).stand, 0.0);
    }

    #[test]
    fn trainings_rules_zero_slow_walks_and_drop_the_feed_forward() {
        let trained = CommandRules {
            min_speed_m_s: TRAINING_MIN_SPEED_M_S,
            yaw_feedforward: 0.0,
            hold_s: 0.0,
        };
        // Walking at 0.18 m/s while turning 0.4 rad/s, the robot 0.2 rad right of the
        // reference's heading.
        let refs = vec![frame(0.2, [0.18, 0.0, 0.0], 0.4, 0.78); 11];
        let s = sample(&robot(0.0), &refs, None, &trained);
        assert!(s.walking, "the yaw rate keeps it walking");
        assert_eq!(s.lin_vel, [0.0; 2]);
        let c = commands(&robot(0.0), &refs, &s);
        assert!((c.ang_vel - HEADING_GAIN * 0.2).abs() < 1e-12);
        // The benchmark's: the speed as it is and the reference's turning fed forward.
        let b = now(&robot(0.0), &refs, None);
        assert!((b.lin_vel[0] - 0.18).abs() < 1e-12);
        assert!((b.ang_vel - (0.4 + HEADING_GAIN * 0.2)).abs() < 1e-12);
    }

    #[test]
    fn a_held_sample_still_feeds_the_heading_back_every_step() {
        let refs = vec![frame(0.5, [0.5, 0.0, 0.0], 0.0, 0.78); 11];
        let s = sample(&robot(0.0), &refs, None, &CommandRules::BENCHMARK);
        // The robot has since turned 0.3 rad toward the target: less to turn.
        let later = commands(&robot(0.3), &refs, &s);
        assert!((later.ang_vel - HEADING_GAIN * 0.2).abs() < 1e-12);
        assert_eq!(later.lin_vel, s.lin_vel);
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
