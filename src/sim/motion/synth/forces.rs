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

/// A level drawn uniformly from `range` (N), kept for provenance.
pub fn level(rng: &mut ChaCha8Rng, range: std::ops::Range<f64>) -> f64 {
    rng.random_range(range)
}
