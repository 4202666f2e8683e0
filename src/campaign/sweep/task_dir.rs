//! A task's directory, `DIR/tasks/<I>/`: every file name in it and every operation on it —
//! its lock, its logs, its run, and the records that say it is done or why it failed —
//! as [`crate::eval::results::RunDir`] is for a run. Whoever executes tasks (the local pool, a
//! Slurm array, a Kubernetes Indexed Job) writes through this type, and the census reads
//! through it, so the two cannot disagree on a name.

use super::plan::Plan;
use super::status::{DoneRecord, FailedRecord, TaskState};
use super::SweepError;
use crate::eval::EvalRequest;
use crate::files::log_text::{
    log_tail, printable, truncated, LOG_LINE_MAX_BYTES, LOG_TAIL_MAX_BYTES,
};
use std::fs::File;
use std::path::{Path, PathBuf};

/// `done.json`: written last, atomically, once the task's run is complete and flushed.
pub const DONE_FILE: &str = "done.json";
/// `failed.json`: why the last attempt failed; removed when the task is tried again.
pub const FAILED_FILE: &str = "failed.json";
/// The advisory lock one attempt holds.
const LOCK_FILE: &str = "lock";
/// The task's run directory (what `eval --out` gets).
const RUN_DIR: &str = "run";
/// The evaluation an attempt hands its `eval` process (`eval --request`): the plan's
/// request with the attempt's session filled in.
const REQUEST_FILE: &str = "request.json";

/// Largest task record read, bytes: a written one is far smaller (its log tail is capped
/// at [`LOG_TAIL_MAX_BYTES`]).
const RECORD_MAX_BYTES: u64 = 1 << 20;

/// Lines of each log quoted in `failed.json`.
const FAILED_LOG_LINES: usize = 12;

/// The output of one of a task's processes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TaskLog {
    /// `eval.log`: the evaluation's standard output and error.
    Eval,
    /// `policy.log`: the launched policy command's.
    Policy,
}

impl TaskLog {
    /// Its file name in the task's directory.
    pub fn file_name(self) -> &'static str {
        match self {
            TaskLog::Eval => "eval.log",
            TaskLog::Policy => "policy.log",
        }
    }
}

/// Task `index`'s directory in a sweep directory.
#[derive(Debug, Clone)]
pub struct TaskDir {
    sweep: PathBuf,
    dir: PathBuf,
    index: usize,
}

