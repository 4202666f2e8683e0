//! Built-in baselines for the `default` profile (action = joint target − default pose).
//!
//! - `hold`: keeps the default pose whatever the reference does. A floor for scores.
//! - `replay`: plays the reference joint angles open loop as PD targets. No balance
//!   feedback at all: it tracks standing motions and falls on anything dynamic.

use super::{Observation, Policy};

/// Holds the default pose (zero action).
#[derive(Debug, Default)]
pub struct HoldPolicy;

impl Policy for HoldPolicy {
    fn name(&self) -> &str {
        "hold"
    }

    fn act(&mut self, _observations: &[Observation], actions: &mut [Vec<f64>]) {
        actions.iter_mut().for_each(|a| a.fill(0.0));
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

    fn act(&mut self, observations: &[Observation], actions: &mut [Vec<f64>]) {
        for (obs, action) in observations.iter().zip(actions.iter_mut()) {
            let reference = &obs.reference[0].joint_pos;
            for ((a, r), d) in action.iter_mut().zip(reference).zip(&self.default_pose) {
                *a = r - d;
            }
        }
    }
}
