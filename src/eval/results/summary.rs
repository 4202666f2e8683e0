//! `summary.json` and `episodes.csv`: the scores of a run's records, written the same way
//! by `eval`, `merge` and a sweep's collect, so a merged run is written exactly as a
//! single one. (`tables.md`, the same scores for people, is written by
//! `report::write_run_tables` from the [`Summary`].)

use super::episode_table::{episode_rows, write_episodes_csv, EpisodeRow, EPISODES_CSV_FILE};
use super::header::parse_versioned;
use super::{Coverage, ResultsError, RunHeader, SUMMARY_FILE};
use crate::eval::metrics::{
    aggregate, stratified_mean_ci, Diagnostics, EpisodeSeries, RegimeThresholds, TaskSummary,
    BOOTSTRAP_RESAMPLES,
};
use crate::eval::EpisodeRecord;
use crate::eval::LatencySummary;
use crate::policy::TransportStats;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// How the policy answered during a run: latency and faults (not part of the scores,
/// but part of the results: a deployment engineer reads these first).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PolicyIoReport {
    /// Per-step latency of the policy (percentiles; the run keeps no samples).
    pub latency: LatencySummary,
    /// Transport counters; present only when the policy ran behind the policy server.
    #[serde(default)]
    pub transport: Option<TransportStats>,
    /// Control steps whose actions missed the budget, summed over episodes.
    #[serde(default)]
    pub deadline_misses: u64,
    /// Control steps with unusable actions, summed over episodes.
    #[serde(default)]
    pub invalid_actions: u64,
    /// Episodes a `--resume` kept from earlier attempts: counted in the faults above,
    /// not in the latency percentiles nor the transport counters, which are this
    /// attempt's.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub resumed_episodes: usize,
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

/// One setting's scores.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SettingSummary {
    /// Per task.
    pub tasks: Vec<TaskSummary>,
    /// Averaged over tasks.
    pub average: Diagnostics,
    /// FATS's bootstrap 95 % interval (episodes resampled within tasks).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fats_ci95: Option<[f64; 2]>,
}

/// `summary.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// [`super::RESULTS_VERSION`] of the writer.
    pub results_version: u32,
    /// The run's header.
    pub header: RunHeader,
    /// Episodes scored.
    pub episodes: usize,
    /// Regime thresholds per task (percentiles of the references' hand forces).
    pub thresholds: BTreeMap<String, RegimeThresholds>,
    /// Scores per setting.
    pub settings: BTreeMap<String, SettingSummary>,
    /// Episodes present and expected per (setting, task).
    pub coverage: Coverage,
    /// Every planned episode is present and none was cut short by a policy failure.
    pub complete: bool,
    /// Latency and faults of the policy, when the writer ran the episodes (a merge of
    /// shards has no single latency histogram).
    pub policy_io: Option<PolicyIoReport>,
}

/// Per setting: per-task summaries and the average over tasks.
pub type SettingResults = BTreeMap<String, (Vec<TaskSummary>, Diagnostics)>;

/// Scores records with the task thresholds (a task without thresholds has every step in
/// the low-force regime).
pub fn summarize(
    records: &[EpisodeRecord],
    thresholds: &BTreeMap<String, RegimeThresholds>,
) -> SettingResults {
    let mut by_setting: BTreeMap<String, Vec<(String, String, EpisodeSeries)>> = BTreeMap::new();
    for r in records {
        by_setting.entry(r.setting.clone()).or_default().push((
            r.task.clone(),
            r.sequence_id.clone(),
            r.series.clone(),
        ));
    }
    let th = |task: &str| RegimeThresholds::of_task(thresholds, task);
    by_setting
        .into_iter()
        .map(|(setting, eps)| {
            let (_, tasks, overall) = aggregate(&eps, &th);
            (setting, (tasks, overall))
        })
        .collect()
}

/// Per setting, FATS's bootstrap 95 % interval: episode scores resampled within each task
/// ([`BOOTSTRAP_RESAMPLES`] resamples, a fixed seed, so a run's interval is reproducible).
/// A setting whose every task has one episode has no interval: resampling one score
/// gives it back, and `81.9 (81.9–81.9)` would claim a precision nothing measured.
pub fn fats_intervals(rows: &[EpisodeRow]) -> BTreeMap<String, [f64; 2]> {
    let mut by_setting: BTreeMap<&str, BTreeMap<&str, Vec<f64>>> = BTreeMap::new();
    for r in rows {
        by_setting
            .entry(&r.setting)
            .or_default()
            .entry(&r.task)
            .or_default()
            .push(r.score);
    }
    by_setting
        .into_iter()
        .filter(|(_, tasks)| tasks.values().any(|scores| scores.len() > 1))
        .map(|(setting, tasks)| {
            let groups: Vec<Vec<f64>> = tasks.into_values().collect();
            let ci = stratified_mean_ci(&groups, BOOTSTRAP_RESAMPLES, 0);
            (setting.to_string(), ci.ci95)
        })
        .collect()
}

