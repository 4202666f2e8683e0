//! The tasks `collect` scores: done, and their run complete and the task's own. A task
//! marked done whose run is another configuration's stops the collect (a run that is not
//! the cell's is never scored under its label); one whose run is incomplete is not
//! counted, said so, and its cell is unfinished — which a collect refuses unless asked
//! for a partial one.

use super::{compact_ranges, CheckedCensus, Plan, RunProblem, SweepError, TaskDir};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// A sweep's tasks as `collect` counts them.
#[derive(Debug)]
pub struct CountedTasks {
    /// Tasks whose run counts.
    pub done: BTreeSet<usize>,
    /// `task I: why` for each task marked done whose run does not count.
    pub not_counted: Vec<String>,
    /// Cells with a task not done, in order.
    pub unfinished_cells: Vec<usize>,
    /// Tasks not done, in order.
    pub not_done: Vec<usize>,
}

impl CountedTasks {
    /// Counts the tasks of `plan` in sweep directory `dir`, each done task's run checked;
    /// [`SweepError::NotThisTask`] for a done task holding another configuration's run.
    pub fn of(dir: &Path, plan: &Plan) -> Result<Self, SweepError> {
        let checked = CheckedCensus::of(dir, plan)?;
        let mut not_counted = Vec::new();
        for (i, problem) in checked.not_counted {
            match problem {
                RunProblem::NotThisTask(why) => {
                    return Err(SweepError::NotThisTask {
                        why,
                        run_dir: TaskDir::of(dir, i).run_dir(),
                    })
                }
                RunProblem::Incomplete(why) => not_counted.push(format!("task {i}: {why}")),
            }
        }
        let done: BTreeSet<usize> = checked.census.done.into_iter().collect();
        let not_done: Vec<usize> = (0..plan.tasks.len())
            .filter(|i| !done.contains(i))
            .collect();
        let unfinished_cells: BTreeSet<usize> =
            not_done.iter().map(|&i| plan.tasks[i].cell).collect();
        Ok(Self {
            done,
            not_counted,
            unfinished_cells: unfinished_cells.into_iter().collect(),
            not_done,
        })
    }

    /// Refuses unfinished cells unless `partial`: [`SweepError::Unfinished`] says which,
    /// which tasks are not done, and why tasks marked done do not count.
    pub fn require_finished(&self, plan: &Plan, partial: bool) -> Result<(), SweepError> {
        if self.unfinished_cells.is_empty() || partial {
            return Ok(());
        }
        Err(SweepError::Unfinished {
            unfinished: self.unfinished_cells.len(),
            cells: plan.cells.len(),
            unfinished_cells: compact_ranges(&self.unfinished_cells),
            not_done: compact_ranges(&self.not_done),
            not_counted: self.not_counted.iter().map(|w| format!("; {w}")).collect(),
        })
    }

    /// The run directories of cell `cell`'s done tasks in sweep directory `dir`, in task
    /// order.
    pub fn runs_of_cell(&self, dir: &Path, plan: &Plan, cell: usize) -> Vec<PathBuf> {
        plan.tasks
            .iter()
            .filter(|t| t.cell == cell && self.done.contains(&t.index))
            .map(|t| TaskDir::of(dir, t.index).run_dir())
            .collect()
    }
}
