//! The same episodes on two engines, compared (`thorarena crosscheck`): per episode the
//! survival, mean keypoint error and score on each and their differences; per setting the
//! means and the mean paired difference with a bootstrap confidence interval — survival
//! under force is chaotic per episode, so only means over many episodes say anything.

mod files;
mod series;

pub use files::{
    compare_runs, write_crosscheck, Crosscheck, CrosscheckCsvRow, CROSSCHECK_CSV_FILE,
    CROSSCHECK_JSON_FILE,
};
pub use series::{SeriesByEpisode, SeriesLog};

pub use crate::eval::metrics::{mean_ci, MeanCi};
use crate::eval::metrics::{score_episode, stratified_mean_ci, RegimeThresholds};
use crate::eval::Setting;
use crate::eval::{EpisodeKey, EpisodeRecord};
use serde::Serialize;
use std::collections::BTreeMap;

/// One episode's numbers on one engine.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct EngineNumbers {
    /// Survival `s_i`.
    pub survival: f64,
    /// Mean keypoint error over the steps survived, mm (NaN without a step).
    pub kp_mm: f64,
    /// Episode score `S_i`.
    pub score: f64,
}

impl EngineNumbers {
    fn of(r: &EpisodeRecord, thresholds: &RegimeThresholds) -> Self {
        let s = score_episode(&r.series, thresholds);
        let e = &r.series.kp_err_m;
        Self {
            survival: s.survival,
            kp_mm: if e.is_empty() {
                f64::NAN
            } else {
                1e3 * e.iter().sum::<f64>() / e.len() as f64
            },
            score: s.score,
        }
    }
}

/// How far the joint angles of one episode drift apart between two engines over its
/// first control steps (the closed loop: each engine's policy sees its own state).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct JointDivergence {
    /// Control steps compared (both engines ran them).
    pub steps: usize,
    /// Root mean square over those steps and all joints of `q_b − q_a`, rad.
    pub rms_rad: f64,
    /// Largest `|q_b − q_a|` over those steps and joints, rad.
    pub max_rad: f64,
    /// Root mean square over joints at the last step compared, rad.
    pub final_rms_rad: f64,
}

/// The divergence of two joint-angle series (per control step, then per joint), over
/// the steps both have; `None` without a common step or with unequal joint counts.
pub fn joint_divergence(a: &[Vec<f64>], b: &[Vec<f64>]) -> Option<JointDivergence> {
    let steps = a.len().min(b.len());
    let joints = a.first()?.len();
    if steps == 0
        || joints == 0
        || a[..steps]
            .iter()
            .chain(&b[..steps])
            .any(|q| q.len() != joints)
    {
        return None;
    }
    let (mut sum_sq, mut max_rad, mut last_sq) = (0.0, 0.0_f64, 0.0);
    for (qa, qb) in a[..steps].iter().zip(&b[..steps]) {
        last_sq = 0.0;
        for (x, y) in qa.iter().zip(qb) {
            let d = y - x;
            last_sq += d * d;
            max_rad = max_rad.max(d.abs());
        }
        sum_sq += last_sq;
    }
    Some(JointDivergence {
        steps,
        rms_rad: (sum_sq / (steps * joints) as f64).sqrt(),
        max_rad,
        final_rms_rad: (last_sq / joints as f64).sqrt(),
    })
}

/// The engines' accumulated foot slip (all feet) differing by more than this means their
/// feet no longer move alike on the ground, m.
pub const SLIP_PARTING_M: f64 = 0.02;

/// The feet's slip over one episode on both engines.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FootSlipPair {
    /// Slip of all feet over the whole episode (to its end or fall) on each engine, m.
    pub total_m: [f64; 2],
    /// First time since the start at which the engines' accumulated slip differs by
    /// more than [`SLIP_PARTING_M`], s; `None` if it never does over the steps both ran.
    pub parts_at_s: Option<f64>,
}

