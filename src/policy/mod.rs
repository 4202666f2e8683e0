//! The in-process `Policy` trait — batched, so a Rust baseline, a batched Python policy
//! and a C++ policy all see the same loop — and the built-in baselines.

mod builtin;

pub use builtin::{BalanceGains, BalancePolicy, HoldPolicy, ReplayPolicy};

use crate::motion::ReferenceFrame;
use crate::physics::RootState;

/// What a policy sees of one environment at one control step: benchmark signals, not any
/// policy's tensor (adapters build their own from these).
#[derive(Debug, Clone)]
pub struct Observation {
    /// Control step within the episode.
    pub step: usize,
    /// Time since the episode started, s.
    pub time_s: f64,
    /// Root pose and velocity (base-frame velocity and projected gravity via its methods).
    pub root: RootState,
    /// Joint angles, canonical order, rad.
    pub q: Vec<f64>,
    /// Joint velocities, rad/s.
    pub qd: Vec<f64>,
    /// The previous raw action.
    pub last_action: Vec<f64>,
    /// Reference frames at the policy's requested offsets from now.
    pub reference: Vec<ReferenceFrame>,
}

/// A controller driven one control step at a time for a batch of environments.
pub trait Policy {
    /// Name used in results.
    fn name(&self) -> &str;

    /// Times ahead of the current step, s, at which the policy wants reference frames
    /// (TWIST2: `[0.0]`; GMT: 20 frames up to 1.9 s).
    fn reference_offsets_s(&self) -> Vec<f64> {
        vec![0.0]
    }

    /// Environment `env` starts a new episode.
    fn reset(&mut self, _env: usize) {}

    /// One raw action per observation (interpreted by the dynamics profile).
    fn act(&mut self, observations: &[Observation], actions: &mut [Vec<f64>]);
}
