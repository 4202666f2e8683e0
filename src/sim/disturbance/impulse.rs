//! Random impulses: pushes of a drawn magnitude and horizontal direction, at drawn times, on
//! the torso or on a drawn hand — the disturbance whole-body trackers are commonly
//! evaluated with (holosoma's `--push.config.force-range 50 200`, amazon-far/holosoma PR
//! #86). Each episode's draws come from the setting's seed and the sequence id alone, so a
//! sequence gets the same pushes in every run, on every engine, whatever ran before it.

use crate::sim::motion::{LEFT, RIGHT};
use nalgebra::Vector3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// Where impulses push.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ImpulseTarget {
    /// The torso, at the torso frame's origin.
    Torso,
    /// One hand per impulse, drawn (`Hand(side)` names the side of a drawn pulse).
    Hands,
    /// Hand `side` ([`LEFT`] or [`RIGHT`]): the target of one drawn pulse.
    Hand(usize),
}

/// Random impulses' specification.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Impulses {
    /// Smallest and largest magnitude, N (uniform between).
    pub force_n: [f64; 2],
    /// How long each acts, constant, s.
    pub duration_s: f64,
    /// Shortest and longest time from one impulse's end (or the start) to the next, s.
    pub interval_s: [f64; 2],
    /// Where they push: [`ImpulseTarget::Torso`] or [`ImpulseTarget::Hands`].
    pub target: ImpulseTarget,
    /// Seed of the draws (with the sequence id).
    pub seed: u64,
}

/// One drawn impulse.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pulse {
    /// When it starts, s from the episode's start.
    pub start_s: f64,
    /// How long it acts, s.
    pub duration_s: f64,
    /// Its constant world-frame force, N (horizontal).
    pub force_w: Vector3<f64>,
    /// What it pushes: the torso or one hand.
    pub target: ImpulseTarget,
}

impl Pulse {
    /// Whether it acts at `t_s` (its start included, its end not).
    pub fn acts_at(&self, t_s: f64) -> bool {
        t_s >= self.start_s && t_s < self.start_s + self.duration_s
    }
}

impl Impulses {
    /// The pulses of an episode of `sequence_id` lasting `duration_s`: from the start, an
    /// interval, a pulse, an interval, … until past the end.
    pub fn draw(&self, sequence_id: &str, duration_s: f64) -> Vec<Pulse> {
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed ^ fnv1a64(sequence_id.as_bytes()));
        let uniform = |rng: &mut ChaCha8Rng, [lo, hi]: [f64; 2]| {
            if hi > lo {
                rng.random_range(lo..hi)
            } else {
                lo
            }
        };
        let mut pulses = Vec::new();
        let mut t = 0.0;
        loop {
            t += uniform(&mut rng, self.interval_s);
            if t >= duration_s || !t.is_finite() {
                return pulses;
            }
            let magnitude = uniform(&mut rng, self.force_n);
            let yaw = rng.random_range(0.0..std::f64::consts::TAU);
            let target = match self.target {
                ImpulseTarget::Hands => {
                    ImpulseTarget::Hand(if rng.random_bool(0.5) { LEFT } else { RIGHT })
                }
                other => other,
            };
            pulses.push(Pulse {
                start_s: t,
                duration_s: self.duration_s,
                force_w: Vector3::new(yaw.cos(), yaw.sin(), 0.0) * magnitude,
                target,
            });
            t += self.duration_s;
        }
    }
}

/// FNV-1a, 64 bits: a sequence id folded into the seed, the same on every platform.
fn fnv1a64(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}
