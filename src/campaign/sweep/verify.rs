//! A task's run checked against its plan entry before it counts: by `sweep task` before
//! it writes `done.json`, and by `collect` before it scores the run under its cell's
//! label. `eval` exits 0 when a policy died while every remaining episode was in flight
//! (each ends `policy_failed`), and a run directory can be replaced or copied: so a run
//! counts only when its header is the configuration the cell plans (policy, dataset and
//! its hash, settings, shard, engine, rules) and it holds every planned episode, none
//! cut short by a policy failure.

use super::{census, Census, Plan, SweepError, Task, TaskDir};
use crate::eval::results::{Coverage, ResultsError, RunDir, RunHeader};
use crate::eval::{EpisodeRecord, EvalRequest};
use crate::policy::network_file::short_hash;

/// Why a task's run does not count for the task.
#[derive(Debug)]
pub enum RunProblem {
    /// Episodes missing or cut short by a policy failure: `eval --resume` (a retried
    /// task) runs them.
    Incomplete(String),
    /// The run is another configuration's: never scored under this cell.
    NotThisTask(String),
}

/// The run's records when `run` is complete and is task `task`'s; `Err` when it cannot
/// be read at all (naming the file).
pub fn check_task_run(
    plan: &Plan,
    task: &Task,
    run: &RunDir,
) -> Result<Result<Vec<EpisodeRecord>, RunProblem>, ResultsError> {
    let header = run.read_header()?;
    if let Some(problem) = header_problem(plan, task, &header, &task.request) {
        return Ok(Err(RunProblem::NotThisTask(format!(
            "{}: not task {}'s run: {problem}",
            run.header_file().display(),
            task.index
        ))));
    }
    let log = run.read_log(&header)?;
    let coverage = Coverage::of(&header, &log.records);
    if log.torn_tail || !coverage.is_complete() || log.records.len() != task.episodes {
        let expected: usize = coverage.cells.iter().map(|c| c.expected).sum();
        return Ok(Err(RunProblem::Incomplete(format!(
            "its run holds {} of {expected} planned episodes, {} of them ended policy_failed (the policy process died mid-episode){}",
            log.records.len(),
            coverage.policy_failed(),
            if log.torn_tail { ", and a line cut short" } else { "" }
        ))));
    }
    Ok(Ok(log.records))
}

/// The first field of `header` that is not what `task`'s cell plans.
fn header_problem(
    plan: &Plan,
    task: &Task,
    header: &RunHeader,
    run: &EvalRequest,
) -> Option<String> {
    let cell = &plan.cells[task.cell];
    // Values as run.json writes them (`[1, 2]`, `null`), not Rust's debug text.
    let differs = |field: &str, got: String, planned: String| {
        Some(format!(
            "its {field} is {got}, cell {} (`{}`) plans {planned}",
            cell.index, cell.policy.name
        ))
    };
    // A launched policy names itself; an in-process one is named by its kind.
    if let Some(arg) = cell.policy.policy.named() {
        let kind = arg.family().name;
        if header.policy != kind {
            return differs("policy", shown(&header.policy), shown(&kind));
        }
    }
    if let Some(planned) = &cell.policy.network_sha256 {
        let ran = header
            .identity
            .as_ref()
            .and_then(|i| i.network.as_ref())
            .map(|n| n.sha256.as_str());
        if ran != Some(planned.as_str()) {
            return Some(format!(
                "its network is {}, cell {} (`{}`) plans sha256 {} (the file was replaced since the sweep was planned)",
                ran.map_or_else(|| "not recorded".into(), |s| format!("sha256 {}", short_hash(s))),
                cell.index,
                cell.policy.name,
                short_hash(planned)
            ));
        }
    }
    let dataset = cell.dataset.display().to_string();
    let setting = &cell.setting;
    let termination = run.termination;
    let io = run.io;
    if header.dataset != dataset {
        differs("dataset", shown(&header.dataset), shown(&dataset))
    } else if header.dataset_sha256 != cell.dataset_sha256 {
        differs(
            "dataset hash",
            shown(&header.dataset_sha256),
            shown(&cell.dataset_sha256),
        )
    } else if header.subset.as_ref().map(|s| &s.selection)
        != (!cell.selection.is_all()).then_some(&cell.selection)
    {
        differs(
            "tasks/sequences",
            shown(&header.subset),
            shown(&cell.selection),
        )
    } else if header.sequences.len() != cell.episodes {
        differs(
            "sequence count",
            shown(&header.sequences.len()),
            shown(&cell.episodes),
        )
    } else if header.settings != [setting.clone()] {
        differs("settings", shown(&header.settings), shown(setting))
    } else if header.shard != run.shard {
        differs("shard", shown(&header.shard), shown(&run.shard))
    } else if header.keypoints != run.keypoints {
        differs(
            "keypoint set",
            shown(&header.keypoints),
            shown(&run.keypoints),
        )
    } else if !cell.policy.profile.ends_with(".toml") && header.profile != cell.policy.profile {
        differs(
            "profile",
            shown(&header.profile),
            shown(&cell.policy.profile),
        )
    } else if header.io != io {
        differs("policy I/O rules", shown(&header.io), shown(&io))
    } else if header.termination != termination {
        differs(
            "termination rule",
            shown(&header.termination),
            shown(&termination),
        )
    } else if header.engine.name() != cell.engine.engine {
        differs(
            "engine",
            shown(&header.engine.name()),
            shown(&cell.engine.engine),
        )
    } else if cell
        .engine
        .physics_dt_s
        .is_some_and(|dt| dt != header.physics_dt_s)
    {
        differs(
            "physics step",
            shown(&header.physics_dt_s),
            shown(&cell.engine.physics_dt_s),
        )
    } else if header.planned_jobs().len() != task.episodes {
        differs(
            "planned episodes",
            shown(&header.planned_jobs().len()),
            shown(&task.episodes),
        )
    } else {
        None
    }
}

