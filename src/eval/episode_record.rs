//! One finished episode: how it ended, what the policy got wrong, and the series its
//! scores are computed from — what the runner produces and the run directory stores.

use crate::eval::metrics::EpisodeSeries;
use serde::{Deserialize, Serialize};

/// Why an episode ended early.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Termination {
    /// Torso height error above the rule's limit.
    TorsoHeight,
    /// Torso tilt error above the rule's limit.
    TorsoTilt,
    /// The policy missed its latency budget under the `fail` miss rule.
    DeadlineMiss,
    /// The policy sent a non-finite or out-of-range action under the `fail` miss rule.
    InvalidAction,
    /// The policy process died or left mid-episode (not the policy's tracking: a run
    /// resumed with `--resume` runs such episodes again).
    PolicyFailed,
    /// The physics state became non-finite (absurd forces or gains): counted as a fall,
    /// and the step that diverged is not recorded, so no NaN reaches the results.
    PhysicsDiverged,
}

/// One way a policy's answer can fail an environment for one control step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PolicyFault {
    /// No action within the latency budget.
    DeadlineMiss,
    /// A non-finite action, or one beyond the profile's `max_abs_action`.
    InvalidAction,
}

impl PolicyFault {
    /// The termination it causes under the `fail` miss rule.
    pub fn termination(self) -> Termination {
        match self {
            Self::DeadlineMiss => Termination::DeadlineMiss,
            Self::InvalidAction => Termination::InvalidAction,
        }
    }
}

/// Ways a policy's answer failed an environment, counted per episode.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default)]
pub struct PolicyFaults {
    /// Control steps whose action missed the latency budget.
    pub deadline_misses: u64,
    /// Control steps whose action was non-finite or beyond the profile's `max_abs_action`.
    pub invalid_actions: u64,
}

impl PolicyFaults {
    /// True when nothing went wrong (kept out of the results then).
    pub fn is_empty(&self) -> bool {
        *self == Self::default()
    }
}

/// An episode's identity in a run: no run holds two records of one key.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct EpisodeKey {
    /// Task.
    pub task: String,
    /// Sequence id.
    pub sequence_id: String,
    /// Setting name.
    pub setting: String,
}

impl std::fmt::Display for EpisodeKey {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{} ({})", self.task, self.sequence_id, self.setting)
    }
}

/// One finished episode, as streamed to `episodes.jsonl`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EpisodeRecord {
    /// Task.
    pub task: String,
    /// Sequence id.
    pub sequence_id: String,
    /// Setting name.
    pub setting: String,
    /// Replay coefficient.
    pub coefficient: f64,
    /// Policy name.
    pub policy: String,
    /// Why it ended early, if it did.
    pub termination: Option<Termination>,
    /// Deadline misses and invalid actions (absent when there were none).
    #[serde(default, skip_serializing_if = "PolicyFaults::is_empty")]
    pub faults: PolicyFaults,
    /// The per-step series the scores are computed from.
    pub series: EpisodeSeries,
}

impl EpisodeRecord {
    /// The episode's identity in a run.
    pub fn key(&self) -> EpisodeKey {
        EpisodeKey {
            task: self.task.clone(),
            sequence_id: self.sequence_id.clone(),
            setting: self.setting.clone(),
        }
    }
}