/// Compares two engines' per-step accumulated slip (per control step, per foot, as
/// [`crate::eval::episode::EpisodeTrace::foot_slip_m`]); `None` if either is empty.
pub fn foot_slip_pair(a: &[Vec<f64>], b: &[Vec<f64>], control_dt_s: f64) -> Option<FootSlipPair> {
    let total = |s: &[f64]| s.iter().sum::<f64>();
    let (last_a, last_b) = (a.last()?, b.last()?);
    let parts = a
        .iter()
        .zip(b)
        .position(|(x, y)| (total(x) - total(y)).abs() > SLIP_PARTING_M);
    Some(FootSlipPair {
        total_m: [total(last_a), total(last_b)],
        parts_at_s: parts.map(|k| (k + 1) as f64 * control_dt_s),
    })
}

/// `crosscheck.json`: the two runs compared, how, and the comparisons themselves.
#[derive(Debug, Serialize)]
pub struct CrosscheckFile<'a> {
    /// The run directories, per engine.
    pub runs: EngineRuns<'a>,
    /// Bootstrap resamples of every interval.
    pub bootstrap_resamples: usize,
    /// Seconds of each episode over which joint angles are compared.
    pub divergence_seconds: f64,
    /// Per setting.
    pub settings: &'a [SettingComparison],
    /// Per push force, over its directions (empty without pushes).
    pub push_levels: &'a [SettingComparison],
    /// Every episode on both engines.
    pub episodes: &'a [EpisodePair],
}

/// The run directory of each engine in a crosscheck.
#[derive(Debug, Serialize)]
pub struct EngineRuns<'a> {
    /// The rapier run.
    pub rapier: &'a std::path::Path,
    /// The MuJoCo run.
    pub mujoco: &'a std::path::Path,
}

/// One episode on both engines.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EpisodePair {
    /// Task.
    pub task: String,
    /// Sequence id.
    pub sequence_id: String,
    /// Setting.
    pub setting: String,
    /// The first engine's numbers (the baseline).
    pub a: EngineNumbers,
    /// The second engine's.
    pub b: EngineNumbers,
    /// Joint-angle divergence over the first second, when both runs recorded it (an
    /// episode carried over by `--resume` did not).
    pub joint_divergence: Option<JointDivergence>,
    /// The feet's slip on both engines, when both runs recorded it.
    pub foot_slip: Option<FootSlipPair>,
}

impl EpisodePair {
    /// The episode's identity.
    pub fn key(&self) -> EpisodeKey {
        EpisodeKey {
            task: self.task.clone(),
            sequence_id: self.sequence_id.clone(),
            setting: self.setting.clone(),
        }
    }
}

/// A mean over episodes, on each engine, and the mean paired difference `b − a` with its
/// bootstrap 95 % confidence interval.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Compared {
    /// Mean on the first engine.
    pub a: f64,
    /// Mean on the second engine.
    pub b: f64,
    /// Mean of `b − a` over the episodes.
    pub diff: f64,
    /// 2.5th and 97.5th percentiles of the bootstrap means of `b − a`.
    pub ci95: [f64; 2],
}

/// One setting's comparison.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SettingComparison {
    /// Setting name.
    pub setting: String,
    /// Episodes compared.
    pub episodes: usize,
    /// Survival.
    pub survival: Compared,
    /// Mean keypoint error, mm (episodes with a step on both engines).
    pub kp_mm: Compared,
    /// Episode score `S_i`, the plain mean over episodes.
    pub score: Compared,
    /// FATS: the mean over tasks of each task's mean episode score, as `eval` reports it
    /// (the bootstrap resamples episodes within each task).
    pub fats: Compared,
    /// RMS joint-angle divergence over the first second, rad (episodes that have it).
    pub joint_divergence_rad: MeanCi,
    /// Slip of all feet over an episode, m (episodes that have it).
    pub foot_slip_m: Compared,
    /// Episodes whose engines' slip parted (of those that have it).
    pub slip_parted: usize,
    /// When the slip parted, s since the start (over the episodes where it did).
    pub slip_parts_at_s: MeanCi,
}

