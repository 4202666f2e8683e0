//! Whether a named tracker held each sequence without force (`data check --rollout`): a
//! sequence a good tracker cannot hold with no force on it is a data problem, not a
//! policy result. The rollouts are run elsewhere (`campaign::data_check`); this is what
//! the check reports of them.

use serde::Serialize;
use std::fmt::Write;

/// One sequence's rollout without force.
#[derive(Debug, Clone, Serialize)]
pub struct SequenceHeld {
    /// Task.
    pub task: String,
    /// Sequence id.
    pub sequence_id: String,
    /// The share of the reference's control steps the tracker stayed up for, 0 to 1
    /// (the benchmark's survival).
    pub survival: f64,
    /// Why the episode ended early (the run's termination, snake case), if it did.
    pub ended_by: Option<String>,
}

impl SequenceHeld {
    /// The tracker stayed up to the reference's end.
    pub fn held(&self) -> bool {
        self.ended_by.is_none() && self.survival >= 1.0
    }
}

/// A tracker's rollouts of every sequence of the checked dataset, without force.
#[derive(Debug, Clone, Serialize)]
pub struct TrackerHeld {
    /// The policy, as it was named.
    pub policy: String,
    /// Physics engine of the rollouts.
    pub engine: String,
    /// The run directory holding the rollouts (`thorarena view`, `report` read it).
    pub run: String,
    /// Per sequence, in the dataset's order.
    pub sequences: Vec<SequenceHeld>,
}

impl TrackerHeld {
    /// Sequences of `task`, and how many of them the tracker held.
    pub fn held_of(&self, task: &str) -> (usize, usize) {
        let of_task = self.sequences.iter().filter(|s| s.task == task);
        let held = of_task.clone().filter(|s| s.held()).count();
        (held, of_task.count())
    }

    /// Mean survival over the sequences of `task` (NaN without any).
    pub fn mean_survival(&self, task: &str) -> f64 {
        let v: Vec<f64> = self
            .sequences
            .iter()
            .filter(|s| s.task == task)
            .map(|s| s.survival)
            .collect();
        v.iter().sum::<f64>() / v.len() as f64
    }

    /// The Markdown section: per task in `tasks`' order, the sequences held and the mean
    /// survival; then every sequence not held, with when and why it ended.
    pub fn markdown(&self, tasks: &[&str]) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "\n## Held without force by {} ({}; run {})\n",
            self.policy, self.engine, self.run
        );
        let _ = writeln!(s, "| task | sequences held | mean survival |");
        let _ = writeln!(s, "|---|---:|---:|");
        for task in tasks {
            let (held, of) = self.held_of(task);
            let mean = self.mean_survival(task);
            let _ = writeln!(s, "| {task} | {held} / {of} | {mean:.3} |");
        }
        let dropped: Vec<&SequenceHeld> = self.sequences.iter().filter(|q| !q.held()).collect();
        if dropped.is_empty() {
            let _ = writeln!(s, "\nEvery sequence held to its end.");
        } else {
            let _ = writeln!(
                s,
                "\nNot held (a data problem unless the tracker is at fault):\n"
            );
            for q in dropped {
                let why = q.ended_by.as_deref().unwrap_or("ended early");
                let _ = writeln!(
                    s,
                    "- {}/{}: {why} at {:.0} % of the reference",
                    q.task,
                    q.sequence_id,
                    100.0 * q.survival
                );
            }
        }
        s
    }
}
