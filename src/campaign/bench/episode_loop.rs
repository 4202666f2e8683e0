//! The whole episode loop on one core: simulated seconds per wall second, and the share
//! of the time spent outside the physics step (force replay, metrics, policy,
//! bookkeeping) — what batching and overlap can win at most.

use crate::eval::episode::{Episode, EpisodeSetup};
use crate::policy::Policy;
use crate::sim::motion::Sequence;
use crate::sim::physics::Physics;
use std::time::{Duration, Instant};

/// One pass over a set of sequences.
#[derive(Debug, Clone, PartialEq)]
pub struct EpisodeLoopTiming {
    /// Episodes run.
    pub episodes: usize,
    /// Seconds simulated.
    pub simulated_s: f64,
    /// Wall time of the loop.
    pub wall: Duration,
    /// Of it, inside the physics step.
    pub in_physics: Duration,
}

impl EpisodeLoopTiming {
    /// Simulated seconds per wall second.
    pub fn real_time_factor(&self) -> f64 {
        self.simulated_s / self.wall.as_secs_f64()
    }

    /// The share of wall time outside the physics step, 0–1.
    pub fn outside_physics(&self) -> f64 {
        1.0 - self.in_physics.as_secs_f64() / self.wall.as_secs_f64()
    }
}

/// Runs one episode per sequence with `policy` acting every control step of
/// `control_dt_s`, one after the other on this thread.
pub fn time_episode_loop(
    setup: &EpisodeSetup,
    sequences: &[Sequence],
    policy: &mut dyn Policy,
    physics: &mut dyn Physics,
    control_dt_s: f64,
) -> EpisodeLoopTiming {
    let mut t = EpisodeLoopTiming {
        episodes: sequences.len(),
        simulated_s: 0.0,
        wall: Duration::ZERO,
        in_physics: Duration::ZERO,
    };
    let mut actions = vec![vec![0.0; setup.robot.n_joints()]];
    for seq in sequences {
        let started = Instant::now();
        let mut ep = Episode::start(setup, seq, physics);
        let mut steps = 0usize;
        while !ep.is_done() {
            policy.act(&[ep.observation()], &mut actions);
            ep.advance(physics, &actions[0]);
            steps += 1;
        }
        t.in_physics += ep.physics_wall();
        t.wall += started.elapsed();
        t.simulated_s += steps as f64 * control_dt_s;
    }
    t
}
