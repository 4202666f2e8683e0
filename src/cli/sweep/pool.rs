//! `sweep run`: the local pool ([`thorarena::sweep::run_pool`]), N tasks at a time, with
//! a progress bar over the sweep.

use super::task::cores;
use super::RunArgs;
use anyhow::bail;
use std::sync::Arc;
use thorarena::sweep::{printable, run_pool, CheckedCensus, Outcome, Plan, Pool};

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
    let pending = checked.not_done();
    let to_run = pending.len();
    eprintln!(
        "sweep {}: {} of {} tasks to run, {jobs} at a time, {workers} worker(s) each",
        args.dir.display(),
        to_run,
        plan.tasks.len()
    );
    let bar = indicatif::ProgressBar::new(plan.episodes() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{bar:40} {pos}/{len} episodes  {elapsed} elapsed, ~{eta} left  {msg}",
        )
        .expect("valid template"),
    );
    let exe = std::env::current_exe()?;
    let pool = Pool {
        exe: &exe,
        dir: &args.dir,
        plan: plan.clone(),
        jobs,
        workers,
    };
    let results = run_pool(&pool, pending, done_episodes, &mut |p| {
        bar.set_position(p.episodes as u64);
        bar.set_message(format!(
            "tasks: {}/{to_run} done, {} failed",
            p.tasks_done, p.failed
        ));
    });
    bar.finish_and_clear();
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
