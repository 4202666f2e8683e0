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

use crate::eval::EvalSpec;

/// What the runner needs of an evaluation ([`Self::of`] an [`EvalSpec`]).
pub struct EvalPlan<'a> {
    /// The checked evaluation: robot, profile, keypoints, termination, settings, threads,
    /// slots, pipeline, policy I/O rules, traces and engine (checked by its loader: a
    /// physics can be made for it).
    pub spec: &'a EvalSpec,
    /// Record the trace of every other episode too, over its first this many seconds
    /// (`crosscheck` compares the engines' joint angles there).
    pub trace_first_s: Option<f64>,
}

impl<'a> EvalPlan<'a> {
    /// The runner's view of a checked evaluation; with `trace_first_s`, every episode also
    /// records its first seconds (what `crosscheck` compares).
    pub fn of(spec: &'a EvalSpec, trace_first_s: Option<f64>) -> Self {
        Self {
            spec,
            trace_first_s,
        }
    }
}
