//! Which of a dataset's sequences an evaluation runs: all of them (the benchmark), or those
//! of some tasks and/or some sequences (`eval --tasks`, `--sequences`, a sweep's `tasks`
//! and `sequences`). A run records its selection, so a partial run is never read as full
//! coverage of its dataset.

use serde::{Deserialize, Serialize};
use thiserror::Error;

/// A selection of sequences. Empty lists select everything; both given, a sequence must
/// pass both.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SequenceSelection {
    /// Tasks to keep (empty: every task).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub tasks: Vec<String>,
    /// Sequences to keep, each as `SEQUENCE_ID` or `TASK/SEQUENCE_ID` (empty: every one).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub sequences: Vec<String>,
}

/// A selection that names something the dataset does not hold, or keeps nothing.
#[derive(Debug, Error, PartialEq, Eq)]
pub enum SelectionError {
    /// A task the dataset does not have.
    #[error("no task `{task}` in the dataset (it has: {available})")]
    UnknownTask {
        /// As given.
        task: String,
        /// The dataset's tasks, comma separated.
        available: String,
    },
    /// A sequence the dataset does not have.
    #[error("no sequence `{sequence}` in the dataset (give SEQUENCE_ID or TASK/SEQUENCE_ID; `thorarena data info` lists them)")]
    UnknownSequence {
        /// As given.
        sequence: String,
    },
    /// Every name exists, but no sequence passes both lists.
    #[error("no sequence is of the tasks {tasks} and among the sequences {sequences}")]
    Empty {
        /// The tasks, comma separated.
        tasks: String,
        /// The sequences, comma separated.
        sequences: String,
    },
    /// A name given twice (it would not run twice, but it is almost always a typo).
    #[error("`{0}` is given twice")]
    Repeated(String),
}

impl SequenceSelection {
    /// Every sequence.
    pub fn is_all(&self) -> bool {
        self.tasks.is_empty() && self.sequences.is_empty()
    }

    /// The items of `items` the selection keeps, in their order; `key` gives an item's
    /// `(task, sequence_id)`. Every task and sequence named must exist.
    pub fn pick<T>(
        &self,
        items: Vec<T>,
        key: impl Fn(&T) -> (&str, &str),
    ) -> Result<Vec<T>, SelectionError> {
        for list in [&self.tasks, &self.sequences] {
            for (i, name) in list.iter().enumerate() {
                if list[..i].contains(name) {
                    return Err(SelectionError::Repeated(name.clone()));
                }
            }
        }
        for task in &self.tasks {
            if !items.iter().any(|t| key(t).0 == task) {
                let mut available: Vec<&str> = items.iter().map(|t| key(t).0).collect();
                available.dedup();
                return Err(SelectionError::UnknownTask {
                    task: task.clone(),
                    available: available.join(", "),
                });
            }
        }
        for sequence in &self.sequences {
            if !items.iter().any(|t| names(sequence, key(t))) {
                return Err(SelectionError::UnknownSequence {
                    sequence: sequence.clone(),
                });
            }
        }
        let kept: Vec<T> = items
            .into_iter()
            .filter(|t| {
                let k = key(t);
                (self.tasks.is_empty() || self.tasks.iter().any(|task| task == k.0))
                    && (self.sequences.is_empty() || self.sequences.iter().any(|s| names(s, k)))
            })
            .collect();
        if kept.is_empty() {
            return Err(SelectionError::Empty {
                tasks: self.tasks.join(", "),
                sequences: self.sequences.join(", "),
            });
        }
        Ok(kept)
    }

    /// `tasks a,b; sequences x`, the selection's fields as given; empty for everything.
    pub fn spelled(&self) -> String {
        let mut parts = Vec::new();
        if !self.tasks.is_empty() {
            parts.push(format!("tasks {}", self.tasks.join(",")));
        }
        if !self.sequences.is_empty() {
            parts.push(format!("sequences {}", self.sequences.join(",")));
        }
        parts.join("; ")
    }
}

/// Whether `given` (`ID` or `TASK/ID`) names the sequence `(task, id)`.
fn names(given: &str, (task, id): (&str, &str)) -> bool {
    match given.split_once('/') {
        Some((t, i)) => t == task && i == id,
        None => given == id,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dataset() -> Vec<(&'static str, &'static str)> {
        vec![
            ("clean_table", "clean_table_000"),
            ("clean_table", "clean_table_001"),
            ("push_chair", "push_chair_000"),
            ("push_chair", "x"),
            ("pull_chair", "x"),
        ]
    }

    fn pick(
        tasks: &[&str],
        sequences: &[&str],
    ) -> Result<Vec<(&'static str, &'static str)>, SelectionError> {
        let s = SequenceSelection {
            tasks: tasks.iter().map(|t| t.to_string()).collect(),
            sequences: sequences.iter().map(|t| t.to_string()).collect(),
        };
        s.pick(dataset(), |&(t, i)| (t, i))
    }

    #[test]
    fn tasks_and_sequences_narrow_together_in_dataset_order() {
        assert_eq!(pick(&[], &[]).unwrap().len(), 5);
        assert_eq!(
            pick(&["push_chair", "clean_table"], &[]).unwrap(),
            &dataset()[..4]
        );
        assert_eq!(pick(&[], &["x"]).unwrap(), &dataset()[3..]);
        assert_eq!(pick(&[], &["pull_chair/x"]).unwrap(), &dataset()[4..]);
        assert_eq!(pick(&["push_chair"], &["x"]).unwrap(), &dataset()[3..4]);
    }

    #[test]
    fn unknown_names_and_empty_selections_are_errors() {
        assert!(matches!(
            pick(&["push_chiar"], &[]),
            Err(SelectionError::UnknownTask { available, .. }) if available == "clean_table, push_chair, pull_chair"
        ));
        assert!(matches!(
            pick(&[], &["push_chair/clean_table_000"]),
            Err(SelectionError::UnknownSequence { .. })
        ));
        assert!(matches!(
            pick(&["pull_chair"], &["clean_table_000"]),
            Err(SelectionError::Empty { .. })
        ));
        assert_eq!(
            pick(&["push_chair", "push_chair"], &[]),
            Err(SelectionError::Repeated("push_chair".into()))
        );
    }
}

/// A run of part of its dataset: the selection, and how many sequences the whole dataset
/// has (so a table can say "2 of 12 sequences").
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Subset {
    /// Tasks and sequences chosen.
    #[serde(flatten)]
    pub selection: SequenceSelection,
    /// Sequences of the whole dataset.
    pub dataset_sequences: usize,
}

impl Subset {
    /// "2 of the dataset's 12 sequences (tasks push_chair)".
    pub fn describe(&self, planned: usize) -> String {
        format!(
            "{planned} of the dataset's {} sequences ({})",
            self.dataset_sequences,
            self.selection.spelled()
        )
    }
}
