//! Force profile building blocks: raised-cosine envelopes, short pulses, slow random
//! fluctuations and sensor noise, all drawn from the sequence's seeded generator.
//!
//! Calibration. Real task forces (SOURCES.md, Task forces) are wiping 5–30 N, lifting
//! 20–40 N per hand, chairs 15–50 N sustained and 50–100 N break-away, carrying 10–50 N;
//! but a policy trained without forces survives a steady 10 N/hand push only 75 % of the
//! time (20 N: 41 %, 30 N: 30 %; SOURCES.md, push probe), while the paper's TWIST2 kept
//! 0.94 survival under the recorded forces. The synthetic levels are therefore scaled
//! down: wiping presses 5–12 N with 3–8 N friction against the stroke; lifting holds
//! 12–22 N per hand, vertical, only while grasped; chairs 8–18 N per hand against the
//! walking direction (modulated by the gait) with one or two 0.2–0.5 s break-away peaks
//! of 30–60 N; carrying 5–10 N vertical plus a partner's ±10 N along the walk with a few
//! tugs. Onsets and releases are raised-cosine ramps of 0.2–0.6 s. Sensor noise:
//! σ = 0.3 N white plus a slow bias drift (0.2–0.6 N).

use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use std::f64::consts::PI;

/// Raised-cosine step: 0 for `x ≤ 0`, 1 for `x ≥ 1`, C¹ in between.
pub fn rc(x: f64) -> f64 {
    0.5 - 0.5 * (PI * x.clamp(0.0, 1.0)).cos()
}

/// Contact window: rises from 0 at `on` to 1 at `on + rise`, falls from 1 at `off` to 0 at
/// `off + fall` (raised-cosine onsets and releases rather than force steps, which no
/// sensor records).
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct Window {
    /// Start of the onset, s.
    pub on: f64,
    /// Onset duration, s.
    pub rise: f64,
    /// Start of the release, s.
    pub off: f64,
    /// Release duration, s.
    pub fall: f64,
}

impl Window {
    /// Envelope value at `t`, 0…1.
    pub fn at(&self, t: f64) -> f64 {
        rc((t - self.on) / self.rise) * (1.0 - rc((t - self.off) / self.fall))
    }
}

/// Short bump of `width` seconds centred at `t0`, peak 1 (a break-away peak).
pub fn pulse(t: f64, t0: f64, width: f64) -> f64 {
    let x = (t - t0) / width;
    if x.abs() >= 0.5 {
        0.0
    } else {
        0.5 + 0.5 * (2.0 * PI * x).cos()
    }
}

/// A smooth random signal: a few sinusoids with random frequencies and phases, scaled so
/// that its amplitude never exceeds `amp`.
#[derive(Debug, Clone)]
pub struct Wobble {
    parts: Vec<(f64, f64, f64)>,
}

impl Wobble {
    /// Frequencies drawn from `f_lo..f_hi` Hz.
    pub fn new(rng: &mut ChaCha8Rng, f_lo: f64, f_hi: f64, amp: f64) -> Self {
        let n = 3;
        let weights: Vec<f64> = (0..n).map(|_| rng.random_range(0.3..1.0)).collect();
        let total: f64 = weights.iter().sum();
        let parts = weights
            .iter()
            .map(|w| {
                (
                    amp * w / total,
                    2.0 * PI * rng.random_range(f_lo..f_hi),
                    rng.random_range(0.0..2.0 * PI),
                )
            })
            .collect();
        Self { parts }
    }

    /// Value at `t`, within ±amp.
    pub fn at(&self, t: f64) -> f64 {
        self.parts
            .iter()
            .map(|(a, w, p)| a * (w * t + p).sin())
            .sum()
    }
}

/// Sensor imperfections of one hand: white noise σ ≈ 0.3 N per axis plus a slow bias
/// drift of up to `drift` N per axis (strain-gauge offsets wander with temperature).
#[derive(Debug, Clone)]
pub struct SensorNoise {
    sigma_n: f64,
    drift: [Wobble; 3],
}

impl SensorNoise {
    /// Draws the drift of the three axes.
    pub fn new(rng: &mut ChaCha8Rng, sigma_n: f64, drift_n: f64) -> Self {
        Self {
            sigma_n,
            drift: [0, 1, 2].map(|_| Wobble::new(rng, 0.01, 0.05, drift_n)),
        }
    }

    /// Noise to add at time `t` (one Gaussian draw per axis).
    pub fn sample(&self, rng: &mut ChaCha8Rng, t: f64) -> [f64; 3] {
        [0, 1, 2].map(|a| {
            let g: f64 = StandardNormal.sample(rng);
            self.sigma_n * g + self.drift[a].at(t)
        })
    }
}