/// Pairs the records of two runs of the same episodes (by task, sequence and setting);
/// `thresholds` are the runs' regime thresholds per task. Episodes in only one run are
/// left out and returned by key.
pub fn pair_episodes(
    a: &[EpisodeRecord],
    b: &[EpisodeRecord],
    thresholds: &BTreeMap<String, RegimeThresholds>,
) -> (Vec<EpisodePair>, Vec<EpisodeKey>) {
    let by_key: BTreeMap<_, _> = b.iter().map(|r| (r.key(), r)).collect();
    let mut unpaired: Vec<_> = Vec::new();
    let mut pairs = Vec::new();
    for r in a {
        let th = &RegimeThresholds::of_task(thresholds, &r.task);
        match by_key.get(&r.key()) {
            Some(o) => pairs.push(EpisodePair {
                task: r.task.clone(),
                sequence_id: r.sequence_id.clone(),
                setting: r.setting.clone(),
                a: EngineNumbers::of(r, th),
                b: EngineNumbers::of(o, th),
                joint_divergence: None,
                foot_slip: None,
            }),
            None => unpaired.push(r.key()),
        }
    }
    let a_keys: std::collections::BTreeSet<_> = a.iter().map(EpisodeRecord::key).collect();
    unpaired.extend(
        b.iter()
            .map(EpisodeRecord::key)
            .filter(|k| !a_keys.contains(k)),
    );
    (pairs, unpaired)
}

/// Means and the paired difference of `values` (`(a, b)` per episode; pairs with a NaN
/// are left out), with `resamples` bootstrap resamples from `seed`.
pub fn compare(values: &[(f64, f64)], resamples: usize, seed: u64) -> Compared {
    let v: Vec<(f64, f64)> = values
        .iter()
        .copied()
        .filter(|(a, b)| a.is_finite() && b.is_finite())
        .collect();
    if v.is_empty() {
        return Compared {
            a: f64::NAN,
            b: f64::NAN,
            diff: f64::NAN,
            ci95: [f64::NAN; 2],
        };
    }
    let n = v.len() as f64;
    let mean = |f: &dyn Fn(&(f64, f64)) -> f64| v.iter().map(f).sum::<f64>() / n;
    let diffs: Vec<f64> = v.iter().map(|(a, b)| b - a).collect();
    let d = mean_ci(&diffs, resamples, seed);
    Compared {
        a: mean(&|p| p.0),
        b: mean(&|p| p.1),
        diff: d.mean,
        ci95: d.ci95,
    }
}

/// FATS on each engine over `pairs` (the mean over tasks of the mean episode score) and
/// the difference, with a stratified bootstrap: each resample draws every task's episodes
/// with replacement from that task, so each task keeps its weight.
pub fn compare_fats(pairs: &[&EpisodePair], resamples: usize, seed: u64) -> Compared {
    let mut by_task: BTreeMap<&str, Vec<(f64, f64)>> = BTreeMap::new();
    for p in pairs {
        if p.a.score.is_finite() && p.b.score.is_finite() {
            by_task
                .entry(p.task.as_str())
                .or_default()
                .push((p.a.score, p.b.score));
        }
    }
    if by_task.is_empty() {
        return Compared {
            a: f64::NAN,
            b: f64::NAN,
            diff: f64::NAN,
            ci95: [f64::NAN; 2],
        };
    }
    let tasks = by_task.len() as f64;
    let fats = |pick: &dyn Fn(&(f64, f64)) -> f64| {
        by_task
            .values()
            .map(|v| v.iter().map(pick).sum::<f64>() / v.len() as f64)
            .sum::<f64>()
            / tasks
    };
    let (a, b) = (fats(&|p| p.0), fats(&|p| p.1));
    let diffs: Vec<Vec<f64>> = by_task
        .values()
        .map(|v| v.iter().map(|(x, y)| y - x).collect())
        .collect();
    Compared {
        a,
        b,
        diff: b - a,
        ci95: stratified_mean_ci(&diffs, resamples, seed).ci95,
    }
}