impl RunProblem {
    /// Why the run does not count, in one line.
    pub fn why(&self) -> &str {
        match self {
            Self::Incomplete(why) | Self::NotThisTask(why) => why,
        }
    }
}

/// The tasks by state as [`census`] reads them, except that a task counts as done only
/// when its run does: those whose `done.json` is there but whose run does not count are
/// in `not_counted`, with why, and among the not-done tasks. `done.json` says a run was
/// complete when its task finished; the run directory can change after that (edited,
/// replaced, cut short by hand), so every command that counts a task done — `status`,
/// `collect`, and `run`/`task` deciding whether to skip it — checks the run itself.
#[derive(Debug)]
pub struct CheckedCensus {
    /// The directories' census, `done` holding only the tasks whose run counts.
    pub census: Census,
    /// Tasks marked done whose run does not count, with why, in task order (a run that
    /// cannot be read is `Incomplete`: `eval --resume` says what is wrong with it).
    pub not_counted: Vec<(usize, RunProblem)>,
}

impl CheckedCensus {
    /// Every task of `plan` in sweep directory `dir`, each done task's run checked. A run
    /// that cannot be read at all does not count (the reason names the file): a command
    /// that only reports — `status` — never stops at it.
    pub fn of(dir: &std::path::Path, plan: &Plan) -> Result<Self, SweepError> {
        let mut census = census(dir, plan)?;
        let mut not_counted = Vec::new();
        census.done.retain(|&i| {
            let run = RunDir::new(TaskDir::of(dir, i).run_dir());
            let problem = match check_task_run(plan, &plan.tasks[i], &run) {
                Ok(Ok(_)) => return true,
                Ok(Err(problem)) => problem,
                Err(e) => RunProblem::Incomplete(format!("its run cannot be read: {e}")),
            };
            not_counted.push((i, problem));
            false
        });
        Ok(Self {
            census,
            not_counted,
        })
    }

    /// The tasks to run: failed, started, not started, and marked done without counting.
    pub fn not_done(&self) -> Vec<usize> {
        let mut v = self.census.not_done();
        v.extend(self.not_counted.iter().map(|(i, _)| *i));
        v.sort_unstable();
        v
    }
}

/// `value` as run.json writes it (JSON: `[1, 2]` for a shard, `null` for none).
fn shown<T: serde::Serialize + ?Sized>(value: &T) -> String {
    serde_json::to_string(value).unwrap_or_else(|_| "(unwritable)".into())
}
