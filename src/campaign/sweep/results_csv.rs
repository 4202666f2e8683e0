//! `results.csv`: one typed row per cell, its columns the fields of [`ResultsRow`], so a
//! renamed metric is a compile error here rather than a column silently left empty.

use super::{CellResult, Plan};
use crate::eval::metrics::Diagnostics;
use serde::Serialize;

/// `results.csv`, in the sweep directory.
pub const RESULTS_CSV_FILE: &str = "results.csv";

/// One cell of a sweep: its axes, how much of it ran, and its scores (empty where
/// undefined or not run). Keypoint errors in mm, as every table prints them.
#[derive(Debug, Serialize)]
pub struct ResultsRow {
    cell: usize,
    #[serde(serialize_with = "crate::files::names::csv_text::serialize")]
    policy: String,
    /// As the spec names it: relative to the spec's directory when inside it.
    #[serde(serialize_with = "crate::files::names::csv_text::serialize")]
    dataset: String,
    #[serde(serialize_with = "crate::files::names::csv_text::serialize")]
    setting: String,
    force_coefficient: Option<f64>,
    push_n: Option<f64>,
    #[serde(serialize_with = "crate::files::names::csv_text::serialize")]
    latency_rule: String,
    #[serde(serialize_with = "crate::files::names::csv_text::serialize")]
    budget: String,
    #[serde(serialize_with = "crate::files::names::csv_text::serialize")]
    latency_mode: String,
    #[serde(serialize_with = "crate::files::names::csv_text::serialize")]
    miss_rule: String,
    #[serde(serialize_with = "crate::files::names::csv_text::serialize")]
    profile: String,
    #[serde(serialize_with = "crate::files::names::csv_text::serialize")]
    keypoints: String,
    episodes: usize,
    episodes_expected: usize,
    complete: bool,
    fats: Option<f64>,
    /// FATS's bootstrap 95 % interval (episodes resampled within tasks).
    fats_ci95_low: Option<f64>,
    fats_ci95_high: Option<f64>,
    survival: Option<f64>,
    /// Re-anchored at the robot's root, as FATS scores it.
    kp_error_mm: Option<f64>,
    /// Not re-anchored: the reference where it is in the world, drift included.
    global_kp_mm: Option<f64>,
    low_kp_mm: Option<f64>,
    high_kp_mm: Option<f64>,
    robustness_rho: Option<f64>,
    power_overhead_eta: Option<f64>,
    upper_kp_mm: Option<f64>,
    lower_kp_mm: Option<f64>,
    fats_std: Option<f64>,
    /// The tasks whose load lies outside what the policy's family was trained with, `;`
    /// between them (`run.json`'s `outside_training`); empty when none does.
    #[serde(serialize_with = "crate::files::names::csv_text::serialize")]
    outside_training: String,
    latency_p50_us: Option<f64>,
    latency_p99_us: Option<f64>,
    latency_p999_us: Option<f64>,
    deadline_misses: Option<u64>,
    invalid_actions: Option<u64>,
    policy_failures: Option<u64>,
    #[serde(serialize_with = "crate::files::names::csv_text::serialize")]
    engine: String,
    physics_dt_s: Option<f64>,
}

/// A finite number, or an empty cell.
fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

/// The rows of every cell, in plan order.
pub fn results_rows(plan: &Plan, results: &[Option<CellResult>]) -> Vec<ResultsRow> {
    plan.cells
        .iter()
        .zip(results)
        .map(|(cell, r)| {
            let setting = &cell.setting;
            let scores = r.as_ref().and_then(|r| r.summary.settings.values().next());
            let d = |f: fn(&Diagnostics) -> f64| scores.and_then(|s| finite(f(&s.average)));
            let ci = scores.and_then(|s| s.fats_ci95);
            let latency = r.as_ref().and_then(|r| r.latency);
            let faults = r.as_ref().map(|r| r.faults);
            ResultsRow {
                cell: cell.index,
                policy: cell.policy.name.clone(),
                dataset: cell
                    .dataset
                    .strip_prefix(&plan.workdir)
                    .unwrap_or(&cell.dataset)
                    .display()
                    .to_string(),
                setting: cell.setting.spelling(),
                force_coefficient: Some(setting.coefficient),
                // Empty for a disturbance (`event:…`, `impulse:…`, `payload:…`): no push,
                // and not a push of 0 either; the setting column names it.
                push_n: setting.disturbance.is_none().then_some(setting.push_n),
                latency_rule: cell.latency.name.clone(),
                budget: cell.latency.budget.clone(),
                latency_mode: cell.latency.mode.clone(),
                miss_rule: cell.latency.miss_rule.clone(),
                profile: cell.policy.profile.clone(),
                keypoints: cell.policy.keypoints.clone(),
                episodes: r.as_ref().map_or(0, |r| r.episodes),
                episodes_expected: cell.episodes,
                complete: r.as_ref().is_some_and(|r| r.complete),
                fats: d(|d| d.fats),
                fats_ci95_low: ci.and_then(|c| finite(c[0])),
                fats_ci95_high: ci.and_then(|c| finite(c[1])),
                survival: d(|d| d.survival),
                kp_error_mm: d(|d| d.kp_mm),
                global_kp_mm: d(|d| d.global_kp_mm),
                low_kp_mm: d(|d| d.low_kp_mm),
                high_kp_mm: d(|d| d.high_kp_mm),
                robustness_rho: d(|d| d.robustness),
                power_overhead_eta: d(|d| d.power_overhead),
                upper_kp_mm: d(|d| d.upper_kp_mm),
                lower_kp_mm: d(|d| d.lower_kp_mm),
                fats_std: d(|d| d.fats_std),
                outside_training: r
                    .as_ref()
                    // A cell runs one setting: its marks are the run's only ones.
                    .and_then(|r| r.summary.header.outside_training.values().next())
                    .map_or(String::new(), |tasks| {
                        tasks.keys().cloned().collect::<Vec<_>>().join(";")
                    }),
                latency_p50_us: latency.map(|l| l.p50_us),
                latency_p99_us: latency.map(|l| l.p99_us),
                latency_p999_us: latency.map(|l| l.p999_us),
                deadline_misses: faults.map(|f| f.deadline_misses),
                invalid_actions: faults.map(|f| f.invalid_actions),
                policy_failures: faults.map(|f| f.policy_failures),
                engine: cell.engine.name.clone(),
                physics_dt_s: r.as_ref().map(|r| r.summary.header.physics_dt_s),
            }
        })
        .collect()
}

/// `results.csv`'s text: a header of the field names, then one line per cell.
pub fn results_csv(plan: &Plan, results: &[Option<CellResult>]) -> String {
    let mut w = csv::Writer::from_writer(Vec::new());
    for row in results_rows(plan, results) {
        w.serialize(row)
            .expect("a row of numbers and strings serializes");
    }
    String::from_utf8(w.into_inner().expect("in memory")).expect("UTF-8")
}

/// Writes [`results_csv`] to `dir`/[`RESULTS_CSV_FILE`]; returns its path.
pub fn write_results_csv(
    dir: &std::path::Path,
    plan: &Plan,
    results: &[Option<CellResult>],
) -> Result<std::path::PathBuf, super::SweepError> {
    let path = dir.join(RESULTS_CSV_FILE);
    super::write_atomic(&path, results_csv(plan, results).as_bytes())?;
    Ok(path)
}
