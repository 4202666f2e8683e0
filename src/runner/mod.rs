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

mod latency;
mod lockstep;

pub use latency::{LatencyRecorder, LatencySummary};
pub use lockstep::{run_eval, RunOutcome};

use crate::episode::TerminationRule;
use crate::metrics::RegimeThresholds;
use crate::motion::{Reference, Sequence};
use crate::policy::{LatencyMode, MissRule};
use crate::profile::Profile;
use crate::robot::RobotModel;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// A force setting: a name, the replay coefficient, and an optional constant push.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Setting {
    /// `force`, `no-force`, `coef-<x>`, `push-<N>` or `push-<N>@<deg>`.
    pub name: String,
    /// Replay coefficient.
    pub coefficient: f64,
    /// A constant world-frame +x push on each hand, N, ramped in over
    /// [`crate::replay::PUSH_RAMP_S`] (a sensitivity probe, as in SOURCES.md, TWIST2 in MuJoCo; recorded
    /// forces are not replayed with it).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub push_n: f64,
    /// The push's direction, degrees counter-clockwise from the reference's initial
    /// heading (`push:<N>@<deg>`; 90: from the robot's right); `None`: world +x.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub push_heading_deg: Option<f64>,
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

impl Setting {
    /// True when both settings load the robot the same way, however spelled (`force` and
    /// `1`; `no-force` and `push:0`; a zero push in any direction).
    pub fn same_load(&self, other: &Self) -> bool {
        let heading = |s: &Self| {
            if s.push_n == 0.0 {
                None
            } else {
                Some(s.push_heading_deg.unwrap_or(0.0).rem_euclid(360.0))
            }
        };
        self.coefficient == other.coefficient
            && self.push_n == other.push_n
            && heading(self) == heading(other)
    }

    /// Largest |replay coefficient| accepted: ten times the recorded forces is already
    /// far beyond any interaction; larger values only make the physics diverge.
    pub const MAX_COEFFICIENT: f64 = 10.0;
    /// Largest |push| per hand accepted, N (the G1 weighs 33 kg; a probe beyond this
    /// measures nothing but divergence).
    pub const MAX_PUSH_N: f64 = 1000.0;

    /// Parses `force`, `no-force`, a replay coefficient (|c| ≤ [`Self::MAX_COEFFICIENT`]),
    /// or `push:<N>` (|N| ≤ [`Self::MAX_PUSH_N`]) with an optional `@<deg>` direction from
    /// the reference's initial heading (−360 ≤ deg ≤ 360).
    pub fn parse(s: &str) -> Option<Self> {
        let plain = |name: String, coefficient: f64| Self {
            name,
            coefficient,
            push_n: 0.0,
            push_heading_deg: None,
        };
        match s {
            "force" => Some(plain("force".into(), 1.0)),
            "no-force" => Some(plain("no-force".into(), 0.0)),
            other => {
                if let Some(spec) = other.strip_prefix("push:") {
                    let (n, deg) = match spec.split_once('@') {
                        Some((n, deg)) => (n, Some(deg)),
                        None => (spec, None),
                    };
                    let n: f64 = n
                        .parse()
                        .ok()
                        .filter(|n: &f64| n.is_finite() && n.abs() <= Self::MAX_PUSH_N)?;
                    let deg: Option<f64> = match deg {
                        Some(d) => Some(
                            d.parse()
                                .ok()
                                .filter(|d: &f64| d.is_finite() && d.abs() <= 360.0)?,
                        ),
                        None => None,
                    };
                    return Some(Self {
                        name: match deg {
                            Some(d) => format!("push-{n}@{d}"),
                            None => format!("push-{n}"),
                        },
                        coefficient: 0.0,
                        push_n: n,
                        push_heading_deg: deg,
                    });
                }
                other
                    .parse::<f64>()
                    .ok()
                    .filter(|c| c.is_finite() && c.abs() <= Self::MAX_COEFFICIENT)
                    .map(|c| plain(format!("coef-{c}"), c))
            }
        }
    }
}

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

/// The rules of the policy's answers: the same for every policy of a comparison, so they
/// are part of the run's identity (`run.json`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PolicyIoRules {
    /// Deadline-miss (and invalid-action) rule.
    pub miss_rule: MissRule,
    /// When actions take effect in simulated time.
    pub latency_mode: LatencyMode,
    /// Largest usable |raw action| (units of the profile's action); beyond it, or
    /// non-finite, an action is invalid and the miss rule applies.
    pub max_abs_action: f64,
    /// Latency budget per step, s (`None`: lock-step). Enforced by remote policies.
    pub budget_s: Option<f64>,
}

impl Default for PolicyIoRules {
    fn default() -> Self {
        Self {
            miss_rule: MissRule::Hold,
            latency_mode: LatencyMode::Ignore,
            max_abs_action: 100.0,
            budget_s: None,
        }
    }
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
