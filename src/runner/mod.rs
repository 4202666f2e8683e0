//! The full-coverage evaluation: every sequence of a dataset once per setting, spread over
//! worker threads, each finished episode streamed to a JSON-lines file, and the scores
//! aggregated per setting.
//!
//! Determinism: an episode's result depends only on its sequence, setting and policy (a
//! reset rebuilds the physics world; policies are created per worker and reset per
//! episode), and aggregates sum in (task, id) order, so results are identical for any
//! number of workers.
//!
//! Two loops over N environment slots, the slots' physics spread over worker threads.
//! `lockstep`: the coordinator hands the whole batch of observations to the policy each
//! control step — a policy process over shared memory, or a built-in — and applies the
//! returned actions. `free_running`: a policy with copies for the workers (the networks in
//! process) acts on each worker for its own slots, and the workers never wait for each
//! other.

mod free_running;
mod lockstep;

pub use lockstep::{run_eval, RunOutcome};

use crate::evaluation::{EvalSpec, PolicyIoRules, Setting, TerminationRule};
use crate::profile::Profile;
use crate::robot::RobotModel;

/// What the runner needs of an evaluation ([`Self::of`] an [`EvalSpec`]).
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
    /// Slot groups of the lock-step loop: 1, one batch of every slot per control step; 2,
    /// the slots split in two halves, the workers stepping one while the policy answers
    /// for the other (checked by [`EvalSpec`]; the free-running loop has no groups).
    pub pipeline_depth: usize,
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

impl<'a> EvalPlan<'a> {
    /// The runner's view of a checked evaluation; with `trace_first_s`, every episode also
    /// records its first seconds (what `crosscheck` compares).
    pub fn of(spec: &'a EvalSpec, trace_first_s: Option<f64>) -> Self {
        Self {
            robot: &spec.robot,
            profile: &spec.profile,
            keypoints: &spec.keypoints,
            termination: spec.termination,
            settings: spec.settings.clone(),
            workers: spec.workers,
            envs: spec.envs,
            pipeline_depth: spec.pipeline_depth,
            io: spec.io,
            trace: spec.trace.clone(),
            trace_first_s,
            engine: spec.engine.clone(),
        }
    }
}