/// The force levels a generator version draws from, N (per hand unless named *total*).
///
/// Version 1 scales the real levels down (see above). Version 2 draws them at the real
/// levels of SOURCES.md, "Task forces": wiping presses 10–22 N per wiping hand, friction
/// 0.3–0.5 of it, so the hand's force stays in the 5–30 N range with its ±10 % wobble; a 4–8 kg container weighs 20–40 N on each
/// hand; a chair takes 30–50 N in total to keep moving and 60–100 N in total to break
/// loose; a carried object shared with a partner puts 10–30 N of its weight on both hands
/// together and the partner pushes or pulls up to 25 N, with tugs to 40 N, each hand's force
/// held at 25 N so the two stay within the 10–50 N range; a lifting hand holds at most 40 N.
/// The motions carry them ([`super::balance`]).
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct Levels {
    /// Generator version these belong to.
    pub version: u32,
    /// Wiping: the table's push on a wiping hand.
    pub press: (f64, f64),
    /// Wiping: friction against the stroke (v1: N; v2: a fraction of the press).
    pub friction: (f64, f64),
    /// Lifting: the container's weight on each hand.
    pub lift: (f64, f64),
    /// Chairs: the sustained level (v1: per hand; v2: total of both hands).
    pub chair_sustained: (f64, f64),
    /// Chairs: the break-away peak (v1: per hand; v2: total of both hands).
    pub chair_peak: (f64, f64),
    /// Carrying: the weight share (v1: per hand; v2: total of both hands).
    pub carry_vertical: (f64, f64),
    /// Carrying: the partner's push or pull, amplitude (v1: per hand; v2: total).
    pub carry_partner: (f64, f64),
    /// Carrying: a partner's tug (v1: per hand; v2: total).
    pub carry_tug: (f64, f64),
    /// Lifting: the most one hand holds, N (v2: the cited 40 N per hand). A dominant hand's
    /// share of a heavy container, with the lift's acceleration, would pass it: the excess
    /// goes to the other hand, up to the same bound. None in v1, whose forces never reach it.
    pub lift_hand_max: Option<f64>,
    /// Carrying: the most one hand's force reaches, N (v2: 25 N, so both hands stay within
    /// the cited 10–50 N while a tug meets the partner's push). None in v1.
    pub carry_hand_max: Option<f64>,
}

impl Levels {
    /// The levels of generator version `version` (1 or 2).
    pub fn of(version: u32) -> Self {
        if version >= 2 {
            Self {
                version,
                press: (10.0, 22.0),
                friction: (0.3, 0.5),
                lift: (20.0, 40.0),
                chair_sustained: (30.0, 50.0),
                chair_peak: (60.0, 100.0),
                carry_vertical: (10.0, 30.0),
                carry_partner: (10.0, 25.0),
                carry_tug: (25.0, 40.0),
                lift_hand_max: Some(40.0),
                carry_hand_max: Some(25.0),
            }
        } else {
            Self {
                version,
                press: (5.0, 12.0),
                friction: (3.0, 8.0),
                lift: (12.0, 22.0),
                chair_sustained: (8.0, 18.0),
                chair_peak: (30.0, 60.0),
                carry_vertical: (5.0, 10.0),
                carry_partner: (6.0, 10.0),
                carry_tug: (6.0, 10.0),
                lift_hand_max: None,
                carry_hand_max: None,
            }
        }
    }

    /// A per-hand level from a range that version 2 gives as a total of both hands.
    pub fn per_hand(&self, total_or_hand: f64) -> f64 {
        if self.version >= 2 {
            0.5 * total_or_hand
        } else {
            total_or_hand
        }
    }
}

/// Two hands' loads `want` (N, left and right) with neither above `max`: what one hand
/// cannot hold goes to the other, up to the same bound (the total is kept while it fits
/// in two hands).
pub fn shared_within(want: [f64; 2], max: Option<f64>) -> [f64; 2] {
    let Some(m) = max else { return want };
    [
        (want[0] + (want[1] - m).max(0.0)).min(m),
        (want[1] + (want[0] - m).max(0.0)).min(m),
    ]
}

/// A level drawn uniformly from `range` (N), kept for provenance.
pub fn level(rng: &mut ChaCha8Rng, range: (f64, f64)) -> f64 {
    rng.random_range(range.0..range.1)
}

#[cfg(test)]
mod tests {
    use super::shared_within;

    #[test]
    fn a_hand_over_its_bound_passes_the_excess_to_the_other_up_to_the_same_bound() {
        assert_eq!(shared_within([50.0, 20.0], None), [50.0, 20.0]);
        assert_eq!(shared_within([30.0, 20.0], Some(40.0)), [30.0, 20.0]);
        assert_eq!(shared_within([50.0, 20.0], Some(40.0)), [40.0, 30.0]);
        assert_eq!(shared_within([20.0, 55.0], Some(40.0)), [35.0, 40.0]);
        // More than both hands can hold: each at the bound.
        assert_eq!(shared_within([60.0, 30.0], Some(40.0)), [40.0, 40.0]);
    }
}