/// Per setting (in the order first seen), the comparison of `pairs`.
pub fn compare_settings(
    pairs: &[EpisodePair],
    resamples: usize,
    seed: u64,
) -> Vec<SettingComparison> {
    let mut order: Vec<&str> = Vec::new();
    for p in pairs {
        if !order.contains(&p.setting.as_str()) {
            order.push(&p.setting);
        }
    }
    order
        .into_iter()
        .map(|setting| {
            let ps: Vec<&EpisodePair> = pairs.iter().filter(|p| p.setting == setting).collect();
            let col = |f: &dyn Fn(&EngineNumbers) -> f64| -> Vec<(f64, f64)> {
                ps.iter().map(|p| (f(&p.a), f(&p.b))).collect()
            };
            SettingComparison {
                setting: setting.to_string(),
                episodes: ps.len(),
                survival: compare(&col(&|e| e.survival), resamples, seed),
                kp_mm: compare(&col(&|e| e.kp_mm), resamples, seed),
                score: compare(&col(&|e| e.score), resamples, seed),
                fats: compare_fats(&ps, resamples, seed),
                joint_divergence_rad: mean_ci(
                    &ps.iter()
                        .filter_map(|p| p.joint_divergence.map(|d| d.rms_rad))
                        .collect::<Vec<_>>(),
                    resamples,
                    seed,
                ),
                foot_slip_m: compare(
                    &ps.iter()
                        .filter_map(|p| p.foot_slip.map(|f| (f.total_m[0], f.total_m[1])))
                        .collect::<Vec<_>>(),
                    resamples,
                    seed,
                ),
                slip_parted: ps
                    .iter()
                    .filter(|p| p.foot_slip.is_some_and(|f| f.parts_at_s.is_some()))
                    .count(),
                slip_parts_at_s: mean_ci(
                    &ps.iter()
                        .filter_map(|p| p.foot_slip.and_then(|f| f.parts_at_s))
                        .collect::<Vec<_>>(),
                    resamples,
                    seed,
                ),
            }
        })
        .collect()
}