/// An attempt's hold on its task: released when dropped (or when the process dies).
#[derive(Debug)]
pub struct TaskLock(#[allow(dead_code)] File);

impl TaskDir {
    /// Task `index` of the sweep in `sweep_dir`.
    pub fn of(sweep_dir: &Path, index: usize) -> Self {
        Self {
            sweep: sweep_dir.to_path_buf(),
            dir: Plan::task_dir(sweep_dir, index),
            index,
        }
    }

    /// The directory.
    pub fn path(&self) -> &Path {
        &self.dir
    }

    /// The task's run directory.
    pub fn run_dir(&self) -> PathBuf {
        self.dir.join(RUN_DIR)
    }

    /// The log of one of its processes.
    pub fn log_file(&self, log: TaskLog) -> PathBuf {
        self.dir.join(log.file_name())
    }

    /// `failed.json`.
    pub fn failed_file(&self) -> PathBuf {
        self.dir.join(FAILED_FILE)
    }

    fn io(&self, path: PathBuf) -> impl FnOnce(std::io::Error) -> SweepError {
        move |source| SweepError::Io { path, source }
    }

    /// Creates the directory and takes its exclusive lock, waiting while another attempt
    /// holds it (a second copy of a task waits, then finds it done).
    pub fn lock(&self) -> Result<TaskLock, SweepError> {
        // Made inside the sweep's directory: a link planted along `tasks/NNNNNN` is not
        // entered, nor another user's directory.
        crate::files::no_follow::make_dir_within(&self.sweep, &self.dir)
            .map_err(self.io(self.dir.clone()))?;
        let path = self.dir.join(LOCK_FILE);
        let file = crate::files::no_follow::create(&path).map_err(self.io(path.clone()))?;
        use std::os::fd::AsRawFd;
        loop {
            // SAFETY: flock on a descriptor we own.
            if unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX) } == 0 {
                return Ok(TaskLock(file));
            }
            let e = std::io::Error::last_os_error();
            if e.kind() != std::io::ErrorKind::Interrupted {
                return Err(self.io(path)(e));
            }
        }
    }

    /// Creates (truncates) one of its logs for an attempt.
    pub fn create_log(&self, log: TaskLog) -> Result<File, SweepError> {
        let path = self.log_file(log);
        crate::files::no_follow::create(&path).map_err(self.io(path))
    }

    /// Forgets the last attempt's failure (a new attempt starts).
    pub fn clear_failed(&self) {
        let _ = std::fs::remove_file(self.failed_file());
    }

    /// Withdraws `done.json` (its run no longer counts: the task runs again). Unlike a
    /// stale `failed.json`, a `done.json` left behind would make the task look done, so
    /// failing to remove it is an error.
    pub fn clear_done(&self) -> Result<(), SweepError> {
        let path = self.dir.join(DONE_FILE);
        match std::fs::remove_file(&path) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(self.io(path)(e)),
            _ => Ok(()),
        }
    }

    /// Writes the evaluation this attempt runs, `request.json`, atomically; returns its
    /// path for `eval --request`.
    pub fn write_request(&self, request: &EvalRequest) -> Result<PathBuf, SweepError> {
        let path = self.dir.join(REQUEST_FILE);
        request.write(&path).map_err(self.io(path.clone()))?;
        Ok(path)
    }

    /// Records that the task is done: `done.json`, atomically, last.
    pub fn write_done(&self, done: &DoneRecord) -> Result<(), SweepError> {
        let json = serde_json::to_string_pretty(done).expect("a DoneRecord serialises");
        write_atomic(&self.dir.join(DONE_FILE), json.as_bytes())
    }

    /// Records why the attempt failed, with the tails of `logs` (bounded and printable
    /// however much, and whatever, the processes wrote). Returns the reason as recorded.
    pub fn write_failed(&self, reason: &str, logs: &[TaskLog]) -> Result<String, SweepError> {
        let reason = truncated(&printable(reason), LOG_LINE_MAX_BYTES);
        let mut quoted = Vec::new();
        let mut budget = LOG_TAIL_MAX_BYTES;
        for &log in logs {
            let mut lines = log_tail(&self.log_file(log), FAILED_LOG_LINES);
            let mut bytes: usize = lines.iter().map(String::len).sum();
            while bytes > budget {
                bytes -= lines.remove(0).len();
            }
            if !lines.is_empty() {
                budget -= bytes;
                quoted.push(format!("--- {}", log.file_name()));
                quoted.extend(lines);
            }
        }
        let record = FailedRecord {
            task: self.index,
            reason: reason.clone(),
            log_tail: quoted,
        };
        let json = serde_json::to_string_pretty(&record).expect("a FailedRecord serialises");
        write_atomic(&self.failed_file(), json.as_bytes())?;
        Ok(reason)
    }

    /// The task's state as its directory shows it. A record is read as what its location
    /// says: one claiming another task (copied, misplaced) is an error naming the file —
    /// it would otherwise count one task twice and drop another from `--array`.
    pub fn state(&self) -> Result<TaskState, SweepError> {
        if let Some(r) = self.read_record::<DoneRecord>(DONE_FILE, |r| r.task)? {
            return Ok(TaskState::Done(r));
        }
        if let Some(r) = self.read_record::<FailedRecord>(FAILED_FILE, |r| r.task)? {
            return Ok(TaskState::Failed(r));
        }
        Ok(if self.run_dir().exists() {
            TaskState::Started
        } else {
            TaskState::NotStarted
        })
    }

    /// Reads record `name` if it is there, bounded in size and checked to be this task's.
    fn read_record<T: serde::de::DeserializeOwned>(
        &self,
        name: &str,
        task_of: impl Fn(&T) -> usize,
    ) -> Result<Option<T>, SweepError> {
        let path = self.dir.join(name);
        let bad = |message: String| SweepError::BadRecord {
            path: path.clone(),
            message,
        };
        let text = match crate::files::bounded_read::read_to_string(
            &path,
            "task record",
            RECORD_MAX_BYTES,
        ) {
            Ok(text) => text,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(source) => return Err(self.io(path.clone())(source)),
        };
        let record: T = serde_json::from_str(&text).map_err(|e| bad(e.to_string()))?;
        let claimed = task_of(&record);
        if claimed != self.index {
            return Err(bad(format!(
                "says it is task {claimed}'s but lies in task {}'s directory (moved or copied?): remove it, and `sweep run` redoes the task",
                self.index
            )));
        }
        Ok(Some(record))
    }
}

/// Writes `bytes` to `path` with [`crate::files::atomic_file::write`] (a temporary
/// sibling, synced, renamed, its directory synced; nothing left behind on failure).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), SweepError> {
    crate::files::atomic_file::write(path, bytes).map_err(|source| SweepError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// [`write_atomic`], creating `path`'s directory (and `also`, a directory the file names,
/// such as the logs of a job script) first.
pub fn write_atomic_in_new_dir(
    path: &Path,
    bytes: &[u8],
    also: Option<&Path>,
) -> Result<(), SweepError> {
    for dir in path.parent().into_iter().chain(also) {
        std::fs::create_dir_all(dir).map_err(|source| SweepError::Io {
            path: dir.to_path_buf(),
            source,
        })?;
    }
    write_atomic(path, bytes)
}
