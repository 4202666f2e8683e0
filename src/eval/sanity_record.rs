//! What the sanity check said about a policy before its run (`run.json` `sanity`): the
//! record every score carries, so a reader knows whether the policy was shown to be wired
//! right (`thorarena::eval::sanity` runs the check; this is its vocabulary).

use serde::{Deserialize, Serialize};

/// The sanity check's verdict on a run's policy. A failed check refuses the run, so a run
/// exists only with one of these.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "status", rename_all = "snake_case")]
pub enum SanityRecord {
    /// Every check held, tracking `tracking_reference` (`task/sequence`).
    Passed {
        /// The reference the tracking and zero-action checks ran.
        tracking_reference: String,
    },
    /// The check was not run because the run said `--unchecked`: its scores are not
    /// shown to measure a correctly wired policy.
    Unchecked,
    /// The check does not apply: `why` (a built-in baseline is a floor, not a tracker; a
    /// policy process is checked by running its network in process).
    Exempt {
        /// Why.
        why: String,
    },
}

impl SanityRecord {
    /// One phrase for tables and logs.
    pub fn label(&self) -> String {
        match self {
            Self::Passed { tracking_reference } => {
                format!("passed (tracking {tracking_reference})")
            }
            Self::Unchecked => "not run (unchecked)".into(),
            Self::Exempt { why } => format!("exempt: {why}"),
        }
    }
}
