//! What has run: each task's directory holds `done.json` (written last, atomically, once
//! its results are complete and flushed) or `failed.json` (why the last attempt failed);
//! [`TaskDir`] reads and writes them, this module counts them.

use super::plan::Plan;
use super::task_dir::TaskDir;
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

/// Reads task `index`'s state from sweep directory `dir` (see [`TaskDir::state`]).
pub fn task_state(dir: &Path, index: usize) -> Result<TaskState, SweepError> {
    TaskDir::of(dir, index).state()
}

/// Tasks by state: (done, failed with reasons, started, not started). A record's
/// task is the directory it lies in (`task_state` refuses one claiming another).
#[derive(Debug)]
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
