//! [`RunDir`]: a run directory's file names and everything done to it — start (afresh or
//! resuming), append records as episodes finish, write traces, finish with the scores,
//! rewrite a run merged from shards. Every command that writes or reads a run goes
//! through it, so no file name of a run is spelled anywhere else.

use super::episodes::{write_record, EpisodeLog};
use super::header::{read_header, write_header};
use super::summary::{read_summary, sort_records, write_results, PolicyIoReport, Summary};
use super::{
    ResultsError, RunHeader, EPISODES_CSV_FILE, EPISODES_FILE, HEADER_FILE, SUMMARY_FILE,
    TABLES_FILE,
};
use crate::eval::episode::TraceStep;
use crate::eval::metrics::RegimeThresholds;
use crate::eval::{EpisodeKey, EpisodeRecord, Termination};
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The directory of rollout traces, in a run directory.
pub const TRACES_DIR: &str = "traces";

/// The largest trace file read, bytes (1 GiB: a trace is some 10 KB per control step).
pub const MAX_TRACE_BYTES: u64 = 1 << 30;

/// The series `crosscheck` compares beyond the records, in each engine's run directory.
pub const CROSSCHECK_SERIES_FILE: &str = "crosscheck-series.jsonl";

/// Every entry a run directory may hold (what `--overwrite` replaces).
pub const RUN_FILES: [&str; 6] = [
    HEADER_FILE,
    EPISODES_FILE,
    SUMMARY_FILE,
    TABLES_FILE,
    EPISODES_CSV_FILE,
    TRACES_DIR,
];

/// The lock file of a run directory: the process holding it (`flock`, released by the
/// kernel when that process ends, however it ends) is the directory's one writer.
pub const LOCK_FILE: &str = ".writer.lock";

/// The writer's hold on a run directory ([`RunDir::lock`]); dropping it lets another in.
#[derive(Debug)]
pub struct RunLock {
    _file: std::fs::File,
    /// The lock file.
    path: PathBuf,
    /// The run directory, and whether taking the lock made it.
    dir: PathBuf,
    made_dir: bool,
}

impl RunLock {
    /// Gives the lock up, and with it — when no run was started in the directory (no
    /// `run.json`: a DDS bridge that got no command) — the lock file, and the directory if
    /// taking the lock made it and nothing else is in it: a command that wrote no run
    /// leaves nothing behind.
    pub fn release_if_unwritten(self) {
        if self.dir.join(HEADER_FILE).exists() {
            return;
        }
        let _ = std::fs::remove_file(&self.path);
        if self.made_dir {
            let _ = std::fs::remove_dir(&self.dir);
        }
    }
}

/// A run directory (it need not exist yet).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RunDir {
    dir: PathBuf,
}

/// What [`RunDir::start`] found and kept.
#[derive(Debug, Default)]
pub struct Started {
    /// Records of a previous attempt kept by a resume (none afresh), in file order.
    pub kept: Vec<EpisodeRecord>,
    /// A previous run was there to resume (false: a resume found nothing and started
    /// afresh).
    pub resumed: bool,
    /// The previous attempt's last line was cut short (a killed writer) and is dropped.
    pub torn_tail_dropped: bool,
    /// Finished episodes whose trace was asked for but is not in `traces/` (lost to a
    /// full disk, or removed): not kept, so they run again and write it.
    pub trace_missing: Vec<EpisodeKey>,
}

impl RunDir {
    /// The run directory at `dir`.
    pub fn new(dir: impl Into<PathBuf>) -> Self {
        Self { dir: dir.into() }
    }

    /// The directory.
    pub fn path(&self) -> &Path {
        &self.dir
    }

    /// `run.json`.
    pub fn header_file(&self) -> PathBuf {
        self.dir.join(HEADER_FILE)
    }

    /// `episodes.jsonl`.
    pub fn episodes_file(&self) -> PathBuf {
        self.dir.join(EPISODES_FILE)
    }

    /// `summary.json`.
    pub fn summary_file(&self) -> PathBuf {
        self.dir.join(SUMMARY_FILE)
    }

    /// `tables.md`.
    pub fn tables_file(&self) -> PathBuf {
        self.dir.join(TABLES_FILE)
    }

    /// `crosscheck-series.jsonl` (a run made by `crosscheck`).
    pub fn crosscheck_series_file(&self) -> PathBuf {
        self.dir.join(CROSSCHECK_SERIES_FILE)
    }

    /// `traces/`.
    pub fn traces_dir(&self) -> PathBuf {
        self.dir.join(TRACES_DIR)
    }

    /// The trace of one episode: `traces/<task>-<sequence>-<setting>.json`.
    pub fn trace_file(&self, key: &EpisodeKey) -> PathBuf {
        self.traces_dir().join(format!(
            "{}-{}-{}.json",
            key.task, key.sequence_id, key.setting
        ))
    }

