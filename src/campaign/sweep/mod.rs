//! Headless parallel sweeps: a TOML spec of axes (policies, datasets, settings, latency
//! rules, shards) expanded into a numbered plan of tasks, each exactly one `thorarena eval`
//! invocation on one shard of one cell. Running, scheduling and merging reuse the run,
//! shard and merge machinery of `eval`; this module only says *what* to run and records
//! *what has run*, so any engine that can start `thorarena sweep task DIR --index I` —
//! the local pool, a Slurm job array, a Kubernetes Indexed Job — can execute a sweep.
//!
//! Each `thorarena sweep` command is one call here — [`plan_sweep`], [`run_sweep`],
//! [`run_engine_task`], [`SweepStatus`], [`slurm_array`], [`write_k8s_job`],
//! [`collect_sweep`] (whose last product is a report with the curves of `figures.rs`); the command
//! line only parses, calls and prints what they return or tell.
//!
//! Layout of a sweep directory:
//!
//! ```text
//! DIR/plan.json            the expanded plan (format version, cells, tasks, eval args)
//! DIR/tasks/<I>/run/       task I's eval run directory (run.json, episodes.jsonl, …)
//! DIR/tasks/<I>/done.json  written last, atomically, once the run is complete and flushed
//! DIR/tasks/<I>/failed.json  why the last attempt failed (removed when it is retried)
//! DIR/tasks/<I>/eval.log, policy.log   output of the eval and of the policy command
//! DIR/cells/<C>/           a cell's shards merged by `sweep collect`
//! DIR/results.csv, DIR/report.html   `sweep collect`
//! DIR/slurm/, DIR/k8s/     generated job scripts and manifests
//! ```

mod array;
mod attempt;
mod axes;
mod cells;
mod check;
mod cluster;
mod collect;
mod counted_tasks;
mod engine_task;
mod figures;
mod k8s;
mod local_run;
mod plan;
mod planned_datasets;
mod planning;
mod pool;
mod results_csv;
mod scale_fill;
mod slurm;
mod spec;
mod status;
mod status_report;
mod task_dir;
mod verify;

pub use crate::files::log_text::{
    create_log, log_tail, printable, truncated, LOG_LINE_MAX_BYTES, LOG_TAIL_MAX_BYTES,
};
pub use array::compact_ranges;
pub use attempt::{run_task, Outcome};
pub use cells::{CellFaults, CellLatency, CellResult};
pub use cluster::{slurm_array, SlurmArray};
pub use collect::{collect_sweep, CollectError, CollectedSweep, SweepCollect};
pub use counted_tasks::CountedTasks;
use engine_task::available_cores;
pub use engine_task::{run_engine_task, EngineTask, TaskEnded};
pub use k8s::{k8s_manifest_path, write_k8s_job, K8sRequest, WrittenK8sJob};
pub use local_run::{run_sweep, LocalRun, RunFinished, RunObserver, RunProgress, RunStarting};
pub use plan::{
    diff_plans, Cell, DatasetInfo, EngineAxis, LatencyRule, Plan, PolicyAxis, SequenceInfo, Task,
    PLAN_FILE, PLAN_FORMAT,
};
pub use planned_datasets::{changed_datasets, planned_sequences};
pub use planning::{check_cells_load, plan_sweep, PlannedSweep};
pub use pool::{run_pool, Pool, PoolProgress, TaskResult};
pub use results_csv::{results_csv, results_rows, write_results_csv, ResultsRow, RESULTS_CSV_FILE};
pub use scale_fill::{finish_with_shard_runs, write_large_spec, ScaleFillError};
pub use slurm::{
    sbatch_script, shell_quote, slurm_logs_dir, slurm_script_path, write_sbatch_script,
    SbatchRequest,
};
pub use spec::{EngineSpec, LatencySpec, PolicySpec, SpecSetting, SweepSpec};
pub use status::{census, task_state, Census, DoneRecord, FailedRecord, TaskState};
pub use status_report::SweepStatus;
pub use task_dir::{write_atomic, TaskDir, TaskLock, TaskLog, DONE_FILE, FAILED_FILE};
pub use verify::{check_task_run, CheckedCensus, RunProblem};

