//! The vocabulary of an evaluation, below both the runner that performs one and the run
//! directory that stores it: force [`Setting`]s, the rules every policy is held to
//! ([`TerminationRule`], [`PolicyIoRules`], [`Budget`]), the [`schedule`] of episodes, an
//! episode's identity ([`EpisodeKey`]) and outcome ([`EpisodeRecord`], [`Termination`],
//! [`PolicyFaults`]), the regime thresholds of a dataset's tasks, the policy's latency
//! histogram — and [`EvalRequest`], one evaluation as asked for, which [`EvalSpec`] checks.
//!
//! The room's units, from the ground up: [`metrics`] (FATS from plain arrays), [`episode`]
//! (one rollout as a state machine), [`runner`] (a whole dataset over workers), [`results`]
//! (the run directory), [`sanity`] (the check before scores count) and [`pipeline`] (an
//! evaluation end to end). `runner` and `results` both point down at this vocabulary and
//! never at each other, so a record can travel from the runner to the report without
//! either knowing the other.

pub mod episode;
pub mod flag_names;
pub mod metrics;
pub mod pipeline;
pub mod results;
pub mod rollout_data;
pub mod runner;
pub mod sanity;

mod episode_record;
mod latency;
mod outside_training;
mod request;
mod rules;
mod sanity_record;
mod schedule;
mod setting;
mod spec;
mod thresholds;

pub use episode_record::{EpisodeKey, EpisodeRecord, PolicyFault, PolicyFaults, Termination};
pub use latency::{LatencyRecorder, LatencySummary};
pub use outside_training::{
    outside_training, setting_outside, OutsideTraining, SettingOutside, TaskForceSpans,
};
pub use request::{parse_shard, EngineChoice, EvalRequest, RequestFileError};
pub use rules::{check_budget_s, parse_budget, short_number, Budget, MAX_BUDGET, MIN_BUDGET};
pub use rules::{LatencyMode, MissRule, PolicyIoRules, TerminationRule};
pub use sanity_record::SanityRecord;
pub use schedule::{reference_steps, schedule};
pub use setting::{spelled as spelled_settings, Setting, SettingError};
pub use spec::{
    check_settings, Advice, EvalSpec, SpecError, DEFAULT_SETTINGS, MAX_ENVS, MAX_PIPELINE_DEPTH,
    MAX_SUBSTEPS, MAX_WORKERS,
};
pub use thresholds::task_thresholds;
