//! How much of its plan a run holds: a run killed early, a cut file or a policy that died
//! leaves cells with fewer episodes than planned, and every table built from it says so.

use super::RunHeader;
use crate::eval::EpisodeRecord;
use crate::eval::Termination;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt::Write;

/// Episodes of one (setting, task) cell.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct CellCoverage {
    /// Setting name.
    pub setting: String,
    /// Task.
    pub task: String,
    /// Episodes the run's plan (or shard) holds.
    pub expected: usize,
    /// Episodes recorded.
    pub present: usize,
    /// Of those, episodes cut short because the policy process failed (scored as ended
    /// there; `eval --resume` runs them again).
    pub policy_failed: usize,
}

/// Every cell of a run, in schedule order (settings, then tasks in dataset order).
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Coverage {
    /// The cells.
    pub cells: Vec<CellCoverage>,
}

impl Coverage {
    /// The coverage of `records` (already checked against `header`).
    pub fn of(header: &RunHeader, records: &[EpisodeRecord]) -> Self {
        let mut index: BTreeMap<(usize, String), usize> = BTreeMap::new();
        let mut cells: Vec<CellCoverage> = Vec::new();
        let mut cell = |s: usize, task: &str| -> usize {
            *index.entry((s, task.to_string())).or_insert_with(|| {
                cells.push(CellCoverage {
                    setting: header.settings[s].name.clone(),
                    task: task.to_string(),
                    expected: 0,
                    present: 0,
                    policy_failed: 0,
                });
                cells.len() - 1
            })
        };
        let mut planned = Vec::new();
        for (q, s) in header.planned_jobs() {
            planned.push(cell(s, &header.sequences[q].task));
        }
        let mut found = Vec::new();
        for r in records {
            let s = header.setting_index(&r.setting).unwrap_or(usize::MAX);
            if s < header.settings.len() {
                found.push((
                    cell(s, &r.task),
                    r.termination == Some(Termination::PolicyFailed),
                ));
            }
        }
        for i in planned {
            cells[i].expected += 1;
        }
        for (i, failed) in found {
            cells[i].present += 1;
            cells[i].policy_failed += usize::from(failed);
        }
        Self { cells }
    }

    /// Every planned episode is recorded, none cut short by a policy failure.
    pub fn is_complete(&self) -> bool {
        self.cells
            .iter()
            .all(|c| c.present == c.expected && c.policy_failed == 0)
    }

    /// Planned episodes not recorded.
    pub fn missing(&self) -> usize {
        self.cells
            .iter()
            .map(|c| c.expected.saturating_sub(c.present))
            .sum()
    }

    /// Episodes cut short by a policy failure.
    pub fn policy_failed(&self) -> usize {
        self.cells.iter().map(|c| c.policy_failed).sum()
    }

    /// One sentence on what is missing; `None` when complete.
    pub fn sentence(&self) -> Option<String> {
        (!self.is_complete()).then(|| {
            let expected: usize = self.cells.iter().map(|c| c.expected).sum();
            format!(
                "partial run: {} of {expected} planned episodes missing, {} cut short by a policy failure (scored as ended there); `thorarena eval --resume` on the run runs them",
                self.missing(),
                self.policy_failed()
            )
        })
    }

    /// The cells that are not complete, as a Markdown table of present / expected.
    pub fn markdown(&self) -> String {
        let mut s = String::from(
            "| Setting | Task | Episodes present / expected | Cut short by a policy failure |\n|---|---|---:|---:|\n",
        );
        for c in self
            .cells
            .iter()
            .filter(|c| c.present != c.expected || c.policy_failed > 0)
        {
            let _ = writeln!(
                s,
                "| {} | {} | {} / {} | {} |",
                c.setting, c.task, c.present, c.expected, c.policy_failed
            );
        }
        s
    }
}
