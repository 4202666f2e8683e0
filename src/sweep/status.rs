//! What has run: each task's directory holds `done.json` (written last, atomically, once
//! its results are complete and flushed) or `failed.json` (why the last attempt failed).

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

/// Reads task `index`'s state from sweep directory `dir`.
pub fn task_state(dir: &Path, index: usize) -> Result<TaskState, SweepError> {
    let tdir = Plan::task_dir(dir, index);
    let read = |name: &str| -> Result<Option<String>, SweepError> {
        let path = tdir.join(name);
        match std::fs::read_to_string(&path) {
            Ok(t) => Ok(Some(t)),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
            Err(source) => Err(SweepError::Io { path, source }),
        }
    };
    let bad = |name: &str, e: serde_json::Error| SweepError::BadRecord {
        path: tdir.join(name),
        message: e.to_string(),
    };
    if let Some(t) = read("done.json")? {
        return Ok(TaskState::Done(
            serde_json::from_str(&t).map_err(|e| bad("done.json", e))?,
        ));
    }
    if let Some(t) = read("failed.json")? {
        return Ok(TaskState::Failed(
            serde_json::from_str(&t).map_err(|e| bad("failed.json", e))?,
        ));
    }
    Ok(if tdir.join("run").exists() {
        TaskState::Started
    } else {
        TaskState::NotStarted
    })
}
