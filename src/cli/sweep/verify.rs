//! A task's run checked against its plan entry ([`thorarena::sweep::check_task_run`]).
//!
//! `done.json` says a run was complete when its task finished; the run directory can
//! change after that (edited, replaced, cut short by hand). So every command that counts
//! a task done — `status`, `collect`, and `run`/`task` deciding whether to skip it —
//! checks the run itself, here.

use std::path::Path;
use thorarena::evaluation::EpisodeRecord;
use thorarena::results::RunDir;
pub(super) use thorarena::sweep::RunProblem;
use thorarena::sweep::{census, Census, Plan, Task, TaskDir};

/// The run's records when `run` is complete and is task `task`'s.
pub(super) fn check_task_run(
    plan: &Plan,
    task: &Task,
    run: &Path,
) -> anyhow::Result<Result<Vec<EpisodeRecord>, RunProblem>> {
    Ok(thorarena::sweep::check_task_run(
        plan,
        task,
        &RunDir::new(run),
    )?)
}

/// Why a task marked done does not count, in one line.
pub(super) fn problem_text(problem: &RunProblem) -> &str {
    match problem {
        RunProblem::Incomplete(why) | RunProblem::NotThisTask(why) => why,
    }
}

/// The tasks by state as [`census`] reads them, except that a task counts as done only
/// when its run does: those whose `done.json` is there but whose run does not count are
/// in `not_counted`, with why, and among the not-done tasks.
pub(super) struct CheckedCensus {
    /// The directories' census, `done` holding only the tasks whose run counts.
    pub census: Census,
    /// Tasks marked done whose run does not count, with why, in task order (a run that
    /// cannot be read is `Incomplete`: `eval --resume` says what is wrong with it).
    pub not_counted: Vec<(usize, RunProblem)>,
}

impl CheckedCensus {
    /// Every task of `plan` in sweep directory `dir`, each done task's run checked. A run
    /// that cannot be read at all does not count (the reason names the file): a command
    /// that only reports — `status` — never stops at it.
    pub fn of(dir: &Path, plan: &Plan) -> anyhow::Result<Self> {
        let mut census = census(dir, plan)?;
        let mut not_counted = Vec::new();
        census.done.retain(|&i| {
            let run = TaskDir::of(dir, i).run_dir();
            let problem = match check_task_run(plan, &plan.tasks[i], &run) {
                Ok(Ok(_)) => return true,
                Ok(Err(problem)) => problem,
                Err(e) => RunProblem::Incomplete(format!("its run cannot be read: {e:#}")),
            };
            not_counted.push((i, problem));
            false
        });
        Ok(Self {
            census,
            not_counted,
        })
    }

    /// The tasks to run: failed, started, not started, and marked done without counting.
    pub fn not_done(&self) -> Vec<usize> {
        let mut v = self.census.not_done();
        v.extend(self.not_counted.iter().map(|(i, _)| *i));
        v.sort_unstable();
        v
    }
}
