//! `episodes.csv`: one row per episode with the numbers a reader wants per sequence
//! (survival, mean and RMS keypoint error, score, why it ended), so per-sequence results
//! can be read off a spreadsheet instead of the per-step series of `episodes.jsonl`.

use super::ResultsError;
use crate::eval::metrics::{score_episode, RegimeThresholds};
use crate::eval::EpisodeRecord;
use crate::eval::Termination;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// `episodes.csv`.
pub const EPISODES_CSV_FILE: &str = "episodes.csv";

/// One row of `episodes.csv`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EpisodeRow {
    /// Task.
    #[serde(with = "crate::files::names::csv_text")]
    pub task: String,
    /// Sequence id.
    #[serde(with = "crate::files::names::csv_text")]
    pub sequence_id: String,
    /// Setting name.
    #[serde(with = "crate::files::names::csv_text")]
    pub setting: String,
    /// Survival `s_i = min(T_i / T_ref, 1)`.
    pub survival: f64,
    /// Mean over the episode's control steps of the keypoint error, mm.
    pub kp_error_mean_mm: f64,
    /// Root mean square over the episode's control steps of the keypoint error, mm.
    pub kp_error_rms_mm: f64,
    /// Episode score `S_i`, 0–100 (FATS is its mean over a task, then over tasks).
    pub score: f64,
    /// Why the episode ended early; empty when it ran to the end of its reference.
    #[serde(with = "crate::files::names::csv_text")]
    pub termination: String,
}

/// The rows of `records` (in their order), scored with each task's regime thresholds (a
/// task without thresholds has every step in the low-force regime).
pub fn episode_rows(
    records: &[EpisodeRecord],
    thresholds: &BTreeMap<String, RegimeThresholds>,
) -> Vec<EpisodeRow> {
    records
        .iter()
        .map(|r| {
            let th = RegimeThresholds::of_task(thresholds, &r.task);
            let score = score_episode(&r.series, &th);
            let e = &r.series.kp_err_m;
            let mean = if e.is_empty() {
                f64::NAN
            } else {
                1e3 * e.iter().sum::<f64>() / e.len() as f64
            };
            let rms = r.series.kp_rms_m().map_or(f64::NAN, |rms| 1e3 * rms);
            EpisodeRow {
                task: r.task.clone(),
                sequence_id: r.sequence_id.clone(),
                setting: r.setting.clone(),
                survival: score.survival,
                kp_error_mean_mm: mean,
                kp_error_rms_mm: rms,
                score: score.score,
                termination: r.termination.map(termination_name).unwrap_or_default(),
            }
        })
        .collect()
}

/// A termination as `episodes.jsonl` spells it (`torso_height`, `policy_failed`, …).
fn termination_name(t: Termination) -> String {
    serde_json::to_value(t)
        .ok()
        .and_then(|v| v.as_str().map(str::to_string))
        .unwrap_or_default()
}

/// Writes `rows` to `path` as CSV with a header line.
pub fn write_episodes_csv(path: &Path, rows: &[EpisodeRow]) -> Result<(), ResultsError> {
    let failed = |source: std::io::Error| ResultsError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut w = csv::Writer::from_writer(Vec::new());
    for row in rows {
        w.serialize(row)
            .map_err(|e| failed(std::io::Error::other(e)))?;
    }
    let bytes = w
        .into_inner()
        .map_err(|e| failed(std::io::Error::other(e.to_string())))?;
    crate::files::atomic_file::write(path, bytes).map_err(failed)
}
