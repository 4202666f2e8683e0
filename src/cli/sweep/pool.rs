//! `sweep run`: the local pool, N tasks at a time, with progress over the sweep.

use super::task::{cores, run_task, Outcome};
use super::verify::CheckedCensus;
use super::RunArgs;
use anyhow::bail;
use std::collections::VecDeque;
use std::path::Path;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use thorarena::results::RunDir;
use thorarena::sweep::{printable, Plan, TaskDir};
pub(super) fn run_all(args: &RunArgs) -> anyhow::Result<()> {
    let plan = Arc::new(Plan::load(&args.dir)?);
    let jobs = match args.jobs {
        Some(0) => bail!("--jobs must be at least 1"),
        Some(j) => j,
        None => cores(),
    };
    let workers = (cores() / jobs).max(1);
    // Done means the run counts (a task marked done whose run changed since runs again).
    let checked = CheckedCensus::of(&args.dir, &plan)?;
    let done_episodes: usize = checked
        .census
        .done
        .iter()
        .map(|&i| plan.tasks[i].episodes)
        .sum();
    let pending: VecDeque<usize> = checked.not_done().into();
    let to_run = pending.len();
    eprintln!(
        "sweep {}: {} of {} tasks to run, {jobs} at a time, {workers} worker(s) each",
        args.dir.display(),
        to_run,
        plan.tasks.len()
    );
    let queue = Arc::new(Mutex::new(pending));
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
            let dir = args.dir.clone();
            std::thread::spawn(move || loop {
                let Some(i) = queue.lock().expect("queue").pop_front() else {
                    return;
                };
                running.lock().expect("running").push(i);
                let r = run_task(&dir, &plan, i, workers).map_err(|e| format!("{e:#}"));
                running.lock().expect("running").retain(|&x| x != i);
                results.lock().expect("results").push((i, r));
            })
        })
        .collect();

    let bar = indicatif::ProgressBar::new(plan.episodes() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{bar:40} {pos}/{len} episodes  {elapsed} elapsed, ~{eta} left  {msg}",
        )
        .expect("valid template"),
    );
    loop {
        let finished = handles.iter().all(|h| h.is_finished());
        let (mut episodes, mut failed, mut tasks_done) = (done_episodes, 0usize, 0usize);
        for (i, r) in results.lock().expect("results").iter() {
            match r {
                Ok(Outcome::Done | Outcome::AlreadyDone) => {
                    episodes += plan.tasks[*i].episodes;
                    tasks_done += 1;
                }
                _ => failed += 1,
            }
        }
        for &i in running.lock().expect("running").iter() {
            episodes +=
                count_lines(&RunDir::new(TaskDir::of(&args.dir, i).run_dir()).episodes_file());
        }
        bar.set_position(episodes as u64);
        bar.set_message(format!(
            "tasks: {tasks_done}/{to_run} done, {failed} failed"
        ));
        if finished {
            break;
        }
        std::thread::sleep(Duration::from_millis(250));
    }
    bar.finish_and_clear();
    for h in handles {
        h.join()
            .map_err(|_| anyhow::anyhow!("a task thread panicked"))?;
    }
    let results = results.lock().expect("results");
    let failures: Vec<String> = results
        .iter()
        .filter_map(|(i, r)| match r {
            Ok(Outcome::Failed(reason)) => Some(format!("task {i}: {}", printable(reason))),
            Err(e) => Some(format!("task {i}: {}", printable(e))),
            _ => None,
        })
        .collect();
    eprintln!(
        "sweep {}: {} tasks run, {} failed",
        args.dir.display(),
        results.len(),
        failures.len()
    );
    if !failures.is_empty() {
        for f in &failures {
            eprintln!("  {f}");
        }
        bail!(
            "{} task(s) failed; `thorarena sweep status {}` shows why, `sweep run` again retries them",
            failures.len(),
            args.dir.display()
        );
    }
    Ok(())
}

/// A task index and how its attempt ended (an error is the sweep's, not the task's).
pub(super) type TaskResult = (usize, Result<Outcome, String>);

pub(super) fn count_lines(path: &Path) -> usize {
    std::fs::read(path)
        .map(|b| b.iter().filter(|&&c| c == b'\n').count())
        .unwrap_or(0)
}
