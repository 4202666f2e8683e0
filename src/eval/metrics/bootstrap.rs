//! Bootstrap confidence intervals for scores averaged over episodes. Survival under force
//! is chaotic per episode, so a benchmark mean is only read with its interval: episodes are
//! resampled with replacement (within each task, when the statistic is a mean of task
//! means, as FATS is), from a fixed seed so a run's interval is reproducible.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// Resamples the tables and summaries use.
pub const BOOTSTRAP_RESAMPLES: usize = 2000;

/// A mean over episodes with its bootstrap 95 % confidence interval.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MeanCi {
    /// Episodes in the mean.
    pub episodes: usize,
    /// The mean.
    pub mean: f64,
    /// 2.5th and 97.5th percentiles of the bootstrap means.
    pub ci95: [f64; 2],
}

impl MeanCi {
    /// Nothing to average.
    const EMPTY: Self = Self {
        episodes: 0,
        mean: f64::NAN,
        ci95: [f64::NAN; 2],
    };
}

/// The mean of `values` and its bootstrap interval from `resamples` resamples (NaN
/// without a value).
pub fn mean_ci(values: &[f64], resamples: usize, seed: u64) -> MeanCi {
    if values.is_empty() {
        return MeanCi::EMPTY;
    }
    stratified_mean_ci(&[values.to_vec()], resamples, seed)
}

/// The mean over groups of each group's mean (FATS: tasks, each the mean of its
/// episodes), with a bootstrap interval that resamples episodes within each group, so
/// every resample keeps the task mix. Empty groups are left out.
pub fn stratified_mean_ci(groups: &[Vec<f64>], resamples: usize, seed: u64) -> MeanCi {
    let groups: Vec<&Vec<f64>> = groups.iter().filter(|g| !g.is_empty()).collect();
    if groups.is_empty() {
        return MeanCi::EMPTY;
    }
    let n = groups.len() as f64;
    let mean_of =
        |pick: &mut dyn FnMut(&[f64]) -> f64| groups.iter().map(|g| pick(g)).sum::<f64>() / n;
    let mean = mean_of(&mut |g| g.iter().sum::<f64>() / g.len() as f64);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let estimates: Vec<f64> = (0..resamples.max(1))
        .map(|_| {
            mean_of(&mut |g| {
                (0..g.len())
                    .map(|_| g[rng.random_range(0..g.len())])
                    .sum::<f64>()
                    / g.len() as f64
            })
        })
        .collect();
    MeanCi {
        episodes: groups.iter().map(|g| g.len()).sum(),
        mean,
        ci95: central_95(estimates),
    }
}

/// The 2.5th and 97.5th percentiles of bootstrap estimates (not empty).
pub fn central_95(mut estimates: Vec<f64>) -> [f64; 2] {
    estimates.sort_by(f64::total_cmp);
    let last = estimates.len() - 1;
    let pct = |p: f64| estimates[((p * last as f64).round() as usize).min(last)];
    [pct(0.025), pct(0.975)]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_interval_holds_the_mean_and_narrows_with_more_episodes() {
        let few: Vec<f64> = (0..8).map(|i| f64::from(i % 4) * 10.0).collect();
        let many: Vec<f64> = (0..800).map(|i| f64::from(i % 4) * 10.0).collect();
        let (a, b) = (mean_ci(&few, 2000, 1), mean_ci(&many, 2000, 1));
        assert_eq!(a.mean, 15.0);
        assert!(a.ci95[0] < 15.0 && 15.0 < a.ci95[1], "{a:?}");
        assert!(
            b.ci95[1] - b.ci95[0] < 0.3 * (a.ci95[1] - a.ci95[0]),
            "{a:?} {b:?}"
        );
    }

    #[test]
    fn a_stratified_mean_weighs_groups_not_episodes() {
        // Task means 0 and 100: FATS 50 however many episodes each task has.
        let ci = stratified_mean_ci(&[vec![0.0; 2], vec![100.0; 50], vec![]], 500, 3);
        assert_eq!(ci.mean, 50.0);
        assert_eq!(
            ci.ci95,
            [50.0, 50.0],
            "no spread within a task, none in FATS"
        );
        assert_eq!(ci.episodes, 52);
        assert!(stratified_mean_ci(&[], 10, 0).mean.is_nan());
    }
}
