//! `sweep run` in one call: every task not done — a task marked done whose run no longer
//! counts included — run on the local pool, `jobs` at a time, the cores shared among
//! them, with what happens told to an observer as it goes (a sweep can run for hours).

use super::{at_least_one, PoolProgress, SweepError};
use super::{available_cores, printable, run_pool, CheckedCensus, Outcome, Plan, Pool};
use std::fmt::{self, Display, Formatter};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A local run of a sweep as asked for.
#[derive(Debug, Clone)]
pub struct LocalRun<'a> {
    /// The `thorarena` binary whose `eval` runs each task.
    pub exe: &'a Path,
    /// The sweep directory.
    pub dir: &'a Path,
    /// Tasks at a time [default: the cores]; each gets cores / jobs workers.
    pub jobs: Option<usize>,
}

/// What a run is about to do.
#[derive(Debug, Clone)]
pub struct RunStarting {
    /// The sweep directory, as given.
    pub dir: PathBuf,
    /// Tasks to run now.
    pub to_run: usize,
    /// Tasks planned.
    pub tasks: usize,
    /// Episodes planned, done ones included: what the progress counts up to.
    pub episodes: usize,
    /// Tasks at a time.
    pub jobs: usize,
    /// Worker threads per task.
    pub workers: usize,
}

/// Where a run stands.
#[derive(Debug, Clone, Copy)]
pub struct RunProgress {
    /// The pool's count (episodes include those done before).
    pub pool: PoolProgress,
    /// Tasks this run started with.
    pub to_run: usize,
}

/// How a run ended.
#[derive(Debug, Clone)]
pub struct RunFinished {
    /// The sweep directory, as given.
    pub dir: PathBuf,
    /// Tasks attempted.
    pub attempted: usize,
    /// `task I: why` for each that failed, printable.
    pub failures: Vec<String>,
}

/// Hears a local run (the library prints nothing; `sweep run` shows a progress bar).
pub trait RunObserver {
    /// The tasks to run are known.
    fn starting(&mut self, _starting: &RunStarting) {}
    /// Every quarter second while tasks run.
    fn progress(&mut self, _progress: &RunProgress) {}
    /// Every task has ended; sent before a failure is returned as the run's error.
    fn finished(&mut self, _finished: &RunFinished) {}
}

/// An observer that hears nothing.
impl RunObserver for () {}

/// Runs every task of `run` not done; [`SweepError::TasksFailed`] when any fails.
pub fn run_sweep(run: &LocalRun, observer: &mut dyn RunObserver) -> Result<(), SweepError> {
    let plan = Arc::new(Plan::load(run.dir)?);
    let jobs = match run.jobs {
        Some(j) => at_least_one(j, "option.jobs")?,
        None => available_cores(),
    };
    let workers = (available_cores() / jobs).max(1);
    // Done means the run counts (a task marked done whose run changed since runs again).
    let checked = CheckedCensus::of(run.dir, &plan)?;
    let done_episodes: usize = checked
        .census
        .done
        .iter()
        .map(|&i| plan.tasks[i].episodes)
        .sum();
    let pending = checked.not_done();
    let to_run = pending.len();
    observer.starting(&RunStarting {
        dir: run.dir.to_path_buf(),
        to_run,
        tasks: plan.tasks.len(),
        episodes: plan.episodes(),
        jobs,
        workers,
    });
    let pool = Pool {
        exe: run.exe,
        dir: run.dir,
        plan: plan.clone(),
        jobs,
        workers,
    };
    let results = run_pool(&pool, pending, done_episodes, &mut |progress| {
        observer.progress(&RunProgress {
            pool: progress,
            to_run,
        });
    });
    let failures: Vec<String> = results
        .iter()
        .filter_map(|(i, r)| match r {
            Ok(Outcome::Failed(reason)) => Some(format!("task {i}: {}", printable(reason))),
            Err(e) => Some(format!("task {i}: {}", printable(e))),
            _ => None,
        })
        .collect();
    let failed = failures.len();
    observer.finished(&RunFinished {
        dir: run.dir.to_path_buf(),
        attempted: results.len(),
        failures,
    });
    if failed > 0 {
        return Err(SweepError::TasksFailed {
            failed,
            dir: run.dir.to_path_buf(),
        });
    }
    Ok(())
}

impl Display for RunStarting {
    /// The line before the progress bar.
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "sweep {}: {} of {} tasks to run, {} at a time, {} worker(s) each",
            self.dir.display(),
            self.to_run,
            self.tasks,
            self.jobs,
            self.workers
        )
    }
}

impl Display for RunProgress {
    /// The progress bar's message.
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "tasks: {}/{} done, {} failed",
            self.pool.tasks_done, self.to_run, self.pool.failed
        )
    }
}

impl Display for RunFinished {
    /// The summary, then each failure on its own indented line.
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "sweep {}: {} tasks run, {} failed",
            self.dir.display(),
            self.attempted,
            self.failures.len()
        )?;
        for failure in &self.failures {
            write!(f, "\n  {failure}")?;
        }
        Ok(())
    }
}
