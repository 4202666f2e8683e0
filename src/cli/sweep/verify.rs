//! A task's run checked against its plan entry ([`thorarena::sweep::check_task_run`]),
//! with the task's `eval` arguments parsed as `eval` parses them.

use super::plan::eval_cli;
use std::path::Path;
use thorarena::evaluation::EpisodeRecord;
use thorarena::results::RunDir;
pub(super) use thorarena::sweep::RunProblem;
use thorarena::sweep::{Plan, Task};

/// The run's records when `run` is complete and is task `task`'s.
pub(super) fn check_task_run(
    plan: &Plan,
    task: &Task,
    run: &Path,
) -> anyhow::Result<Result<Vec<EpisodeRecord>, RunProblem>> {
    let args = eval_cli(task, "check")?;
    let request = args.run.request(&args.policy);
    Ok(thorarena::sweep::check_task_run(
        plan,
        task,
        &RunDir::new(run),
        &request,
    )?)
}
