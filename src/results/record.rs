//! One finished episode, as `episodes.jsonl` holds it, and what makes a record believable.

use super::RunHeader;
use crate::episode::{PolicyFaults, Termination};
use crate::metrics::EpisodeSeries;
use serde::{Deserialize, Serialize};

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
    /// The episode's identity in a run: (task, sequence id, setting).
    pub fn key(&self) -> (String, String, String) {
        (
            self.task.clone(),
            self.sequence_id.clone(),
            self.setting.clone(),
        )
    }

    /// Whether this record can have been written by the run `header` describes: policy,
    /// setting (and its coefficient) and sequence are the header's, the episode is one of
    /// this run's (or shard's) jobs, every series has one finite, non-negative value per
    /// recorded step, no more steps than the reference has, and all of them unless the
    /// episode ended early. The error names the episode and what is wrong.
    pub fn check(&self, header: &RunHeader) -> Result<(), String> {
        let name = format!("{}/{} ({})", self.task, self.sequence_id, self.setting);
        let bad = |what: String| Err(format!("episode {name}: {what}"));
        if self.policy != header.policy {
            return bad(format!(
                "policy `{}`, but the run is of `{}`",
                self.policy, header.policy
            ));
        }
        let Some(s) = header.setting_index(&self.setting) else {
            return bad("a setting this run does not have".into());
        };
        let setting = &header.settings[s];
        if self.coefficient.to_bits() != setting.coefficient.to_bits() {
            return bad(format!(
                "coefficient {}, but the run's setting has {}",
                self.coefficient, setting.coefficient
            ));
        }
        let Some(q) = header.sequence_index(&self.task, &self.sequence_id) else {
            return bad("a task and sequence not in the run's dataset".into());
        };
        if let Some((i, n)) = header.shard {
            let job = s * header.sequences.len() + q;
            if job % n != i {
                return bad(format!("an episode of another shard than {i}/{n}"));
            }
        }
        let steps_ref = header.sequences[q].steps_ref;
        let series = &self.series;
        if series.steps_ref != steps_ref {
            return bad(format!(
                "steps_ref {}, but the reference has {steps_ref} control steps",
                series.steps_ref
            ));
        }
        let columns: [(&str, &[f64]); 6] = [
            ("kp_err_m", &series.kp_err_m),
            ("kp_err_upper_m", &series.kp_err_upper_m),
            ("kp_err_lower_m", &series.kp_err_lower_m),
            ("total_force_n", &series.total_force_n),
            ("power_w", &series.power_w),
            ("root_drift_m", &series.root_drift_m),
        ];
        let steps = series.kp_err_m.len();
        for (column, values) in columns {
            if values.len() != steps {
                return bad(format!(
                    "{column} has {} values, kp_err_m {steps}: one value per recorded step",
                    values.len()
                ));
            }
            if let Some(k) = values.iter().position(|v| !(v.is_finite() && *v >= 0.0)) {
                return bad(format!(
                    "{column}[{k}] is {}: a finite, non-negative value is recorded",
                    values[k]
                ));
            }
        }
        if steps > steps_ref {
            return bad(format!(
                "{steps} recorded steps, more than the reference's {steps_ref}"
            ));
        }
        if self.termination.is_none() && steps != steps_ref {
            return bad(format!(
                "{steps} of {steps_ref} steps recorded, but no termination says why it ended early"
            ));
        }
        Ok(())
    }
}
