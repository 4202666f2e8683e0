//! How the report's figures tell things apart: one colour per policy (the same in every
//! chart of a report, and in every report that holds the same policies), line styles
//! (dashes) for other axes of a sweep or a second run of one policy, marker shapes for
//! settings, and the deterministic jitter that keeps episodes at one survival value from
//! hiding each other. The HTML page and the SVG files both take their styles from here.

use std::collections::BTreeMap;

/// Okabe–Ito: readable with the common colour-vision deficiencies and in greyscale print.
pub const PALETTE: [&str; 8] = [
    "#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000", "#F0E442",
];

/// The colour of legend keys that are not a policy (a marker for a setting, a dash for a
/// sweep axis value).
pub const KEY_COLOR: &str = "#4d4d4d";

/// Line dash patterns (lengths in points; empty = solid), indexed by a dataset's `dash`.
pub const DASHES: [&[f64]; 4] = [&[], &[8.0, 4.0], &[2.0, 3.0], &[10.0, 3.0, 2.0, 3.0]];

/// Names of [`DASHES`], for captions.
pub const DASH_NAMES: [&str; 4] = ["solid", "dashed", "dotted", "dash-dot"];

/// Marker shapes (Chart.js `pointStyle` names; the SVG writer draws the same shapes),
/// indexed by a dataset's `marker`.
pub const MARKERS: [&str; 6] = ["circle", "triangle", "rect", "rectRot", "star", "crossRot"];

/// Half-width of the horizontal jitter of the tracking-vs-survival scatter, in survival
/// units.
pub const SURVIVAL_JITTER: f64 = 0.03;

/// One colour per policy: policies sorted by name take the palette in order, so a policy
/// keeps its colour across the charts of a report and across reports of the same
/// policies. More policies than colours reuse the palette.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct PolicyColors(BTreeMap<String, &'static str>);

impl PolicyColors {
    /// Colours for these policy names (repeats are one policy).
    pub fn new<'a>(policies: impl IntoIterator<Item = &'a str>) -> Self {
        let mut names: Vec<&str> = policies.into_iter().collect();
        names.sort_unstable();
        names.dedup();
        Self(
            names
                .into_iter()
                .enumerate()
                .map(|(i, p)| (p.to_string(), PALETTE[i % PALETTE.len()]))
                .collect(),
        )
    }

    /// The colour of `policy` (a policy not given to [`PolicyColors::new`] gets the key
    /// colour).
    pub fn get(&self, policy: &str) -> &'static str {
        self.0.get(policy).copied().unwrap_or(KEY_COLOR)
    }

    /// Policies and their colours, sorted by name.
    pub fn iter(&self) -> impl Iterator<Item = (&str, &'static str)> {
        self.0.iter().map(|(p, c)| (p.as_str(), *c))
    }
}

/// A deterministic value in `[-1, 1)` from `key` (FNV-1a, then the SplitMix64 finalizer so
/// keys differing in their last byte spread over the whole range): the same episode lands
/// on the same spot in every report.
pub fn jitter(key: &str) -> f64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in key.bytes() {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h ^= h >> 30;
    h = h.wrapping_mul(0xbf58_476d_1ce4_e5b9);
    h ^= h >> 27;
    h = h.wrapping_mul(0x94d0_49bb_1331_11eb);
    h ^= h >> 31;
    // 53 high bits → [0, 1).
    (h >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colours_follow_the_sorted_policy_names_not_their_order() {
        let a = PolicyColors::new(["hold", "balance", "hold"]);
        let b = PolicyColors::new(["balance", "hold"]);
        assert_eq!(a, b);
        assert_eq!(a.get("balance"), PALETTE[0]);
        assert_eq!(a.get("hold"), PALETTE[1]);
        assert_eq!(a.get("unknown"), KEY_COLOR);
    }

    #[test]
    fn jitter_is_deterministic_bounded_and_spread() {
        assert_eq!(jitter("a/b"), jitter("a/b"));
        let v: Vec<f64> = (0..200).map(|i| jitter(&format!("task/seq_{i}"))).collect();
        assert!(v.iter().all(|x| (-1.0..1.0).contains(x)));
        assert!(v.iter().any(|&x| x < -0.5) && v.iter().any(|&x| x > 0.5));
    }
}
