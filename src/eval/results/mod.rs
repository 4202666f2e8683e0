//! The run directory, in one place: what `eval`, `merge` and a sweep write and what
//! `eval --resume`, `merge`, `report` and `view` read back.
//!
//! ```text
//! <run>/run.json        RunHeader: what was measured (policy, profile, dataset and its
//!                       planned sequences, settings, rules); runs are merged, resumed
//!                       and compared only if these agree
//! <run>/episodes.jsonl  EpisodeRecord per line, streamed as episodes finish
//! <run>/summary.json    Summary: the scores computed from the records, and coverage
//! <run>/tables.md       the paper's tables for people
//! <run>/episodes.csv    EpisodeRow per episode: survival, mean and RMS keypoint error,
//!                       score, termination (for spreadsheets)
//! <run>/traces/         rollout traces (`eval --trace`)
//! ```
//!
//! Every record is checked against its header when read ([`EpisodeLog::read`]): one
//! malformed line, a duplicated episode or a series that cannot have been recorded is a
//! [`ResultsError`] naming the file and line, never a panic further on or a silently wrong
//! score. A run that stopped early is read as what it is: [`Coverage`] says how many
//! episodes of each (setting, task) cell are present and how many the plan expects.
//!
//! Every file carries [`RESULTS_VERSION`]; a reader refuses files of another version
//! rather than guess at their meaning.

mod coverage;
pub mod crosscheck;
mod episode_table;
mod episodes;
mod header;
mod identity;
mod merge;
mod output_guard;
mod record_check;
mod run_dir;
mod run_target;
mod summary;

pub use coverage::{CellCoverage, Coverage};
pub use episode_table::{episode_rows, write_episodes_csv, EpisodeRow, EPISODES_CSV_FILE};
pub use episodes::{write_record, EpisodeLog, MAX_EPISODE_LOG_BYTES};
pub use header::{read_header, write_header, PlannedSequence, RunHeader};
pub use identity::{identity_differences, network_label, PolicyIdentity};
pub use merge::{read_shards, MergeError, Shards};
pub use output_guard::{
    check_dataset_dir, check_dir, check_file, check_files_dir, check_run_dir, OutputRefused,
};
pub use run_dir::{
    RecordAppender, RunDir, RunLock, Started, CROSSCHECK_SERIES_FILE, LOCK_FILE, MAX_TRACE_BYTES,
    RUN_FILES, TRACES_DIR,
};
pub use run_target::{free_numbered_dir, RunTarget, RunTargetError};
pub use summary::{
    fats_intervals, read_summary, sort_records, summarize, write_results, PolicyIoReport,
    SettingResults, SettingSummary, Summary,
};

use std::path::PathBuf;

/// Version of the run directory's files. Version 2 added it, the planned sequences of the
/// header and the coverage of the summary; earlier runs carry no version (read as 0).
pub const RESULTS_VERSION: u32 = 2;

/// `run.json`.
pub const HEADER_FILE: &str = "run.json";
/// `episodes.jsonl`.
pub const EPISODES_FILE: &str = "episodes.jsonl";
/// `summary.json`.
pub const SUMMARY_FILE: &str = "summary.json";
/// `tables.md`.
pub const TABLES_FILE: &str = "tables.md";

/// Why a run directory could not be read or written.
#[derive(Debug, thiserror::Error)]
pub enum ResultsError {
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// A file (or one line of `episodes.jsonl`) is not the JSON it should be.
    #[error("{path}{}: {source}", line.map(|l| format!(" line {l}")).unwrap_or_default())]
    Json {
        /// The file.
        path: PathBuf,
        /// 1-based line, for `episodes.jsonl`.
        line: Option<usize>,
        /// The cause.
        source: serde_json::Error,
    },
    /// A file written by another version of ThorArena's results format.
    #[error("{path} is results version {found}; this ThorArena reads version {RESULTS_VERSION} (run the evaluation again with this version, e.g. with `option.overwrite`)")]
    Version {
        /// The file.
        path: PathBuf,
        /// Its version (0: written before versions existed).
        found: u64,
    },
    /// Another process is writing this run directory (it holds the directory's lock).
    #[error("{} is being written by another thorarena process{}: two writers would interleave their records and lose the run; wait for it, or choose another `option.out`", .path.display(), .holder.map(|p| format!(" (pid {p})")).unwrap_or_default())]
    Busy {
        /// The run directory.
        path: PathBuf,
        /// The pid the holder wrote into the lock file, when readable.
        holder: Option<u32>,
    },
    /// A directory a run cannot be written to.
    #[error("{path} is not writable: {source}")]
    NotWritable {
        /// The directory.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// A run resumed or merged with one of another configuration.
    #[error("{path} was started with another configuration (it differs in: {}; the run's first)", differences.join(", "))]
    OtherConfiguration {
        /// The previous run.
        path: PathBuf,
        /// What differs: header fields by name, the policy's identity with both hashes
        /// ([`RunHeader::differences`]).
        differences: Vec<String>,
    },
    /// Two engines' runs of a crosscheck that do not hold the same episodes.
    #[error("{count} episodes ran on one engine only (e.g. {example})")]
    Unpaired {
        /// Episodes in one run only.
        count: usize,
        /// One of them.
        example: crate::eval::EpisodeKey,
    },
    /// Shards that cannot be merged into one run.
    #[error(transparent)]
    Merge(#[from] MergeError),
    /// A record that cannot have been written by the run its header describes.
    #[error("{path} line {line}: {reason}")]
    BadRecord {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// What is wrong, naming the episode.
        reason: String,
    },
}

impl ResultsError {
    fn io(path: impl Into<PathBuf>) -> impl FnOnce(std::io::Error) -> Self {
        let path = path.into();
        move |source| Self::Io { path, source }
    }
}
