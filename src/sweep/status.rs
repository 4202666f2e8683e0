//! What has run: each task's directory holds `done.json` (written last, atomically, once
//! its results are complete and flushed) or `failed.json` (why the last attempt failed).
//! A record is read as what its location says: the directory names the task, and a
//! record claiming another task (copied, misplaced) is an error naming the file — it
//! would otherwise count one task twice and drop another from `--array`.

use super::plan::Plan;
use super::SweepError;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// `done.json`: the task's run holds all its episodes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DoneRecord {
    /// Task index.
    pub task: usize,
    /// Episodes in its `episodes.jsonl` (= the plan's count).
    pub episodes: usize,
    /// Wall seconds the attempt that finished it took.
    pub wall_s: f64,
}

/// `failed.json`: why the last attempt failed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FailedRecord {
    /// Task index.
    pub task: usize,
    /// One line.
    pub reason: String,
    /// The last lines of the policy's or the evaluation's output.
    pub log_tail: Vec<String>,
}

/// A task's state as its directory shows it.
#[derive(Debug, Clone, PartialEq)]
pub enum TaskState {
    /// Complete.
    Done(DoneRecord),
    /// The last attempt failed.
    Failed(FailedRecord),
    /// Started but neither done nor failed: running, or killed mid-way (it resumes).
    Started,
    /// Never started.
    NotStarted,
}

/// Largest task record read, bytes: a written one is far smaller (its log tail is
/// capped at [`super::LOG_TAIL_MAX_BYTES`]).
const RECORD_MAX_BYTES: u64 = 1 << 20;

/// Reads task `index`'s state from sweep directory `dir`.
pub fn task_state(dir: &Path, index: usize) -> Result<TaskState, SweepError> {
    let tdir = Plan::task_dir(dir, index);
    let read = |name: &str| -> Result<Option<String>, SweepError> {
        let path = tdir.join(name);
        let f = match std::fs::File::open(&path) {
            Ok(f) => f,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(source) => return Err(SweepError::Io { path, source }),
        };
        let mut text = String::new();
        use std::io::Read;
        f.take(RECORD_MAX_BYTES + 1)
            .read_to_string(&mut text)
            .map_err(|source| SweepError::Io {
                path: path.clone(),
                source,
            })?;
        if text.len() as u64 > RECORD_MAX_BYTES {
            return Err(SweepError::BadRecord {
                path,
                message: format!("larger than {RECORD_MAX_BYTES} bytes: not a task record"),
            });
        }
        Ok(Some(text))
    };
    let bad = |name: &str, message: String| SweepError::BadRecord {
        path: tdir.join(name),
        message,
    };
    let misplaced = |name: &str, claimed: usize| {
        bad(
            name,
            format!(
                "says it is task {claimed}'s but lies in task {index}'s directory (moved or copied?): remove it, and `sweep run` redoes the task"
            ),
        )
    };
    if let Some(t) = read("done.json")? {
        let r: DoneRecord =
            serde_json::from_str(&t).map_err(|e| bad("done.json", e.to_string()))?;
        if r.task != index {
            return Err(misplaced("done.json", r.task));
        }
        return Ok(TaskState::Done(r));
    }
    if let Some(t) = read("failed.json")? {
        let r: FailedRecord =
            serde_json::from_str(&t).map_err(|e| bad("failed.json", e.to_string()))?;
        if r.task != index {
            return Err(misplaced("failed.json", r.task));
        }
        return Ok(TaskState::Failed(r));
    }
    Ok(if tdir.join("run").exists() {
        TaskState::Started
    } else {
        TaskState::NotStarted
    })
}

/// Tasks by state: (done, failed with reasons, started, not started). A record's
/// task is the directory it lies in (`task_state` refuses one claiming another).
pub struct Census {
    /// Tasks whose `done.json` is there.
    pub done: Vec<usize>,
    /// Tasks whose last attempt failed, with why.
    pub failed: Vec<(usize, FailedRecord)>,
    /// Tasks started and neither done nor failed (running, or interrupted).
    pub started: Vec<usize>,
    /// Tasks never started.
    pub not_started: Vec<usize>,
}

/// Every task of `plan` by its state in sweep directory `dir`.
pub fn census(dir: &Path, plan: &Plan) -> Result<Census, SweepError> {
    let mut c = Census {
        done: Vec::new(),
        failed: Vec::new(),
        started: Vec::new(),
        not_started: Vec::new(),
    };
    for t in &plan.tasks {
        match task_state(dir, t.index)? {
            TaskState::Done(_) => c.done.push(t.index),
            TaskState::Failed(f) => c.failed.push((t.index, f)),
            TaskState::Started => c.started.push(t.index),
            TaskState::NotStarted => c.not_started.push(t.index),
        }
    }
    Ok(c)
}

impl Census {
    /// Every task not done, in index order.
    pub fn not_done(&self) -> Vec<usize> {
        let mut v: Vec<usize> = self.failed.iter().map(|(i, _)| *i).collect();
        v.extend(&self.started);
        v.extend(&self.not_started);
        v.sort_unstable();
        v
    }
}
