//! A sweep of thousands of tasks without simulating them, for timing planning, `sweep
//! status` and `collect` at scale (`thorarena bench sweep`): a spec over many replay
//! coefficients, and every task of its plan finished with a copy of a real run of its
//! shard — header and records renamed to the task's setting and policy — so `status` and
//! `collect` read and check as much as real runs of that size.

use super::{DoneRecord, Plan, SweepError, TaskDir};
use crate::eval::results::{ResultsError, RunDir, RunHeader};
use crate::eval::EpisodeRecord;
use std::path::{Path, PathBuf};

/// The largest `summary.json` or `tables.md` copied from a shard, bytes (a few KiB a cell).
const MAX_RUN_FILE_BYTES: u64 = 64 * crate::files::bounded_read::MIB;

/// Why the large sweep could not be made.
#[derive(Debug, thiserror::Error)]
pub enum ScaleFillError {
    /// A file could not be written or copied.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// A run could not be read or written.
    #[error(transparent)]
    Results(#[from] ResultsError),
    /// A task directory could not be written.
    #[error(transparent)]
    Sweep(#[from] SweepError),
}

/// Writes `dir/large.toml`: the balance and hold baselines on `sample` over enough replay
/// coefficients that, with `shards` shards, the plan has about `tasks` tasks.
pub fn write_large_spec(
    dir: &Path,
    sample: &Path,
    tasks: usize,
    shards: usize,
) -> Result<PathBuf, ScaleFillError> {
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| ScaleFillError::Io { path, source }
    };
    let settings = (tasks / (2 * shards.max(1))).max(1);
    let coefficients: Vec<String> = (0..settings)
        .map(|i| format!("\"{}\"", 0.001 * i as f64))
        .collect();
    std::fs::create_dir_all(dir).map_err(io(dir))?;
    let spec = dir.join("large.toml");
    let text = format!(
        "datasets = [{:?}]\nsettings = [{}]\nshards = {shards}\n[[policy]]\npolicy = \"balance\"\n[[policy]]\npolicy = \"hold\"\n",
        sample.display().to_string(),
        coefficients.join(", "),
    );
    crate::files::atomic_file::write(&spec, text).map_err(io(&spec))?;
    Ok(spec)
}

/// Finishes every task of the plan in `dir` with the run of its shard in `shards` (one
/// real run per shard), renamed to the task's setting and policy; returns the episodes
/// written.
pub fn finish_with_shard_runs(dir: &Path, shards: &[PathBuf]) -> Result<usize, ScaleFillError> {
    let plan = Plan::load(dir)?;
    let sources: Vec<(RunHeader, Vec<EpisodeRecord>)> = shards
        .iter()
        .map(|run| -> Result<_, ScaleFillError> {
            let run = RunDir::new(run);
            let header = run.read_header()?;
            let records = run.read_log(&header)?.records;
            Ok((header, records))
        })
        .collect::<Result<_, _>>()?;
    let mut episodes = 0;
    for task in &plan.tasks {
        let cell = &plan.cells[task.cell];
        let (source, records) = &sources[task.shard.0];
        let setting = cell.setting.clone();
        let mut header = source.clone();
        header.policy = cell.policy.policy.family().name.to_string();
        header.settings = vec![setting.clone()];
        let tdir = TaskDir::of(dir, task.index);
        let run = RunDir::new(tdir.run_dir());
        run.start(&header, false, &|_| false)?;
        let mut appender = run.appender()?;
        for r in records {
            appender.append(&EpisodeRecord {
                setting: setting.name.clone(),
                coefficient: setting.coefficient,
                policy: header.policy.clone(),
                ..r.clone()
            })?;
        }
        appender.flush()?;
        tdir.write_done(&DoneRecord {
            task: task.index,
            episodes: records.len(),
            wall_s: 0.0,
        })?;
        let source = RunDir::new(&shards[task.shard.0]);
        for (from, to) in [
            (source.summary_file(), run.summary_file()),
            (source.tables_file(), run.tables_file()),
        ] {
            crate::files::bounded_read::read(&from, "run file", MAX_RUN_FILE_BYTES)
                .and_then(|bytes| crate::files::atomic_file::write(&to, bytes))
                .map_err(|e| ScaleFillError::Io {
                    path: to,
                    source: e,
                })?;
        }
        episodes += records.len();
    }
    Ok(episodes)
}
