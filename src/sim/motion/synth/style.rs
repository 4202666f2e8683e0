//! A person's style, drawn once per version-2 sequence: how fast and wide they walk and
//! stand, whether they bend at the hips or the waist, where they hold things, which hand
//! does more, and how their force builds, trembles and breaks loose. Every task reads the
//! same style, so the sixty sequences of a task differ the way sixty people would, not
//! only in the task's own ranges. `data check` measures the result (its "Style" table;
//! docs/data-card.md has the distributions).
//!
//! Drawn from its own generator (the sequence's seed with [`STYLE_STREAM`]), so the task
//! draws keep their order; version 1 takes [`Style::neutral`], which changes no number.

use super::skeleton::Skeleton;
use super::tasks::stance_feet;
use nalgebra::{Isometry3, Translation3};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

/// Mixed into a sequence's seed to give its style a stream of its own.
pub const STYLE_STREAM: u64 = 0x5354_594C_4521_0002;

/// Share of left-handed people: about one in ten (M. Papadatou-Pastou et al., "Human
/// handedness: A meta-analysis", Psychological Bulletin 146(6), 2020).
const LEFT_HANDED_SHARE: f64 = 0.1;

/// One person's way of doing the tasks. [`Style::neutral`] is version 1's generator.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Style {
    /// The dominant hand: `"left"`, `"right"`, or `"none"` (neutral).
    pub dominant_hand: &'static str,
    /// How much more the dominant hand carries: added to its share of a two-handed load
    /// (0 to 0.15: 50/50 to 65/35).
    pub dominance: f64,
    /// Speed of movement: steps and bends take 1/tempo of their drawn time (0.8–1.25).
    pub tempo: f64,
    /// Step length scale (0.85–1.15), capped where the legs leave their workspace even
    /// with the trailing foot rolling off ([`MAX_STEP_FORWARD_M`], [`MAX_STEP_BACKWARD_M`]).
    pub stride: f64,
    /// Added to the half-width between the feet, standing and walking, m (−0.015–0.04).
    pub width_m: f64,
    /// Standing: the leading foot ahead of the other, m (0–0.12).
    pub stagger_m: f64,
    /// Standing: the leading foot is the left one.
    pub left_foot_leads: bool,
    /// Bending at the hips rather than the waist: the pelvis pitch is scaled by it, the
    /// waist pitch by 2 − it (0.6–1.4).
    pub hip_share: f64,
    /// Added to where the hands hold a carried object or a chair, m (−0.04–0.04).
    pub hand_height_m: f64,
    /// How slowly a grip's force builds and releases: onsets scale by it (0.6–2).
    pub build: f64,
    /// How much a held force trembles: its fluctuations scale by it (0.5–2).
    pub tremble: f64,
    /// How long a chair's break-away shove lasts: its width scales by it (0.7–1.5).
    pub break_width: f64,
}

/// The longest forward step a style stretches a drawn one to, m: the trailing foot rolls
/// off its toe (a flat one meets its ankle's dorsiflexion limit near 0.27 m).
pub const MAX_STEP_FORWARD_M: f64 = 0.38;
/// The longest backward step, m (the feet stay flat walking backward).
pub const MAX_STEP_BACKWARD_M: f64 = 0.22;

impl Style {
    /// No style: every scale 1, every offset 0 — version 1's numbers exactly.
    pub fn neutral() -> Self {
        Self {
            dominant_hand: "none",
            dominance: 0.0,
            tempo: 1.0,
            stride: 1.0,
            width_m: 0.0,
            stagger_m: 0.0,
            left_foot_leads: false,
            hip_share: 1.0,
            hand_height_m: 0.0,
            build: 1.0,
            tremble: 1.0,
            break_width: 1.0,
        }
    }