/// Scores the records, writes `summary.json` and `episodes.csv`, and returns the summary
/// (its [`Summary::coverage`] says what a run that does not hold its whole plan lacks).
pub fn write_results(
    out: &Path,
    header: &RunHeader,
    records: &[EpisodeRecord],
    thresholds: BTreeMap<String, RegimeThresholds>,
    io: Option<PolicyIoReport>,
) -> Result<Summary, ResultsError> {
    let results = summarize(records, &thresholds);
    let rows = episode_rows(records, &thresholds);
    let intervals = fats_intervals(&rows);
    let coverage = Coverage::of(header, records);
    let csv_path = out.join(EPISODES_CSV_FILE);
    write_episodes_csv(&csv_path, &rows)?;
    let summary = Summary {
        results_version: super::RESULTS_VERSION,
        header: header.clone(),
        episodes: records.len(),
        thresholds,
        settings: results
            .into_iter()
            .map(|(k, (tasks, average))| {
                let fats_ci95 = intervals.get(&k).copied();
                (
                    k,
                    SettingSummary {
                        tasks,
                        average,
                        fats_ci95,
                    },
                )
            })
            .collect(),
        complete: coverage.is_complete(),
        coverage,
        policy_io: io,
    };
    let path = out.join(SUMMARY_FILE);
    let text = serde_json::to_string_pretty(&summary).expect("a summary serializes") + "\n";
    crate::files::atomic_file::write(&path, text).map_err(ResultsError::io(&path))?;
    Ok(summary)
}

/// The largest `summary.json` read, bytes (a cell per task and setting: a few KiB each).
pub const MAX_SUMMARY_BYTES: u64 = 64 * crate::files::bounded_read::MIB;

/// Reads `<run>/summary.json` (a regular file of at most [`MAX_SUMMARY_BYTES`]).
pub fn read_summary(run: &Path) -> Result<Summary, ResultsError> {
    let path = run.join(SUMMARY_FILE);
    let text = crate::files::bounded_read::read_to_string(&path, "summary.json", MAX_SUMMARY_BYTES)
        .map_err(ResultsError::io(&path))?;
    parse_versioned(&path, &text)
}

/// Records sorted into schedule order (the header's setting order, then dataset order).
pub fn sort_records(records: &mut [EpisodeRecord], header: &RunHeader) {
    let rank: std::collections::HashMap<(&str, &str), usize> = header
        .sequences
        .iter()
        .enumerate()
        .map(|(i, s)| ((s.task.as_str(), s.sequence_id.as_str()), i))
        .collect();
    records.sort_by_cached_key(|r| {
        (
            header.setting_index(&r.setting).unwrap_or(usize::MAX),
            rank.get(&(r.task.as_str(), r.sequence_id.as_str()))
                .copied()
                .unwrap_or(usize::MAX),
        )
    });
}

#[cfg(test)]
mod tests {
    use super::fats_intervals;
    use crate::eval::results::EpisodeRow;

    fn row(task: &str, setting: &str, score: f64) -> EpisodeRow {
        EpisodeRow {
            task: task.into(),
            sequence_id: format!("{task}-{score}"),
            setting: setting.into(),
            survival: 1.0,
            kp_error_mean_mm: 10.0,
            kp_error_rms_mm: 10.0,
            score,
            termination: String::new(),
        }
    }

    #[test]
    fn one_episode_per_task_has_no_interval() {
        let rows = [
            row("a", "one-each", 80.0),
            row("b", "one-each", 90.0),
            row("a", "two", 80.0),
            row("a", "two", 84.0),
            row("b", "two", 90.0),
        ];
        let intervals = fats_intervals(&rows);
        assert!(!intervals.contains_key("one-each"), "{intervals:?}");
        let [lo, hi] = intervals["two"];
        assert!(lo < hi && lo <= 86.0 && 86.0 <= hi, "[{lo}, {hi}]");
    }
}
