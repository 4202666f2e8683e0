//! Task-level and benchmark-level aggregates: FATS and the paper's diagnostics.
//!
//! Sums run over episodes sorted by (task, episode id), so every aggregate is bit-for-bit
//! independent of the order episodes finished in (worker count, shards, resume).

use super::episode::{score_episode, EpisodeScore, EpisodeSeries};
use super::regimes::{Regime, RegimeThresholds};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The diagnostics of one task, or their average over tasks.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Diagnostics {
    /// Mean episode score.
    #[serde(deserialize_with = "nan_if_null")]
    pub fats: f64,
    /// Mean survival.
    #[serde(deserialize_with = "nan_if_null")]
    pub survival: f64,
    /// Keypoint RMSE over all steps, mm.
    #[serde(deserialize_with = "nan_if_null")]
    pub kp_mm: f64,
    /// Keypoint RMSE over low-force steps, mm (pooled over the task's steps).
    #[serde(deserialize_with = "nan_if_null")]
    pub low_kp_mm: f64,
    /// Keypoint RMSE over high-force steps, mm.
    #[serde(deserialize_with = "nan_if_null")]
    pub high_kp_mm: f64,
    /// Robustness ρ = E_low / E_high.
    #[serde(deserialize_with = "nan_if_null")]
    pub robustness: f64,
    /// Power overhead η = P_high / P_low.
    #[serde(deserialize_with = "nan_if_null")]
    pub power_overhead: f64,
    /// Upper-body keypoint RMSE, mm.
    #[serde(deserialize_with = "nan_if_null")]
    pub upper_kp_mm: f64,
    /// Lower-body keypoint RMSE, mm.
    #[serde(deserialize_with = "nan_if_null")]
    pub lower_kp_mm: f64,
    /// Population standard deviation of episode scores (NaN for a task of one episode).
    #[serde(deserialize_with = "nan_if_null")]
    pub fats_std: f64,
    /// Mean root drift, m.
    #[serde(deserialize_with = "nan_if_null")]
    pub root_drift_m: f64,
    /// Keypoint RMSE without re-anchoring (drift included), mm; NaN for a run recorded
    /// before it was (its summary has none).
    #[serde(default = "nan", deserialize_with = "nan_if_null")]
    pub global_kp_mm: f64,
}

fn nan() -> f64 {
    f64::NAN
}

/// Reads a number written by serde_json, which writes NaN (an undefined diagnostic) as
/// `null`, back as NaN.
fn nan_if_null<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

/// One task's aggregate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TaskSummary {
    /// Task name.
    pub task: String,
    /// Episodes scored.
    pub episodes: usize,
    /// Its diagnostics.
    pub diagnostics: Diagnostics,
}

/// Pooled sums over a task's steps.
#[derive(Default)]
struct Pool {
    sq: f64,
    n: usize,
}

impl Pool {
    fn add(&mut self, e: f64) {
        self.sq += e * e;
        self.n += 1;
    }
    fn rmse(&self) -> f64 {
        if self.n == 0 {
            f64::NAN
        } else {
            (self.sq / self.n as f64).sqrt()
        }
    }
}