    /// A person drawn from `rng`.
    pub fn draw(rng: &mut ChaCha8Rng) -> Self {
        let left = rng.random_bool(LEFT_HANDED_SHARE);
        Self {
            dominant_hand: if left { "left" } else { "right" },
            dominance: rng.random_range(0.0..0.15),
            tempo: rng.random_range(0.8..1.25),
            stride: rng.random_range(0.85..1.15),
            width_m: rng.random_range(-0.015..0.04),
            stagger_m: rng.random_range(0.0..0.12),
            left_foot_leads: rng.random_bool(0.5),
            hip_share: rng.random_range(0.6..1.4),
            hand_height_m: rng.random_range(-0.04..0.04),
            build: rng.random_range(0.6..2.0),
            tremble: rng.random_range(0.5..2.0),
            break_width: rng.random_range(0.7..1.5),
        }
    }

    /// The dominant hand's index (0 left, 1 right), `None` when neutral.
    pub fn dominant(&self) -> Option<usize> {
        match self.dominant_hand {
            "left" => Some(0),
            "right" => Some(1),
            _ => None,
        }
    }

    /// What the left hand's share of a two-handed load gains (negative: loses).
    pub fn left_bias(&self) -> f64 {
        match self.dominant() {
            Some(0) => self.dominance,
            Some(_) => -self.dominance,
            None => 0.0,
        }
    }

    /// A per-hand force scaled so the dominant hand carries more: side 0 left, 1 right.
    pub fn hand_scale(&self, side: usize) -> f64 {
        let b = 2.0 * self.left_bias();
        if side == 0 {
            1.0 + b
        } else {
            1.0 - b
        }
    }

    /// The pelvis pitch of a drawn bend.
    pub fn pelvis_pitch(&self, drawn: f64) -> f64 {
        drawn * self.hip_share
    }

    /// The waist pitch of a drawn bend.
    pub fn waist_pitch(&self, drawn: f64) -> f64 {
        drawn * (2.0 - self.hip_share)
    }

    /// A step length, capped for the direction of walking (+1 forward).
    pub fn step_length(&self, drawn: f64, direction: f64) -> f64 {
        let cap = if direction > 0.0 {
            MAX_STEP_FORWARD_M
        } else {
            MAX_STEP_BACKWARD_M
        };
        (drawn * self.stride).min(cap.max(drawn))
    }

    /// Both standing feet, wider by [`Style::width_m`] and staggered.
    pub fn stance_feet(&self, sk: &Skeleton) -> [Isometry3<f64>; 2] {
        let mut feet = stance_feet(sk);
        if *self == Self::neutral() {
            return feet;
        }
        for (s, foot) in feet.iter_mut().enumerate() {
            let side = if s == 0 { 1.0 } else { -1.0 };
            let leads = (s == 0) == self.left_foot_leads;
            let ahead = if leads { 0.5 } else { -0.5 } * self.stagger_m;
            foot.translation = Translation3::from(
                foot.translation.vector + nalgebra::Vector3::new(ahead, side * self.width_m, 0.0),
            );
        }
        feet
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn the_neutral_style_changes_no_number() {
        let n = Style::neutral();
        for x in [0.0, 0.123_456_789, -3.5, 1e-9] {
            assert_eq!(n.pelvis_pitch(x), x);
            assert_eq!(n.waist_pitch(x), x);
        }
        assert_eq!(n.step_length(0.21, 1.0), 0.21);
        assert_eq!(n.hand_scale(0), 1.0);
        assert_eq!(n.hand_scale(1), 1.0);
        assert_eq!(n.left_bias(), 0.0);
    }

    #[test]
    fn the_dominant_hand_carries_more_and_steps_stay_under_their_caps() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let mut lefties = 0;
        for _ in 0..2000 {
            let s = Style::draw(&mut rng);
            let d = s.dominant().unwrap();
            assert!(s.hand_scale(d) >= s.hand_scale(1 - d));
            assert!(s.step_length(0.25, 1.0) <= MAX_STEP_FORWARD_M);
            assert!(s.step_length(0.21, -1.0) <= MAX_STEP_BACKWARD_M);
            lefties += usize::from(d == 0);
        }
        assert!(
            (150..250).contains(&lefties),
            "{lefties} of 2000 left-handed"
        );
    }
}
