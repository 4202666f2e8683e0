//! `thorarena sweep …`: plan a sweep from a spec, run its tasks (locally N at a time, or
//! one per process on a Slurm array or a Kubernetes Indexed Job), show its status, and
//! collect the cells into one comparison.
//!
//! A task is one `thorarena eval --request` process of the evaluation its plan holds,
//! into `DIR/tasks/<I>/run`, resuming, so a sweep's episodes are those of separate `eval`
//! runs bit for bit, a killed task resumes, and shards merge with `merge`'s rules. A task
//! is marked done (`done.json`, atomic rename) only after its run holds every planned
//! episode and is flushed to disk; an advisory lock on `tasks/<I>/lock`, held by the task
//! and inherited by its eval process, keeps two copies of one task from running at once.

use super::flags::as_flags;
use std::path::PathBuf;
use thorarena::campaign::sweep::{collect_sweep, SweepCollect};
use thorarena::campaign::sweep::{run_engine_task, EngineTask, SweepStatus};

/// `thorarena sweep …`
#[derive(Debug, clap::Subcommand)]
pub enum SweepCommand {
    /// Validate a sweep spec and write its plan (cells, numbered tasks, exact eval
    /// arguments) into a sweep directory. Planning the same spec again is a no-op; a
    /// changed spec against an existing plan is refused with what changed.
    Plan(PlanArgs),
    /// Run every task that is not done, N at a time, with a progress bar over the sweep.
    Run(SweepRunArgs),
    /// Run exactly one task (the index defaults to SLURM_ARRAY_TASK_ID, else
    /// JOB_COMPLETION_INDEX): skipped when done, resumed when half-done.
    Task(TaskArgs),
    /// Done, failed and not-started tasks, failure reasons, and the not-done set as a
    /// Slurm --array expression.
    Status(StatusArgs),
    /// Write DIR/slurm/sweep.sbatch, an array job over the not-done tasks; --submit hands
    /// it to sbatch.
    Slurm(SlurmArgs),
    /// Write DIR/k8s/job.yaml, a Kubernetes Indexed Job over all tasks.
    K8s(K8sArgs),
    /// Merge each cell's shards and write DIR/results.csv and DIR/report.html.
    Collect(CollectArgs),
}

/// Arguments of `sweep plan`.
#[derive(Debug, clap::Args)]
pub struct PlanArgs {
    /// The sweep spec (TOML; see sweeps/*.toml).
    pub spec: PathBuf,
    /// The sweep directory (created; on every node of a cluster it must be the same
    /// path, on a shared file system).
    #[arg(long)]
    pub out: PathBuf,
}

/// Arguments of `sweep run`.
#[derive(Debug, clap::Args)]
pub struct SweepRunArgs {
    /// The sweep directory.
    pub dir: PathBuf,
    /// Tasks at a time [default: the cores]; each task's eval gets cores / jobs workers.
    #[arg(long)]
    pub jobs: Option<usize>,
}

/// Arguments of `sweep task`.
#[derive(Debug, clap::Args)]
pub struct TaskArgs {
    /// The sweep directory.
    pub dir: PathBuf,
    /// Task index [default: $SLURM_ARRAY_TASK_ID, else $JOB_COMPLETION_INDEX].
    #[arg(long)]
    pub index: Option<usize>,
    /// Worker threads of the evaluation [default: $SLURM_CPUS_PER_TASK, else all cores].
    #[arg(long)]
    pub workers: Option<usize>,
}

/// Arguments of `sweep status`.
#[derive(Debug, clap::Args)]
pub struct StatusArgs {
    /// The sweep directory.
    pub dir: PathBuf,
}

/// Arguments of `sweep slurm`.
#[derive(Debug, clap::Args)]
pub struct SlurmArgs {
    /// The sweep directory.
    pub dir: PathBuf,
    /// Slurm partition.
    #[arg(long)]
    pub partition: Option<String>,
    /// Time limit per task, in Slurm's syntax (e.g. `01:00:00`).
    #[arg(long)]
    pub time: Option<String>,
    /// CPUs per task (the evaluation's worker threads).
    #[arg(long, default_value_t = 1)]
    pub cpus_per_task: usize,
    /// At most this many tasks at once (`%K` of --array).
    #[arg(long)]
    pub max_parallel: Option<usize>,
    /// The thorarena binary the nodes run [default: this one; it must exist at that path
    /// on every node].
    #[arg(long)]
    pub thorarena: Option<PathBuf>,
    /// Submit with sbatch.
    #[arg(long)]
    pub submit: bool,
    /// With --submit: return when the array has finished; non-zero if a task failed.
    #[arg(long, requires = "submit")]
    pub wait: bool,
}

/// Arguments of `sweep k8s`.
#[derive(Debug, clap::Args)]
pub struct K8sArgs {
    /// The sweep directory.
    pub dir: PathBuf,
    /// Container image with `thorarena` on its PATH.
    #[arg(long)]
    pub image: String,
    /// PersistentVolumeClaim holding the sweep directory and its datasets, mounted at the
    /// same absolute paths as here.
    #[arg(long)]
    pub claim: String,
    /// Path inside the claim's volume that is mounted [default: the volume root].
    #[arg(long)]
    pub sub_path: Option<String>,
    /// Pods at once [default: all tasks].
    #[arg(long)]
    pub parallelism: Option<usize>,
    /// CPUs per pod (request and the evaluation's workers).
    #[arg(long, default_value_t = 1)]
    pub cpus_per_task: usize,
}

/// Arguments of `sweep collect`.
#[derive(Debug, clap::Args)]
pub struct CollectArgs {
    /// The sweep directory.
    pub dir: PathBuf,
    /// Collect although some cells are unfinished; their rows say how many episodes
    /// they hold.
    #[arg(long)]
    pub partial: bool,
    /// Put cells simulated by different physics engines into one table and one set of
    /// curves (an `[[engine]]` axis). Refused without it: under force the engines' scores
    /// differ (docs/engines.md, "Force response: rapier against MuJoCo").
    #[arg(long)]
    pub mixed_engines: bool,
}

/// Runs a sweep subcommand.
pub(super) fn run(cmd: &SweepCommand) -> anyhow::Result<()> {
    match cmd {
        SweepCommand::Plan(a) => println!(
            "{}",
            thorarena::campaign::sweep::plan_sweep(&a.spec, &a.out)?
        ),
        SweepCommand::Run(a) => progress_bar::run_all(a)?,
        SweepCommand::Task(a) => {
            let task = EngineTask {
                exe: &std::env::current_exe()?,
                dir: &a.dir,
                index: a.index,
                workers: a.workers,
            };
            println!("{}", run_engine_task(&task)?);
        }
        SweepCommand::Status(a) => {
            let status = SweepStatus::read(&a.dir)?;
            // The task records quote policy output as it is; only the last line names a field.
            print!("{status}");
            println!("{}", as_flags(&status.not_done_line()));
        }
        SweepCommand::Slurm(a) => slurm_k8s::slurm(a)?,
        SweepCommand::K8s(a) => slurm_k8s::k8s(a)?,
        SweepCommand::Collect(a) => {
            let request = SweepCollect {
                dir: &a.dir,
                partial: a.partial,
                mixed_engines: a.mixed_engines,
            };
            eprintln!(
                "{}",
                collect_sweep(&request, &mut |note| eprintln!("{note}"))?
            );
        }
    }
    Ok(())
}

mod progress_bar;
mod slurm_k8s;