use crate::sim::motion::DataError;
use std::path::PathBuf;

/// Errors of sweep specs, plans, task records, and of the commands over them.
#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// The spec is not valid TOML or has unknown keys or wrong types.
    #[error("{path}: {message}")]
    Toml {
        /// The spec file.
        path: PathBuf,
        /// The parser's message (names the key).
        message: String,
    },
    /// The spec parses but says something impossible.
    #[error("{path}: {message}")]
    Invalid {
        /// The spec file.
        path: PathBuf,
        /// What is wrong, naming the key.
        message: String,
    },
    /// A value cannot be written into a job script as the literal it is.
    #[error("{what} `{}`: {why}", printable(.value))]
    Unquotable {
        /// Which value (`option.partition`, the sweep directory, …).
        what: String,
        /// The value.
        value: String,
        /// Why it cannot be written.
        why: String,
    },
    /// A plan or task record is unreadable or from another format version.
    #[error("{path}: {message}")]
    BadRecord {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A task index beyond the plan.
    #[error("task {index}: the plan has tasks 0..{tasks}")]
    NoTask {
        /// The index asked for.
        index: usize,
        /// Tasks in the plan.
        tasks: usize,
    },
    /// A task's process could not be started or waited for.
    #[error("{what}: {source}")]
    Process {
        /// What was being done.
        what: String,
        /// The cause.
        source: std::io::Error,
    },
    /// A policy command cannot be made into a shell line.
    #[error(transparent)]
    CommandLine(#[from] crate::policy::launched::CommandLineError),
    /// The plan's robot does not resolve.
    #[error(transparent)]
    Robot(#[from] crate::policy::registry::RegistryError),
    /// A task's run cannot be read or flushed.
    #[error(transparent)]
    Results(#[from] crate::eval::results::ResultsError),
    /// A planned dataset cannot be loaded.
    #[error(transparent)]
    Data(#[from] DataError),
    /// An option that counts something is 0.
    #[error("`{option}` must be at least 1")]
    Zero {
        /// The option, as the library names it (`option.jobs`).
        option: &'static str,
    },
    /// A path given does not exist (or cannot be made absolute).
    #[error("{} does not exist: {source}", .path.display())]
    Missing {
        /// The path as given.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },

    // Planning (`sweep plan`): the spec's own names are quoted, they are its keys.
    /// The spec file cannot be found.
    #[error("reading the sweep spec {}: {source}", .path.display())]
    SpecMissing {
        /// The spec as given.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// The spec's robot does not resolve.
    #[error("`robot` of the sweep spec: {0}")]
    SpecRobot(#[source] crate::policy::registry::RegistryError),
    /// A dataset of the spec does not exist.
    #[error("`datasets`: {name} (relative to {}) does not exist: {source}", .base.display())]
    DatasetMissing {
        /// The dataset as the spec writes it.
        name: String,
        /// The spec's directory.
        base: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// A dataset of the spec cannot be read.
    #[error("`datasets`: {name}: {source}")]
    DatasetUnreadable {
        /// The dataset as the spec writes it.
        name: String,
        /// The cause.
        source: DataError,
    },
    /// A dataset of the spec holds no sequence.
    #[error("`datasets`: {name} holds no sequence")]
    DatasetEmpty {
        /// The dataset as the spec writes it.
        name: String,
    },
    /// A cell's evaluation is one `eval` refuses.
    #[error("cell {cell} (policy `{policy}`): {source}")]
    CellRequest {
        /// The cell.
        cell: usize,
        /// Its policy's name.
        policy: String,
        /// Why `eval` refuses it (boxed: it is large, and rare).
        source: Box<crate::eval::SpecError>,
    },
    /// A policy's network does not load.
    #[error("policy `{policy}`: {source}")]
    PolicyLoad {
        /// The policy's name.
        policy: String,
        /// Why (boxed: it is large, and rare).
        source: Box<crate::policy::registry::RegistryError>,
    },

    // Running and collecting.
    /// A dataset differs from the one planned: its runs would be scored against other
    /// references.
    #[error(
        "dataset {} changed since the sweep was planned (content hash {planned} then, {now} now): its runs would be scored against other references; restore it, or plan a new sweep",
        .dataset.display()
    )]
    DatasetChanged {
        /// The dataset directory.
        dataset: PathBuf,
        /// The start of its hash as planned.
        planned: String,
        /// The start of its hash now.
        now: String,
    },
    /// A planned dataset cannot be opened.
    #[error("dataset of cell {cell}: {source}")]
    CellDataset {
        /// The first cell planning it.
        cell: usize,
        /// Why.
        source: DataError,
    },
    /// No task index was given and the environment names none.
    #[error("no task index: give `option.index` I, or run under a Slurm array (SLURM_ARRAY_TASK_ID) or a Kubernetes Indexed Job (JOB_COMPLETION_INDEX)")]
    NoTaskIndex,
    /// A cluster engine's variable holds no number.
    #[error("${var} = `{value}` is not a task index: {source}")]
    BadEnvIndex {
        /// The variable.
        var: &'static str,
        /// Its value.
        value: String,
        /// The parser's complaint.
        source: std::num::ParseIntError,
    },
    /// A task's attempt failed; its `failed.json` says why.
    #[error("task {index} failed: {reason} (details: {})", .details.display())]
    TaskFailed {
        /// The task.
        index: usize,
        /// Why, in one line.
        reason: String,
        /// Its `failed.json`.
        details: PathBuf,
    },
    /// Tasks of `sweep run` failed.
    #[error("{failed} task(s) failed; `thorarena sweep status {}` shows why, `sweep run` again retries them", .dir.display())]
    TasksFailed {
        /// How many.
        failed: usize,
        /// The sweep directory.
        dir: PathBuf,
    },
    /// A task marked done holds another configuration's run.
    #[error("{why}; a run that is not the cell's is never scored under its label: remove {} and run the task again", .run_dir.display())]
    NotThisTask {
        /// What differs.
        why: String,
        /// The task's run directory.
        run_dir: PathBuf,
    },
    /// `collect` of a sweep with unfinished cells, not asked to collect partially.
    #[error(
        "{unfinished} of {cells} cells are unfinished (cells {unfinished_cells}; tasks not done: {not_done}{not_counted}): run them (`sweep run` resumes them), or collect with `option.partial`"
    )]
    Unfinished {
        /// Cells unfinished.
        unfinished: usize,
        /// Cells planned.
        cells: usize,
        /// The unfinished cells as ranges.
        unfinished_cells: String,
        /// The tasks not done as ranges.
        not_done: String,
        /// `; task I: why` for each task marked done whose run does not count.
        not_counted: String,
    },

    // Handing the sweep to Slurm.
    /// `sbatch` could not be started.
    #[error("running sbatch (is Slurm's client installed and configured?): {0}")]
    SbatchNotRun(#[source] std::io::Error),
    /// `sbatch` exited with an error.
    #[error("{command}: {status}; {failed} task(s) failed, {not_done} not done (`thorarena sweep status {}`)", .dir.display())]
    SbatchFailed {
        /// The command, without the script.
        command: String,
        /// How it exited.
        status: std::process::ExitStatus,
        /// Tasks failed then.
        failed: usize,
        /// Tasks not done then.
        not_done: usize,
        /// The sweep directory.
        dir: PathBuf,
    },
    /// The array has finished, and tasks are not done.
    #[error("the array finished with {not_done} task(s) not done: {ranges}")]
    ArrayNotDone {
        /// How many.
        not_done: usize,
        /// Which, as ranges.
        ranges: String,
    },
}

/// `n`, refused as [`SweepError::Zero`] naming `option` when it is 0.
fn at_least_one(n: usize, option: &'static str) -> Result<usize, SweepError> {
    if n == 0 {
        return Err(SweepError::Zero { option });
    }
    Ok(n)
}

impl SweepError {
    fn process(what: &str) -> impl FnOnce(std::io::Error) -> Self {
        let what = what.to_string();
        move |source| Self::Process { what, source }
    }
}