    /// The directory holds a run (its `run.json`): anything under that name counts, so a
    /// FIFO or a link to a device there is refused when read, never taken for no run and
    /// started afresh over by `--resume`.
    pub fn holds_run(&self) -> bool {
        std::fs::symlink_metadata(self.header_file()).is_ok()
    }

    /// Reads `run.json`.
    pub fn read_header(&self) -> Result<RunHeader, ResultsError> {
        read_header(&self.dir)
    }

    /// Reads `episodes.jsonl`, every record checked against `header`.
    pub fn read_log(&self, header: &RunHeader) -> Result<EpisodeLog, ResultsError> {
        EpisodeLog::read(&self.episodes_file(), header)
    }

    /// Reads `summary.json`.
    pub fn read_summary(&self) -> Result<Summary, ResultsError> {
        read_summary(&self.dir)
    }

    /// Makes this process the directory's one writer until the returned lock drops, or
    /// says who already is ([`ResultsError::Busy`]). Every writer of a run — `evaluate`,
    /// `merge`, the DDS bridge — holds it from before its first write to after its last,
    /// so two commands given one `--out` cannot interleave their files.
    pub fn lock(&self) -> Result<RunLock, ResultsError> {
        use std::os::fd::AsRawFd;
        let made_dir = !self.dir.exists();
        std::fs::create_dir_all(&self.dir).map_err(ResultsError::io(&self.dir))?;
        let path = self.dir.join(LOCK_FILE);
        let mut file = crate::files::no_follow::open(
            crate::files::no_follow::options()
                .read(true)
                .write(true)
                .create(true)
                .truncate(false),
            &path,
        )
        .map_err(ResultsError::io(&path))?;
        // SAFETY: flock on a descriptor this function owns; no memory is shared.
        if unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) } != 0 {
            let err = std::io::Error::last_os_error();
            if err.raw_os_error() == Some(libc::EWOULDBLOCK) {
                // A pid: a few bytes (the lock holds, so the file is the writer's own).
                let holder =
                    crate::files::bounded_read::read_to_string(&path, "lock file", 1 << 10)
                        .ok()
                        .and_then(|s| s.trim().parse().ok());
                return Err(ResultsError::Busy {
                    path: self.dir.clone(),
                    holder,
                });
            }
            return Err(ResultsError::Io { path, source: err });
        }
        let pid = std::process::id().to_string();
        let written = file
            .set_len(0)
            .and_then(|()| std::io::Write::write_all(&mut file, pid.as_bytes()));
        written.map_err(ResultsError::io(&path))?;
        Ok(RunLock {
            _file: file,
            path,
            dir: self.dir.clone(),
            made_dir,
        })
    }

    /// Whether the directory can be written: it is made if missing (and removed again if
    /// it was), and a probe file is written and removed, so a run fails before its policy
    /// loads rather than after its first episode.
    pub fn check_writable(&self) -> Result<(), ResultsError> {
        let existed = self.dir.exists();
        std::fs::create_dir_all(&self.dir).map_err(ResultsError::io(&self.dir))?;
        let probe = self.dir.join(format!(".write-test-{}", std::process::id()));
        crate::files::no_follow::open(
            crate::files::no_follow::options()
                .write(true)
                .create_new(true),
            &probe,
        )
        .map_err(|source| ResultsError::NotWritable {
            path: self.dir.clone(),
            source,
        })?;
        let _ = std::fs::remove_file(probe);
        if !existed {
            let _ = std::fs::remove_dir(&self.dir);
        }
        Ok(())
    }

    /// Starts the run `header` describes: afresh (an empty `episodes.jsonl`), or with
    /// `resume` and a previous run of the same configuration there, keeping its finished
    /// episodes — all but those a dead policy cut short, which run again — and rewriting
    /// the file without a torn last line — and those whose trace `traced` asks for but
    /// which has no trace file, which run again to write it. A previous run of another
    /// configuration is refused, naming what differs. `run.json` is written last.
    pub fn start(
        &self,
        header: &RunHeader,
        resume: bool,
        traced: &dyn Fn(&EpisodeRecord) -> bool,
    ) -> Result<Started, ResultsError> {
        std::fs::create_dir_all(&self.dir).map_err(ResultsError::io(&self.dir))?;
        let episodes = self.episodes_file();
        let mut started = Started::default();
        if resume && self.holds_run() {
            let previous = self.read_header()?;
            if previous != *header {
                return Err(ResultsError::OtherConfiguration {
                    path: self.dir.clone(),
                    differences: previous.differences(header),
                });
            }
            let log = self.read_log(header)?;
            started.resumed = true;
            started.torn_tail_dropped = log.torn_tail;
            for r in log.records {
                if r.termination == Some(Termination::PolicyFailed) {
                    continue;
                }
                let key = r.key();
                if traced(&r) && std::fs::symlink_metadata(self.trace_file(&key)).is_err() {
                    started.trace_missing.push(key);
                    continue;
                }
                started.kept.push(r);
            }
            EpisodeLog::rewrite(&episodes, &started.kept)?;
        } else {
            crate::files::no_follow::create(&episodes).map_err(ResultsError::io(&episodes))?;
        }
        write_header(&self.dir, header)?;
        Ok(started)
    }

    /// Opens `episodes.jsonl` to append records as episodes finish.
    pub fn appender(&self) -> Result<RecordAppender, ResultsError> {
        let path = self.episodes_file();
        let file =
            crate::files::no_follow::open(crate::files::no_follow::options().append(true), &path)
                .map_err(ResultsError::io(&path))?;
        Ok(RecordAppender {
            writer: std::io::BufWriter::new(file),
            path,
        })
    }

    /// Writes one episode's trace to [`Self::trace_file`].
    pub fn write_trace(&self, key: &EpisodeKey, steps: &[TraceStep]) -> Result<(), ResultsError> {
        let dir = self.traces_dir();
        // Made by the run inside its directory: a link planted there is not entered.
        crate::files::no_follow::make_dir_within(&self.dir, &dir)
            .map_err(ResultsError::io(&dir))?;
        let path = self.trace_file(key);
        let bytes = serde_json::to_vec(steps).map_err(|source| ResultsError::Json {
            path: path.clone(),
            line: None,
            source,
        })?;
        crate::files::atomic_file::write(&path, bytes).map_err(ResultsError::io(&path))
    }

    /// Reads a trace file written by [`Self::write_trace`] (or copied from one).
    pub fn read_trace(path: &Path) -> Result<Vec<TraceStep>, ResultsError> {
        let text = crate::files::bounded_read::read_to_string(path, "trace file", MAX_TRACE_BYTES)
            .map_err(ResultsError::io(path))?;
        serde_json::from_str(&text).map_err(|source| ResultsError::Json {
            path: path.to_path_buf(),
            line: None,
            source,
        })
    }

    /// Finishes a run: sorts `records` into schedule order and writes the scores
    /// (`summary.json`, `episodes.csv`) computed with `thresholds`.
    pub fn finish(
        &self,
        header: &RunHeader,
        records: &mut [EpisodeRecord],
        thresholds: BTreeMap<String, RegimeThresholds>,
        io: Option<PolicyIoReport>,
    ) -> Result<Summary, ResultsError> {
        sort_records(records, header);
        write_results(&self.dir, header, records, thresholds, io)
    }

    /// Flushes the finished run's files to the disk (`run.json`, `episodes.jsonl`,
    /// `summary.json`, `tables.md`), so a record that says the run is done never outlives
    /// the run after a crash.
    pub fn sync(&self) -> Result<(), ResultsError> {
        for path in [
            self.episodes_file(),
            self.header_file(),
            self.summary_file(),
            self.tables_file(),
        ] {
            std::fs::File::open(&path)
                .and_then(|f| f.sync_all())
                .map_err(ResultsError::io(&path))?;
        }
        Ok(())
    }

    /// Writes a whole run at once — `episodes.jsonl` (sorted), `run.json` and the scores —
    /// as a merge of shards does: the same files a single run of those episodes writes.
    pub fn rewrite(
        &self,
        header: &RunHeader,
        records: &mut [EpisodeRecord],
        thresholds: BTreeMap<String, RegimeThresholds>,
    ) -> Result<Summary, ResultsError> {
        sort_records(records, header);
        std::fs::create_dir_all(&self.dir).map_err(ResultsError::io(&self.dir))?;
        EpisodeLog::rewrite(&self.episodes_file(), records)?;
        write_header(&self.dir, header)?;
        write_results(&self.dir, header, records, thresholds, None)
    }
}

/// `episodes.jsonl` open for appending: each record one line, flushed as written, so a
/// killed run loses at most the line being written.
pub struct RecordAppender {
    writer: std::io::BufWriter<std::fs::File>,
    path: PathBuf,
}

impl RecordAppender {
    /// Appends one record.
    pub fn append(&mut self, record: &EpisodeRecord) -> Result<(), ResultsError> {
        write_record(&mut self.writer, record).map_err(ResultsError::io(&self.path))
    }

    /// Flushes what is buffered.
    pub fn flush(&mut self) -> Result<(), ResultsError> {
        self.writer.flush().map_err(ResultsError::io(&self.path))
    }
}
