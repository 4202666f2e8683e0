//! A sweep handed to a cluster engine in one call: a Slurm array over the tasks not done
//! (its script written, and on request submitted, waited for, and the sweep's census
//! checked after), or a Kubernetes Indexed Job over every task. What a user gives is
//! checked before anything is written; what goes on is told line by line, since
//! `sbatch --wait` can block for hours.

use super::{at_least_one, CheckedCensus, Plan, SbatchRequest, SweepError};
use super::{compact_ranges, sbatch_script, write_sbatch_script};
use std::path::{Path, PathBuf};
use std::process::Command;

/// A Slurm array as asked for.
#[derive(Debug, Clone)]
pub struct SlurmArray<'a> {
    /// The sweep directory.
    pub dir: &'a Path,
    /// The `thorarena` the nodes run [default: `this_binary`]; it must exist here.
    pub thorarena: Option<&'a Path>,
    /// The running `thorarena` binary.
    pub this_binary: &'a Path,
    /// CPUs per task (the evaluation's worker threads).
    pub cpus_per_task: usize,
    /// At most this many tasks at once (`%K` of the array).
    pub max_parallel: Option<usize>,
    /// The Slurm partition.
    pub partition: Option<&'a str>,
    /// The time limit per task, in Slurm's syntax.
    pub time: Option<&'a str>,
    /// Hand the script to sbatch.
    pub submit: bool,
    /// Submitted: return once the array has finished, an error if a task is not done.
    pub wait: bool,
}

/// Writes the Slurm array of `array`'s sweep over the tasks not done, and submits it when
/// asked; each line worth telling goes to `say` as it happens. Nothing is written when
/// every task is done.
pub fn slurm_array(array: &SlurmArray, say: &mut dyn FnMut(&str)) -> Result<(), SweepError> {
    let plan = Plan::load(array.dir)?;
    let dir = absolute(array.dir)?;
    at_least_one(array.cpus_per_task, "option.cpus_per_task")?;
    let not_done = CheckedCensus::of(&dir, &plan)?.not_done();
    if not_done.is_empty() {
        say(&format!(
            "every task of {} is done: nothing to submit",
            dir.display()
        ));
        return Ok(());
    }
    let exe = match array.thorarena {
        Some(p) => absolute(p)?,
        None => array.this_binary.to_path_buf(),
    };
    let mut tasks = compact_ranges(&not_done);
    if let Some(k) = array.max_parallel {
        at_least_one(k, "option.max_parallel")?;
        tasks += &format!("%{k}");
    }
    // Checked before anything is written: a value sbatch cannot read literally is refused.
    let script = sbatch_script(&SbatchRequest {
        dir: &dir,
        thorarena: &exe,
        array: &tasks,
        cpus_per_task: array.cpus_per_task,
        partition: array.partition,
        time: array.time,
    })?;
    let script = write_sbatch_script(&dir, &script)?;
    say(&format!(
        "wrote {} ({} tasks: `option.array`={tasks})",
        script.display(),
        not_done.len()
    ));
    if !array.submit {
        say(&format!("submit with: sbatch {}", script.display()));
        return Ok(());
    }
    let mut sbatch = Command::new("sbatch");
    if array.wait {
        sbatch.arg("--wait");
    }
    let options: Vec<String> = sbatch
        .get_args()
        .map(|a| a.to_string_lossy().into_owned())
        .collect();
    let status = sbatch
        .arg(&script)
        .status()
        .map_err(SweepError::SbatchNotRun)?;
    if !status.success() {
        let c = CheckedCensus::of(&dir, &plan)?;
        return Err(SweepError::SbatchFailed {
            command: format!("sbatch {}", options.join(" ")),
            status,
            failed: c.census.failed.len(),
            not_done: c.not_done().len(),
            dir,
        });
    }
    if array.wait {
        let not_done = CheckedCensus::of(&dir, &plan)?.not_done();
        if !not_done.is_empty() {
            return Err(SweepError::ArrayNotDone {
                not_done: not_done.len(),
                ranges: compact_ranges(&not_done),
            });
        }
        say(&format!("all {} tasks done", plan.tasks.len()));
    }
    Ok(())
}

/// `path` absolute, as the nodes and pods name it; it must exist.
pub(super) fn absolute(path: &Path) -> Result<PathBuf, SweepError> {
    std::fs::canonicalize(path).map_err(|source| SweepError::Missing {
        path: path.to_path_buf(),
        source,
    })
}
