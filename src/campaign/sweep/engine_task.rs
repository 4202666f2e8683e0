//! One task as a cluster engine starts it (`sweep task`): its index given, or read from
//! the engine's environment (a Slurm array's `SLURM_ARRAY_TASK_ID`, a Kubernetes Indexed
//! Job's `JOB_COMPLETION_INDEX`), its workers given, or the CPUs Slurm allots, or the
//! cores. The same job script then serves every task.

use super::{at_least_one, run_task, Outcome, Plan, SweepError, TaskDir};
use std::fmt::{self, Display, Formatter};
use std::path::Path;

/// A Slurm array task's index.
const SLURM_INDEX_VAR: &str = "SLURM_ARRAY_TASK_ID";
/// A Kubernetes Indexed Job pod's index.
const K8S_INDEX_VAR: &str = "JOB_COMPLETION_INDEX";
/// The CPUs Slurm allots a task.
const SLURM_CPUS_VAR: &str = "SLURM_CPUS_PER_TASK";

/// The cores this process may use (1 when that cannot be known).
pub(super) fn available_cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// What a `sweep task` process is asked to run.
#[derive(Debug, Clone)]
pub struct EngineTask<'a> {
    /// The `thorarena` binary whose `eval` runs the task.
    pub exe: &'a Path,
    /// The sweep directory.
    pub dir: &'a Path,
    /// The task [default: from the cluster engine's environment].
    pub index: Option<usize>,
    /// Worker threads of its evaluation [default: Slurm's CPUs per task, else the cores].
    pub workers: Option<usize>,
}

/// A task that ended well.
#[derive(Debug, Clone, Copy)]
pub struct TaskEnded {
    /// The task.
    pub index: usize,
    /// It was done before, and skipped.
    pub already_done: bool,
}

/// Runs the task `task` names; a failed attempt is [`SweepError::TaskFailed`].
pub fn run_engine_task(task: &EngineTask) -> Result<TaskEnded, SweepError> {
    let index = match task.index {
        Some(i) => i,
        // Both read, so a malformed one is refused whichever engine runs this.
        None => env_usize(SLURM_INDEX_VAR)?
            .or(env_usize(K8S_INDEX_VAR)?)
            .ok_or(SweepError::NoTaskIndex)?,
    };
    let plan = Plan::load(task.dir)?;
    let workers = match task.workers {
        Some(w) => at_least_one(w, "option.workers")?,
        None => env_usize(SLURM_CPUS_VAR)?.unwrap_or_else(available_cores),
    };
    match run_task(task.exe, task.dir, &plan, index, workers)? {
        Outcome::Done => Ok(TaskEnded {
            index,
            already_done: false,
        }),
        Outcome::AlreadyDone => Ok(TaskEnded {
            index,
            already_done: true,
        }),
        Outcome::Failed(reason) => Err(SweepError::TaskFailed {
            index,
            reason,
            details: TaskDir::of(task.dir, index).failed_file(),
        }),
    }
}

/// A number from environment variable `var`; `None` when it is unset or empty.
fn env_usize(var: &'static str) -> Result<Option<usize>, SweepError> {
    match std::env::var(var) {
        Ok(value) if !value.is_empty() => value
            .trim()
            .parse()
            .map(Some)
            .map_err(|source| SweepError::BadEnvIndex { var, value, source }),
        _ => Ok(None),
    }
}

impl Display for TaskEnded {
    /// The line `sweep task` prints.
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        if self.already_done {
            write!(f, "task {}: already done, skipped", self.index)
        } else {
            write!(f, "task {}: done", self.index)
        }
    }
}
