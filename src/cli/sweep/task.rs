//! `sweep task`: one task ([`thorarena::sweep::run_task`]), its index given or taken from
//! the cluster engine's environment (a Slurm array, a Kubernetes Indexed Job).

use super::TaskArgs;
use anyhow::{bail, Context};
use thorarena::sweep::{run_task, Outcome, Plan, TaskDir};

pub(super) fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

pub(super) fn env_usize(name: &str) -> anyhow::Result<Option<usize>> {
    match std::env::var(name) {
        Ok(v) if !v.is_empty() => {
            Ok(Some(v.trim().parse().with_context(|| {
                format!("${name} = `{v}` is not a task index")
            })?))
        }
        _ => Ok(None),
    }
}

pub(super) fn task(args: &TaskArgs) -> anyhow::Result<()> {
    let index = match args.index {
        Some(i) => i,
        None => env_usize("SLURM_ARRAY_TASK_ID")?
            .or(env_usize("JOB_COMPLETION_INDEX")?)
            .context(
                "no task index: give --index I, or run under a Slurm array \
                 (SLURM_ARRAY_TASK_ID) or a Kubernetes Indexed Job (JOB_COMPLETION_INDEX)",
            )?,
    };
    let plan = Plan::load(&args.dir)?;
    let workers = match args.workers {
        Some(0) => bail!("--workers must be at least 1"),
        Some(w) => w,
        None => env_usize("SLURM_CPUS_PER_TASK")?.unwrap_or_else(cores),
    };
    let exe = std::env::current_exe()?;
    match run_task(&exe, &args.dir, &plan, index, workers)? {
        Outcome::Done => {
            println!("task {index}: done");
            Ok(())
        }
        Outcome::AlreadyDone => {
            println!("task {index}: already done, skipped");
            Ok(())
        }
        Outcome::Failed(reason) => bail!(
            "task {index} failed: {reason} (details: {})",
            TaskDir::of(&args.dir, index).failed_file().display()
        ),
    }
}
