//! The full-coverage evaluation: every sequence of a dataset once per setting, spread over
//! worker threads, each finished episode streamed to a JSON-lines file, and the scores
//! aggregated per setting.
//!
//! Determinism: an episode's result depends only on its sequence, setting and policy (a
//! reset rebuilds the physics world; policies are created per worker and reset per
//! episode), and aggregates sum in (task, id) order, so results are identical for any
//! number of workers.
//!
//! One loop for every policy (`lockstep`): the runner owns N environment slots, hands
//! the whole batch of observations to the policy each control step — in process or over
//! shared memory — and applies the returned actions, the slots' physics spread over worker
//! threads.

mod lockstep;

pub use lockstep::{run_eval, RunOutcome};

use crate::evaluation::{PolicyIoRules, Setting, TerminationRule};
use crate::metrics::RegimeThresholds;
use crate::motion::{Reference, Sequence};
use crate::profile::Profile;
use crate::robot::RobotModel;
use std::collections::BTreeMap;

/// Everything an evaluation needs.
pub struct EvalPlan<'a> {
    /// Robot.
    pub robot: &'a RobotModel,
    /// Dynamics profile.
    pub profile: &'a Profile,
    /// Keypoint set name.
    pub keypoints: &'a str,
    /// Termination rule.
    pub termination: TerminationRule,
    /// Settings to run.
    pub settings: Vec<Setting>,
    /// Worker threads stepping the physics of the environment slots.
    pub workers: usize,
    /// Environment slots stepped in lock-step (one batch per control step to the policy).
    pub envs: usize,
    /// What a missed deadline or an unusable action does, and when actions take effect.
    pub io: PolicyIoRules,
    /// Record rollout traces of the sequences with these `task/sequence_id` names.
    pub trace: Vec<String>,
    /// Record the trace of every other episode too, over its first this many seconds
    /// (`crosscheck` compares the engines' joint angles there).
    pub trace_first_s: Option<f64>,
    /// The physics engine (checked by the caller: [`crate::physics::make_physics`] must
    /// succeed for it before the run).
    pub engine: crate::physics::Engine,
}

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
