//! What makes an episode record believable: that the run its header describes can have
//! written it.

use super::RunHeader;
use crate::eval::EpisodeRecord;

impl RunHeader {
    /// Whether `record` can have been written by the run this header describes: policy,
    /// setting (and its coefficient) and sequence are the header's, the episode is one of
    /// this run's (or shard's) jobs, every series has one finite, non-negative value per
    /// recorded step, no more steps than the reference has, and all of them unless the
    /// episode ended early. The error names the episode and what is wrong.
    pub fn check_record(&self, record: &EpisodeRecord) -> Result<(), String> {
        let header = self;
        let name = record.key();
        let bad = |what: String| Err(format!("episode {name}: {what}"));
        if record.policy != header.policy {
            return bad(format!(
                "policy `{}`, but the run is of `{}`",
                record.policy, header.policy
            ));
        }
        let Some(s) = header.setting_index(&record.setting) else {
            return bad("a setting this run does not have".into());
        };
        let setting = &header.settings[s];
        if record.coefficient.to_bits() != setting.coefficient.to_bits() {
            return bad(format!(
                "coefficient {}, but the run's setting has {}",
                record.coefficient, setting.coefficient
            ));
        }
        let Some(q) = header.sequence_index(&record.task, &record.sequence_id) else {
            return bad("a task and sequence not in the run's dataset".into());
        };
        if let Some((i, n)) = header.shard {
            let job = s * header.sequences.len() + q;
            if job % n != i {
                return bad(format!("an episode of another shard than {i}/{n}"));
            }
        }
        let steps_ref = header.sequences[q].steps_ref;
        let series = &record.series;
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
        // Recorded since the global error was: absent (empty) in older records.
        let global: Option<(&str, &[f64])> = (!series.kp_err_global_m.is_empty())
            .then_some(("kp_err_global_m", series.kp_err_global_m.as_slice()));
        for (column, values) in columns.into_iter().chain(global) {
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
        if record.termination.is_none() && steps != steps_ref {
            return bad(format!(
                "{steps} of {steps_ref} steps recorded, but no termination says why it ended early"
            ));
        }
        Ok(())
    }
}
