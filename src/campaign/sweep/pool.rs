//! The local pool of `sweep run`: tasks `jobs` at a time on threads, each an
//! [`run_task`] attempt, with the sweep's progress told to the caller as it goes.

use super::attempt::{run_task, Outcome};
use super::{Plan, TaskDir};
use crate::eval::results::RunDir;
use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// A task index and how its attempt ended (an error is the sweep's, not the task's).
pub type TaskResult = (usize, Result<Outcome, String>);

/// Where a pool stands, told every quarter second.
#[derive(Debug, Clone, Copy, Default)]
pub struct PoolProgress {
    /// Episodes done: of tasks done before, of tasks finished now, and written so far by
    /// the running ones.
    pub episodes: usize,
    /// Tasks of this pool done.
    pub tasks_done: usize,
    /// Tasks of this pool failed.
    pub failed: usize,
}

/// A local pool: `jobs` tasks at a time, each with `workers` threads, through `exe`'s
/// `eval`.
#[derive(Debug, Clone)]
pub struct Pool<'a> {
    /// The `thorarena` binary.
    pub exe: &'a Path,
    /// The sweep directory.
    pub dir: &'a Path,
    /// Its plan.
    pub plan: Arc<Plan>,
    /// Tasks at a time.
    pub jobs: usize,
    /// Worker threads per task.
    pub workers: usize,
}

/// Runs tasks `pending` of the pool's plan; `done_episodes` are those of tasks done
/// before. Returns every attempt's result, in the order they finished.
pub fn run_pool(
    pool: &Pool,
    pending: Vec<usize>,
    done_episodes: usize,
    tick: &mut dyn FnMut(PoolProgress),
) -> Vec<TaskResult> {
    let Pool {
        exe,
        dir,
        plan,
        jobs,
        workers,
    } = pool.clone();
    let to_run = pending.len();
    let queue = Arc::new(Mutex::new(VecDeque::from(pending)));
    let running: Arc<Mutex<Vec<usize>>> = Arc::new(Mutex::new(Vec::new()));
    let results: Arc<Mutex<Vec<TaskResult>>> = Arc::new(Mutex::new(Vec::new()));
    let handles: Vec<_> = (0..jobs.min(to_run.max(1)))
        .map(|_| {
            let (queue, running, results, plan) = (
                queue.clone(),
                running.clone(),
                results.clone(),
                plan.clone(),
            );
            let (exe, dir): (PathBuf, PathBuf) = (exe.into(), dir.into());
            std::thread::spawn(move || loop {
                let Some(i) = queue.lock().expect("queue").pop_front() else {
                    return;
                };
                running.lock().expect("running").push(i);
                let r = run_task(&exe, &dir, &plan, i, workers).map_err(|e| e.to_string());
                running.lock().expect("running").retain(|&x| x != i);
                results.lock().expect("results").push((i, r));
            })
        })
        .collect();
    loop {
        let finished = handles.iter().all(|h| h.is_finished());
        let mut progress = PoolProgress {
            episodes: done_episodes,
            ..PoolProgress::default()
        };
        for (i, r) in results.lock().expect("results").iter() {
            match r {
                Ok(Outcome::Done | Outcome::AlreadyDone) => {
                    progress.episodes += plan.tasks[*i].episodes;
                    progress.tasks_done += 1;
                }
                _ => progress.failed += 1,
            }
        }
        for &i in running.lock().expect("running").iter() {
            progress.episodes +=
                count_lines(&RunDir::new(TaskDir::of(dir, i).run_dir()).episodes_file());
        }
        tick(progress);
        if finished {
            break;
        }
        std::thread::sleep(Duration::from_millis(250));
    }
    for h in handles {
        // A task thread that panicked has pushed no result: its task is reported below.
        let _ = h.join();
    }
    let mut results = std::mem::take(&mut *results.lock().expect("results"));
    let reported: Vec<usize> = results.iter().map(|(i, _)| *i).collect();
    for i in queue.lock().expect("queue").drain(..) {
        results.push((i, Err("not run: a task thread ended".into())));
    }
    for i in running.lock().expect("running").drain(..) {
        if !reported.contains(&i) {
            results.push((i, Err("its task thread panicked".into())));
        }
    }
    results
}

/// Lines of the file at `path` (0 when it cannot be read): episodes a run has written.
fn count_lines(path: &Path) -> usize {
    use std::io::BufRead;
    let Ok(file) = crate::files::bounded_read::open(
        path,
        "episode log",
        crate::eval::results::MAX_EPISODE_LOG_BYTES,
    ) else {
        return 0;
    };
    let mut reader = std::io::BufReader::new(file);
    let mut lines = 0;
    while let Ok(chunk) = reader.fill_buf() {
        if chunk.is_empty() {
            break;
        }
        lines += chunk.iter().filter(|&&c| c == b'\n').count();
        let read = chunk.len();
        reader.consume(read);
    }
    lines
}
