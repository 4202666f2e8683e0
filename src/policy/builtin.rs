//! Built-in baselines for the `default` profile (action = joint target − default pose).
//!
//! - `hold`: keeps the default pose whatever the reference does. A floor for scores.
//! - `replay`: plays the reference joint angles open loop as PD targets. No balance
//!   feedback at all: arm motions alone tip it over within seconds.
//! - `balance`: `replay` plus ankle/hip feedback on the pelvis tilt. Keeps the standing
//!   tasks upright with and without force; it cannot walk, so it falls on the walking tasks.

use super::{ActOutcome, Observation, Policy};

/// Holds the default pose (zero action).
#[derive(Debug, Default)]
pub struct HoldPolicy;

impl Policy for HoldPolicy {
    fn name(&self) -> &str {
        "hold"
    }

    fn act(&mut self, _observations: &[Observation], actions: &mut [Vec<f64>]) -> ActOutcome {
        actions.iter_mut().for_each(|a| a.fill(0.0));
        ActOutcome::Acted
    }
}

/// Reference joint angles as targets, open loop.
#[derive(Debug)]
pub struct ReplayPolicy {
    default_pose: Vec<f64>,
}

impl ReplayPolicy {
    /// For a robot with this default pose (the `default` profile's action offset).
    pub fn new(default_pose: Vec<f64>) -> Self {
        Self { default_pose }
    }
}

impl Policy for ReplayPolicy {
    fn name(&self) -> &str {
        "replay"
    }

    fn act(&mut self, observations: &[Observation], actions: &mut [Vec<f64>]) -> ActOutcome {
        for (obs, action) in observations.iter().zip(actions.iter_mut()) {
            let reference = &obs.reference[0].joint_pos;
            for ((a, r), d) in action.iter_mut().zip(reference).zip(&self.default_pose) {
                *a = r - d;
            }
        }
        ActOutcome::Acted
    }
}

/// Reference joints as targets plus ankle and hip feedback on the pelvis tilt: a simple
/// stabiliser, not a learned controller.
///
/// The pelvis roll/pitch error against the reference (in the heading frame) and the base
/// angular rate shift the ankle and hip targets so the feet push the body back upright (an
/// ankle/hip strategy). It keeps standing motions upright without force; it does not walk.
#[derive(Debug)]
pub struct BalancePolicy {
    default_pose: Vec<f64>,
    /// Joint indices: (ankle pitch, ankle roll, hip pitch, hip roll) for left and right.
    legs: [[usize; 4]; 2],
    /// Feedback gains: ankle per rad of tilt, ankle per rad/s, hip per rad of tilt.
    gains: BalanceGains,
}

/// Gains of [`BalancePolicy`].
#[derive(Debug, Clone, Copy)]
pub struct BalanceGains {
    /// Ankle target change per rad of pelvis tilt error.
    pub ankle_per_rad: f64,
    /// Ankle target change per rad/s of pelvis angular rate.
    pub ankle_per_rad_s: f64,
    /// Hip target change per rad of pelvis tilt error.
    pub hip_per_rad: f64,
}

impl Default for BalanceGains {
    /// Chosen on the bundled sample (no force): 1.0 / 0.1 / 0.5 and 2.0 / 0.2 / 1.0 both keep
    /// the standing tasks at survival 1.0; the opposite signs fall within seconds.
    fn default() -> Self {
        Self {
            ankle_per_rad: 1.0,
            ankle_per_rad_s: 0.1,
            hip_per_rad: 0.5,
        }
    }
}

impl BalancePolicy {
    /// For a robot (joint names) with the given default pose (the profile's action offset).
    pub fn new(
        robot: &crate::sim::robot::RobotModel,
        default_pose: Vec<f64>,
        gains: BalanceGains,
    ) -> Option<Self> {
        let idx = |n: &str| robot.joint_index(n);
        let side = |s: &str| -> Option<[usize; 4]> {
            Some([
                idx(&format!("{s}_ankle_pitch_joint"))?,
                idx(&format!("{s}_ankle_roll_joint"))?,
                idx(&format!("{s}_hip_pitch_joint"))?,
                idx(&format!("{s}_hip_roll_joint"))?,
            ])
        };
        Some(Self {
            default_pose,
            legs: [side("left")?, side("right")?],
            gains,
        })
    }
}

/// Roll and pitch of a rotation with its heading (yaw) removed.
fn roll_pitch(q: &nalgebra::UnitQuaternion<f64>) -> (f64, f64) {
    let (roll, pitch, _) = q.euler_angles();
    (roll, pitch)
}

impl Policy for BalancePolicy {
    fn name(&self) -> &str {
        "balance"
    }

    fn act(&mut self, observations: &[Observation], actions: &mut [Vec<f64>]) -> ActOutcome {
        let g = self.gains;
        for (obs, action) in observations.iter().zip(actions.iter_mut()) {
            let reference = &obs.reference[0];
            for ((a, r), d) in action
                .iter_mut()
                .zip(&reference.joint_pos)
                .zip(&self.default_pose)
            {
                *a = r - d;
            }
            let (roll, pitch) = roll_pitch(&obs.root.world_from_root.rotation);
            let (roll_ref, pitch_ref) = roll_pitch(&reference.world_from_root.rotation);
            let w = obs.root.ang_vel_b();
            let (e_roll, e_pitch) = (roll - roll_ref, pitch - pitch_ref);
            for leg in &self.legs {
                action[leg[0]] += g.ankle_per_rad * e_pitch + g.ankle_per_rad_s * w.y;
                action[leg[1]] += g.ankle_per_rad * e_roll + g.ankle_per_rad_s * w.x;
                action[leg[2]] += g.hip_per_rad * e_pitch;
                action[leg[3]] += g.hip_per_rad * e_roll;
            }
        }
        ActOutcome::Acted
    }
}
