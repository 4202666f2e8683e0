//! Force regimes: every timestep is low, mid or high by its total recorded hand force.

/// A force regime.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Regime {
    /// Total force at or below the 33rd percentile.
    Low,
    /// Above the 33rd, at or below the 66th percentile.
    Mid,
    /// Above the 66th percentile.
    High,
}

impl Regime {
    /// All regimes, low to high.
    pub const ALL: [Regime; 3] = [Regime::Low, Regime::Mid, Regime::High];

    /// Index in [`Regime::ALL`].
    pub fn index(self) -> usize {
        self as usize
    }
}

/// Weights of the regimes in the force-aware error (low, mid, high), from the paper.
pub const REGIME_WEIGHTS: [f64; 3] = [0.2, 0.3, 0.5];

/// The two thresholds splitting timesteps into regimes, N.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RegimeThresholds {
    /// 33rd percentile of the total hand force.
    pub p33_n: f64,
    /// 66th percentile of the total hand force.
    pub p66_n: f64,
}

impl RegimeThresholds {
    /// A task's thresholds in `by_task`, or, for a task without any, all-zero thresholds
    /// (every step in the low-force regime).
    pub fn of_task(by_task: &std::collections::BTreeMap<String, Self>, task: &str) -> Self {
        by_task.get(task).copied().unwrap_or(Self {
            p33_n: 0.0,
            p66_n: 0.0,
        })
    }

    /// Thresholds from every timestep's total force (any order).
    pub fn from_forces(total_force_n: &[f64]) -> Self {
        let mut sorted = total_force_n.to_vec();
        sorted.sort_by(f64::total_cmp);
        Self {
            p33_n: percentile(&sorted, 33.0),
            p66_n: percentile(&sorted, 66.0),
        }
    }

    /// The regime of a timestep with this total force.
    pub fn regime_of(&self, total_force_n: f64) -> Regime {
        if total_force_n <= self.p33_n {
            Regime::Low
        } else if total_force_n <= self.p66_n {
            Regime::Mid
        } else {
            Regime::High
        }
    }
}

/// Percentile of sorted values with linear interpolation between ranks (numpy's default);
/// 0 for an empty slice.
pub fn percentile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return 0.0;
    }
    let x = p / 100.0 * (sorted.len() - 1) as f64;
    let i = x.floor() as usize;
    let j = (i + 1).min(sorted.len() - 1);
    let f = x - i as f64;
    sorted[i] * (1.0 - f) + sorted[j] * f
}