/// Scores every episode and aggregates per task and over tasks (the benchmark's tables
/// average over tasks). `episodes` are `(task, episode id, series)`; `thresholds` gives
/// each task's regime thresholds. Quantities undefined for a task (no high-force step,
/// say) are NaN there and left out of the average over tasks.
pub fn aggregate(
    episodes: &[(String, String, EpisodeSeries)],
    thresholds: &dyn Fn(&str) -> RegimeThresholds,
) -> (
    Vec<(String, String, EpisodeScore)>,
    Vec<TaskSummary>,
    Diagnostics,
) {
    let mut order: Vec<&(String, String, EpisodeSeries)> = episodes.iter().collect();
    order.sort_by(|a, b| (&a.0, &a.1).cmp(&(&b.0, &b.1)));
    let mut by_task: BTreeMap<&str, Vec<&(String, String, EpisodeSeries)>> = BTreeMap::new();
    for e in order {
        by_task.entry(e.0.as_str()).or_default().push(e);
    }
    let mut scores = Vec::new();
    let mut tasks = Vec::new();
    for (task, eps) in by_task {
        let th = thresholds(task);
        let mut all = Pool::default();
        let mut regime = [Pool::default(), Pool::default(), Pool::default()];
        let (mut upper, mut lower) = (Pool::default(), Pool::default());
        let mut global = Pool::default();
        let mut power = [(0.0f64, 0usize); 3];
        let mut task_scores = Vec::new();
        let mut drift = 0.0;
        for (t, id, s) in eps.iter().map(|e| (&e.0, &e.1, &e.2)) {
            for k in 0..s.kp_err_m.len() {
                let r = th.regime_of(s.total_force_n[k]).index();
                all.add(s.kp_err_m[k]);
                regime[r].add(s.kp_err_m[k]);
                power[r].0 += s.power_w[k];
                power[r].1 += 1;
            }
            s.kp_err_upper_m.iter().for_each(|e| upper.add(*e));
            s.kp_err_lower_m.iter().for_each(|e| lower.add(*e));
            s.kp_err_global_m.iter().for_each(|e| global.add(*e));
            let score = score_episode(s, &th);
            drift += score.mean_root_drift_m;
            task_scores.push(score.clone());
            scores.push((t.clone(), id.clone(), score));
        }
        let n = task_scores.len() as f64;
        let fats = task_scores.iter().map(|s| s.score).sum::<f64>() / n;
        let mean_power = |r: Regime| {
            let (p, c) = power[r.index()];
            if c == 0 {
                f64::NAN
            } else {
                p / c as f64
            }
        };
        let (low, high) = (
            regime[Regime::Low.index()].rmse(),
            regime[Regime::High.index()].rmse(),
        );
        tasks.push(TaskSummary {
            task: task.to_string(),
            episodes: task_scores.len(),
            diagnostics: Diagnostics {
                fats,
                survival: task_scores.iter().map(|s| s.survival).sum::<f64>() / n,
                kp_mm: 1e3 * all.rmse(),
                low_kp_mm: 1e3 * low,
                high_kp_mm: 1e3 * high,
                robustness: low / high,
                power_overhead: mean_power(Regime::High) / mean_power(Regime::Low),
                upper_kp_mm: 1e3 * upper.rmse(),
                lower_kp_mm: 1e3 * lower.rmse(),
                // One episode has no spread to speak of: undefined (a dash, `n/a`), not 0.
                fats_std: if task_scores.len() < 2 {
                    f64::NAN
                } else {
                    (task_scores
                        .iter()
                        .map(|s| (s.score - fats).powi(2))
                        .sum::<f64>()
                        / n)
                        .sqrt()
                },
                root_drift_m: drift / n,
                global_kp_mm: 1e3 * global.rmse(),
            },
        });
    }
    let overall = average_over_tasks(&tasks);
    (scores, tasks, overall)
}

/// Mean of each diagnostic over the tasks where it is defined.
fn average_over_tasks(tasks: &[TaskSummary]) -> Diagnostics {
    let avg = |f: fn(&Diagnostics) -> f64| {
        let v: Vec<f64> = tasks
            .iter()
            .map(|t| f(&t.diagnostics))
            .filter(|x| x.is_finite())
            .collect();
        if v.is_empty() {
            f64::NAN
        } else {
            v.iter().sum::<f64>() / v.len() as f64
        }
    };
    Diagnostics {
        fats: avg(|d| d.fats),
        survival: avg(|d| d.survival),
        kp_mm: avg(|d| d.kp_mm),
        low_kp_mm: avg(|d| d.low_kp_mm),
        high_kp_mm: avg(|d| d.high_kp_mm),
        robustness: avg(|d| d.robustness),
        power_overhead: avg(|d| d.power_overhead),
        upper_kp_mm: avg(|d| d.upper_kp_mm),
        lower_kp_mm: avg(|d| d.lower_kp_mm),
        fats_std: avg(|d| d.fats_std),
        root_drift_m: avg(|d| d.root_drift_m),
        global_kp_mm: avg(|d| d.global_kp_mm),
    }
}
