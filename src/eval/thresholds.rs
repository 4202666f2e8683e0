//! The regime thresholds of a dataset's tasks: what counts as a low- and a high-force step
//! is fixed by the references, so every policy is scored against the same regimes.

use crate::eval::metrics::RegimeThresholds;
use crate::sim::motion::{Reference, Sequence};
use std::collections::BTreeMap;

/// The regime thresholds of each task: percentiles of `|F_L| + |F_R|` over every control
/// step of the task's references (the steps the metrics record).
pub fn task_thresholds(
    sequences: &[Sequence],
    control_dt_s: f64,
) -> BTreeMap<String, RegimeThresholds> {
    let mut forces: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    for seq in sequences {
        let r = Reference::new(seq);
        let steps = (r.duration_s() / control_dt_s + 1e-9).floor() as usize;
        let v = forces.entry(seq.task.clone()).or_default();
        for k in 1..=steps {
            let f = r.sample(k as f64 * control_dt_s).force_sensor;
            v.push(f[0].norm() + f[1].norm());
        }
    }
    forces
        .into_iter()
        .map(|(task, v)| (task, RegimeThresholds::from_forces(&v)))
        .collect()
}
