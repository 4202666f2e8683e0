//! One episode's score: regime errors, the force-aware error `E_i`, survival `s_i` and
//! the score `S_i`.

use super::regimes::{Regime, RegimeThresholds, REGIME_WEIGHTS};
use serde::{Deserialize, Serialize};

/// Error sensitivity σ of the score, m.
pub const SIGMA_M: f64 = 0.15;

/// What an episode recorded at each control step before it ended.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct EpisodeSeries {
    /// Keypoint error `e_kp(t)` over all keypoints, m.
    pub kp_err_m: Vec<f64>,
    /// Keypoint error over the upper-body keypoints, m.
    pub kp_err_upper_m: Vec<f64>,
    /// Keypoint error over the lower-body keypoints, m.
    pub kp_err_lower_m: Vec<f64>,
    /// Recorded total hand force `|F_L| + |F_R|` (regardless of replay), N.
    pub total_force_n: Vec<f64>,
    /// Mechanical power `Σ_j |τ_j · q̇_j|`, W.
    pub power_w: Vec<f64>,
    /// Horizontal distance between robot and reference root, m.
    pub root_drift_m: Vec<f64>,
    /// Keypoint error without re-anchoring — the reference keypoints where the reference
    /// puts them in the world, drift included — m (trackers are judged both ways in the
    /// field). Empty in records written before it was recorded.
    #[serde(default)]
    pub kp_err_global_m: Vec<f64>,
    /// Control steps of the reference (`T_ref`).
    pub steps_ref: usize,
}

impl EpisodeSeries {
    /// Survival `s_i = min(T_i / T_ref, 1)` (0 for a reference without steps).
    pub fn survival(&self) -> f64 {
        if self.steps_ref == 0 {
            0.0
        } else {
            (self.kp_err_m.len() as f64 / self.steps_ref as f64).min(1.0)
        }
    }

    /// RMS of the keypoint error over the recorded steps, m; `None` without a step.
    pub fn kp_rms_m(&self) -> Option<f64> {
        let e = &self.kp_err_m;
        (!e.is_empty()).then(|| (e.iter().map(|x| x * x).sum::<f64>() / e.len() as f64).sqrt())
    }
}

/// An episode's score and its parts.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EpisodeScore {
    /// Keypoint RMSE per regime (low, mid, high), m; `None` where the episode has no step.
    pub regime_rmse_m: [Option<f64>; 3],
    /// Force-aware tracking error `E_i`, m (weights renormalised over present regimes);
    /// `None` when the episode ended before its first step.
    pub error_m: Option<f64>,
    /// Survival `s_i = min(T_i / T_ref, 1)`.
    pub survival: f64,
    /// Score `S_i = 100·exp(−E_i/σ)·s_i` (0 without any step).
    pub score: f64,
    /// Mean power per regime, W.
    pub regime_power_w: [Option<f64>; 3],
    /// Mean root drift, m.
    pub mean_root_drift_m: f64,
}

/// Scores one episode against regime thresholds.
pub fn score_episode(series: &EpisodeSeries, thresholds: &RegimeThresholds) -> EpisodeScore {
    let n = series.kp_err_m.len();
    assert_eq!(series.total_force_n.len(), n, "one force per recorded step");
    assert_eq!(series.power_w.len(), n, "one power per recorded step");
    let mut sq = [0.0f64; 3];
    let mut power = [0.0f64; 3];
    let mut count = [0usize; 3];
    for k in 0..n {
        let r = thresholds.regime_of(series.total_force_n[k]).index();
        sq[r] += series.kp_err_m[k].powi(2);
        power[r] += series.power_w[k];
        count[r] += 1;
    }
    let regime_rmse_m = Regime::ALL.map(|r| {
        let i = r.index();
        (count[i] > 0).then(|| (sq[i] / count[i] as f64).sqrt())
    });
    let regime_power_w = Regime::ALL.map(|r| {
        let i = r.index();
        (count[i] > 0).then(|| power[i] / count[i] as f64)
    });
    let (mut weighted, mut weights) = (0.0, 0.0);
    for (e, w) in regime_rmse_m.iter().zip(REGIME_WEIGHTS) {
        if let Some(e) = e {
            weighted += w * e * e;
            weights += w;
        }
    }
    let error_m = (weights > 0.0).then(|| (weighted / weights).sqrt());
    let survival = series.survival();
    let score = error_m.map_or(0.0, |e| 100.0 * (-e / SIGMA_M).exp() * survival);
    let mean_root_drift_m = if series.root_drift_m.is_empty() {
        0.0
    } else {
        series.root_drift_m.iter().sum::<f64>() / series.root_drift_m.len() as f64
    };
    EpisodeScore {
        regime_rmse_m,
        error_m,
        survival,
        score,
        regime_power_w,
        mean_root_drift_m,
    }
}
