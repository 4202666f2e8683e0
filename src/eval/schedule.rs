//! Which episodes a run (or one shard of it) runs, and how long each one is.

/// The full-coverage schedule: `(sequence index, setting index)`, setting-major, in
/// dataset order. A shard `i/n` takes every n-th job starting at i.
pub fn schedule(
    n_sequences: usize,
    n_settings: usize,
    shard: Option<(usize, usize)>,
) -> Vec<(usize, usize)> {
    (0..n_settings)
        .flat_map(|s| (0..n_sequences).map(move |q| (q, s)))
        .enumerate()
        .filter(|(j, _)| shard.is_none_or(|(i, n)| j % n == i))
        .map(|(_, job)| job)
        .collect()
}

/// Control steps of a reference of `duration_s` at `control_dt_s` (`T_ref`): the steps
/// an episode records when it runs to the end.
pub fn reference_steps(duration_s: f64, control_dt_s: f64) -> usize {
    (duration_s / control_dt_s + 1e-9).floor() as usize
}
