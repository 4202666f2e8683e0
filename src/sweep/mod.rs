//! Headless parallel sweeps: a TOML spec of axes (policies, datasets, settings, latency
//! rules, shards) expanded into a numbered plan of tasks, each exactly one `thorarena eval`
//! invocation on one shard of one cell. Running, scheduling and merging reuse the run,
//! shard and merge machinery of `eval`; this module only says *what* to run and records
//! *what has run*, so any engine that can start `thorarena sweep task DIR --index I` —
//! the local pool, a Slurm job array, a Kubernetes Indexed Job — can execute a sweep.
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
mod k8s;
mod plan;
mod pool;
pub mod process_group;
mod results_csv;
mod scale_fill;
mod slurm;
mod spec;
mod status;
mod task_dir;
mod text;
mod verify;

pub use array::compact_ranges;
pub use attempt::{run_task, Outcome};
pub use cells::{CellFaults, CellLatency, CellResult};
pub use k8s::{k8s_manifest, k8s_manifest_path, write_k8s_manifest, K8sRequest};
pub use plan::{
    diff_plans, Cell, DatasetInfo, EngineAxis, LatencyRule, Plan, PolicyAxis, SequenceInfo, Task,
    PLAN_FILE, PLAN_FORMAT, SESSION_POLICY,
};
pub use pool::{run_pool, Pool, PoolProgress, TaskResult};
pub use results_csv::{results_csv, results_rows, write_results_csv, ResultsRow, RESULTS_CSV_FILE};
pub use scale_fill::{finish_with_shard_runs, write_large_spec, ScaleFillError};
pub use slurm::{
    sbatch_script, shell_quote, slurm_logs_dir, slurm_script_path, write_sbatch_script,
    SbatchRequest,
};
pub use spec::{EngineSpec, LatencySpec, PolicySpec, SweepSpec};
pub use status::{census, task_state, Census, DoneRecord, FailedRecord, TaskState};
pub use task_dir::{write_atomic, TaskDir, TaskLock, TaskLog, DONE_FILE, FAILED_FILE};
pub use text::{
    create_log, log_tail, printable, truncated, LOG_LINE_MAX_BYTES, LOG_TAIL_MAX_BYTES,
};
pub use verify::{check_task_run, CheckedCensus, RunProblem};

use std::path::PathBuf;

/// Errors of sweep specs, plans and task records.
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
    CommandLine(#[from] process_group::CommandLineError),
    /// The plan's robot does not resolve.
    #[error(transparent)]
    Robot(#[from] crate::registry::RegistryError),
    /// A task's run cannot be read or flushed.
    #[error(transparent)]
    Results(#[from] crate::results::ResultsError),
}

impl SweepError {
    fn process(what: &str) -> impl FnOnce(std::io::Error) -> Self {
        let what = what.to_string();
        move |source| Self::Process { what, source }
    }
}