/// Per push force (N per hand, over all its directions; `no-force` is 0 N), the comparison
/// of `pairs`, in increasing force; settings with a replay coefficient are left out. A
/// force response is a curve over force levels: averaging a level's directions gives it
/// enough episodes for a useful interval.
pub fn compare_push_levels(
    pairs: &[EpisodePair],
    settings: &[Setting],
    resamples: usize,
    seed: u64,
) -> Vec<SettingComparison> {
    let level_of = |name: &str| -> Option<f64> {
        let s = settings.iter().find(|s| s.name == name)?;
        s.push_only().map(f64::abs)
    };
    let mut levels: Vec<f64> = pairs.iter().filter_map(|p| level_of(&p.setting)).collect();
    levels.sort_by(f64::total_cmp);
    levels.dedup();
    let label = |n: f64| {
        let directions = settings
            .iter()
            .filter(|s| s.push_only().map(f64::abs) == Some(n))
            .count();
        format!(
            "{n} N ({directions} setting{})",
            if directions == 1 { "" } else { "s" }
        )
    };
    let relabelled: Vec<EpisodePair> = levels
        .iter()
        .flat_map(|&n| {
            pairs
                .iter()
                .filter(move |p| level_of(&p.setting) == Some(n))
                .map(move |p| EpisodePair {
                    setting: label(n),
                    ..p.clone()
                })
        })
        .collect();
    compare_settings(&relabelled, resamples, seed)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_constant_difference_has_a_zero_width_interval_and_noise_a_wider_one() {
        let same: Vec<(f64, f64)> = (0..50).map(|i| (i as f64, i as f64 + 2.0)).collect();
        let c = compare(&same, 500, 1);
        assert_eq!(c.diff, 2.0);
        assert_eq!(c.ci95, [2.0, 2.0]);
        let noisy: Vec<(f64, f64)> = (0..50)
            .map(|i| (0.0, if i % 2 == 0 { 1.0 } else { -1.0 }))
            .collect();
        let c = compare(&noisy, 2000, 1);
        assert!(c.diff.abs() < 1e-12);
        assert!(c.ci95[0] < -0.1 && c.ci95[1] > 0.1, "{:?}", c.ci95);
        // ±1 over 50 episodes: the 95 % interval of the mean is about ±2·(1/√50) = ±0.28.
        assert!(c.ci95[0] > -0.4 && c.ci95[1] < 0.4, "{:?}", c.ci95);
        let with_nan = [(1.0, f64::NAN), (1.0, 2.0)];
        assert_eq!(compare(&with_nan, 10, 1).diff, 1.0);
    }

    #[test]
    fn push_levels_pool_their_directions_and_leave_replays_out() {
        let settings: Vec<Setting> = ["no-force", "push:20@0", "push:20@180", "push:10", "force"]
            .iter()
            .map(|s| Setting::parse(s).expect("valid"))
            .collect();
        let numbers = |survival| EngineNumbers {
            survival,
            kp_mm: 10.0,
            score: 50.0,
        };
        let pairs: Vec<EpisodePair> = settings
            .iter()
            .enumerate()
            .map(|(i, s)| EpisodePair {
                task: "t".into(),
                sequence_id: "q".into(),
                setting: s.name.clone(),
                a: numbers(1.0),
                b: numbers(i as f64 / 10.0),
                joint_divergence: None,
                foot_slip: None,
            })
            .collect();
        let levels = compare_push_levels(&pairs, &settings, 100, 0);
        let names: Vec<&str> = levels.iter().map(|l| l.setting.as_str()).collect();
        assert_eq!(
            names,
            ["0 N (1 setting)", "10 N (1 setting)", "20 N (2 settings)"]
        );
        assert_eq!(levels[2].episodes, 2);
        // The two 20 N directions had b-survival 0.1 and 0.2.
        assert!((levels[2].survival.b - 0.15).abs() < 1e-12);
        assert!((levels[1].survival.b - 0.3).abs() < 1e-12);
    }

    #[test]
    fn fats_weighs_tasks_equally_however_many_episodes_each_has() {
        let pair = |task: &str, a: f64, b: f64| EpisodePair {
            task: task.into(),
            sequence_id: format!("{task}-{a}-{b}"),
            setting: "s".into(),
            a: EngineNumbers {
                survival: 1.0,
                kp_mm: 1.0,
                score: a,
            },
            b: EngineNumbers {
                survival: 1.0,
                kp_mm: 1.0,
                score: b,
            },
            joint_divergence: None,
            foot_slip: None,
        };
        // Task x: three episodes, 10 → 20 each; task y: one episode, 50 → 50.
        let pairs = [
            pair("x", 10.0, 20.0),
            pair("x", 10.0, 20.0),
            pair("x", 10.0, 20.0),
            pair("y", 50.0, 50.0),
        ];
        let refs: Vec<&EpisodePair> = pairs.iter().collect();
        let f = compare_fats(&refs, 200, 3);
        assert_eq!((f.a, f.b, f.diff), (30.0, 35.0, 5.0));
        // Within-task resampling cannot change a task made of equal episodes.
        assert_eq!(f.ci95, [5.0, 5.0]);
        // The plain episode mean would have said +7.5.
        let plain = compare_settings(&pairs, 200, 3);
        assert_eq!(plain[0].score.diff, 7.5);
        assert_eq!(plain[0].fats.diff, 5.0);
    }

    #[test]
    fn joint_divergence_is_taken_over_the_common_steps() {
        let a = vec![vec![0.0, 0.0]; 4];
        let mut b = vec![vec![0.0, 0.0]; 3];
        b[2] = vec![0.3, -0.4];
        let d = joint_divergence(&a, &b).expect("common steps");
        assert_eq!(d.steps, 3);
        assert!((d.max_rad - 0.4).abs() < 1e-12);
        // One step of (0.3, −0.4): 0.25 over 3 steps × 2 joints.
        assert!((d.rms_rad - (0.25_f64 / 6.0).sqrt()).abs() < 1e-12);
        assert!((d.final_rms_rad - (0.25_f64 / 2.0).sqrt()).abs() < 1e-12);
        assert_eq!(joint_divergence(&a, &a).map(|d| d.max_rad), Some(0.0));
        assert!(joint_divergence(&a, &[]).is_none());
        assert!(joint_divergence(&a, &[vec![0.0]]).is_none());
    }

    #[test]
    fn foot_slip_parts_at_the_first_step_the_totals_differ_by_more_than_the_margin() {
        // Two feet; engine b slides 3 cm more from the third step on.
        let a: Vec<Vec<f64>> = (0..5).map(|k| vec![0.01 * k as f64, 0.0]).collect();
        let b: Vec<Vec<f64>> = (0..5)
            .map(|k| vec![0.01 * k as f64, if k >= 2 { 0.03 } else { 0.0 }])
            .collect();
        let p = foot_slip_pair(&a, &b, 0.02).unwrap();
        assert_eq!(p.parts_at_s, Some(0.06));
        assert!((p.total_m[0] - 0.04).abs() < 1e-12 && (p.total_m[1] - 0.07).abs() < 1e-12);
        assert_eq!(foot_slip_pair(&a, &a, 0.02).unwrap().parts_at_s, None);
        assert!(foot_slip_pair(&a, &[], 0.02).is_none());
    }
}
