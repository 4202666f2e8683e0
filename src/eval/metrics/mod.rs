//! FATS and its diagnostics from plain arrays: pure functions, no simulator types, so the
//! scoring can be checked by hand and reused on any rollout source.
//!
//! Definitions follow the paper, with the open points fixed in ARCHITECTURE.md ("Decisions and departures"): keypoint error
//! with root re-anchoring, force regimes by the 33rd/66th percentile of `|F_L| + |F_R|`,
//! regime weights (0.2, 0.3, 0.5) renormalised over the regimes an episode has, σ = 0.15 m.

mod aggregate;
mod bootstrap;
mod episode;
mod keypoints;
mod regimes;

pub use aggregate::{aggregate, Diagnostics, TaskSummary};
pub use bootstrap::{central_95, mean_ci, stratified_mean_ci, MeanCi, BOOTSTRAP_RESAMPLES};
pub use episode::{score_episode, EpisodeScore, EpisodeSeries, SIGMA_M};
pub use keypoints::{keypoint_error_m, reanchor};
pub use regimes::{percentile, Regime, RegimeThresholds, REGIME_WEIGHTS};
