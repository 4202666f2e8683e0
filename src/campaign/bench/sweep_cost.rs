//! What running a sweep as tasks costs next to running the same episodes directly:
//! `sweep run --jobs N` against one `eval --workers N` per (policy, dataset, latency rule)
//! with all the sweep's settings, both run as this binary's own commands; and how long
//! planning, a status census and collecting take for a sweep of thousands of tasks.

use super::PerfError;
use crate::campaign::own_command;
use crate::campaign::sweep::{finish_with_shard_runs, write_large_spec, Plan, TaskDir};
use crate::eval::EvalRequest;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// One round: the sweep and its direct baseline, each timed once.
#[derive(Debug, Clone)]
pub struct SweepRoundTiming {
    /// `sweep run --jobs N`, s.
    pub sweep_s: f64,
    /// The baseline's `eval` runs one after another, s.
    pub evals_s: f64,
    /// Tasks of the plan.
    pub tasks: usize,
    /// Episodes of the plan.
    pub episodes: usize,
    /// `eval` runs of the baseline.
    pub evals: usize,
}

impl SweepRoundTiming {
    /// Sweep time ÷ baseline time.
    pub fn ratio(&self) -> f64 {
        self.sweep_s / self.evals_s
    }
}

/// Planning, status and collecting timed on a large sweep whose tasks are all done.
#[derive(Debug, Clone)]
pub struct SweepScaleTiming {
    /// Tasks planned.
    pub tasks: usize,
    /// `sweep plan`, s.
    pub plan_s: f64,
    /// `sweep status` with every task done (each run read and checked), s.
    pub status_s: f64,
    /// `sweep collect`, s.
    pub collect_s: f64,
    /// Episodes collected.
    pub episodes: usize,
}

/// Round `round` of the comparison: plans `spec` into `scratch/sweep-<round>` and times
/// the sweep against its baseline with `jobs` tasks at a time (workers), in alternating
/// order across rounds. `exe` is this binary.
pub fn time_sweep_round(
    exe: &Path,
    spec: &Path,
    scratch: &Path,
    round: usize,
    jobs: usize,
) -> Result<SweepRoundTiming, PerfError> {
    let dir = scratch.join(format!("sweep-{round}"));
    run_ok(Command::new(exe).args(own_command::sweep_plan(spec, &dir)))?;
    let plan = Plan::load(&dir).map_err(PerfError::other("loading the plan"))?;
    let evals_dir = scratch.join(format!("eval-{round}"));
    let mut baseline = Vec::new();
    for (i, request) in baseline_requests(&plan)?.into_iter().enumerate() {
        let file = evals_dir.join(format!("request-{i}.json"));
        request
            .write(&file)
            .map_err(PerfError::io(format!("writing {}", file.display())))?;
        let mut eval = Command::new(exe);
        eval.args(own_command::eval_once(
            &file,
            &evals_dir.join(i.to_string()),
            jobs,
        ));
        baseline.push(eval);
    }
    let time_sweep = || -> Result<f64, PerfError> {
        let t = Instant::now();
        run_ok(Command::new(exe).args(own_command::sweep_run(&dir, jobs)))?;
        Ok(t.elapsed().as_secs_f64())
    };
    let mut time_evals = || -> Result<f64, PerfError> {
        let t = Instant::now();
        for eval in &mut baseline {
            run_ok(eval)?;
        }
        Ok(t.elapsed().as_secs_f64())
    };
    let (sweep_s, evals_s) = if round.is_multiple_of(2) {
        let s = time_sweep()?;
        (s, time_evals()?)
    } else {
        let e = time_evals()?;
        (time_sweep()?, e)
    };
    Ok(SweepRoundTiming {
        sweep_s,
        evals_s,
        tasks: plan.tasks.len(),
        episodes: plan.episodes(),
        evals: baseline.len(),
    })
}

/// The baseline of `plan`: one request per (policy, dataset, latency rule), with all the
/// settings of its cells and no shard. Launched policies have no baseline.
fn baseline_requests(plan: &Plan) -> Result<Vec<EvalRequest>, PerfError> {
    let mut groups: Vec<(String, EvalRequest)> = Vec::new();
    for task in plan.tasks.iter().filter(|t| t.shard.0 == 0) {
        let cell = &plan.cells[task.cell];
        if cell.policy.policy.command().is_some() {
            return Err(PerfError::Precondition(format!(
                "policy `{}` runs as a command: the baseline needs in-process policies",
                cell.policy.name
            )));
        }
        let key = format!(
            "{}|{}|{:?}",
            cell.policy.name,
            cell.dataset.display(),
            cell.latency
        );
        match groups.iter_mut().find(|g| g.0 == key) {
            Some((_, request)) => request.settings.push(cell.setting.clone()),
            None => groups.push((
                key,
                EvalRequest {
                    shard: None,
                    ..task.request.clone()
                },
            )),
        }
    }
    Ok(groups.into_iter().map(|(_, r)| r).collect())
}

/// Plans ≈ `tasks` tasks (the sample × many force coefficients × 2 shards) into
/// `scratch/large` and times the plan, and `sweep status` and `collect` with every task
/// finished — each task's run written from `first_sweep`'s first cell's two shards (real
/// runs), its header and records renamed to the task's setting and policy, so `collect`
/// reads, checks and merges as much as real runs of that size, without simulating them.
pub fn time_sweep_at_scale(
    exe: &Path,
    scratch: &Path,
    tasks: usize,
    first_sweep: &Path,
) -> Result<SweepScaleTiming, PerfError> {
    let first = Plan::load(first_sweep).map_err(PerfError::other("loading the plan"))?;
    let shards: Vec<PathBuf> = first
        .tasks
        .iter()
        .filter(|t| t.cell == 0)
        .map(|t| TaskDir::of(first_sweep, t.index).run_dir())
        .collect();
    if shards.len() != 2 || first.cells[0].episodes != 12 {
        return Err(PerfError::Precondition(
            "timing a sweep at scale needs a spec whose first cell is 2 shards of the bundled sample (sweeps/sample.toml)".into(),
        ));
    }
    let spec = write_large_spec(scratch, &first.cells[0].dataset, tasks, shards.len())
        .map_err(PerfError::other("writing the large spec"))?;
    let dir = scratch.join("large");
    let t = Instant::now();
    run_ok(Command::new(exe).args(own_command::sweep_plan(&spec, &dir)))?;
    let plan_s = t.elapsed().as_secs_f64();
    let plan = Plan::load(&dir).map_err(PerfError::other("loading the large plan"))?;
    let episodes = finish_with_shard_runs(&dir, &shards)
        .map_err(PerfError::other("finishing the large sweep's tasks"))?;
    let t = Instant::now();
    run_ok(Command::new(exe).args(own_command::sweep_step("status", &dir)))?;
    let status_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    run_ok(Command::new(exe).args(own_command::sweep_step("collect", &dir)))?;
    let collect_s = t.elapsed().as_secs_f64();
    Ok(SweepScaleTiming {
        tasks: plan.tasks.len(),
        plan_s,
        status_s,
        collect_s,
        episodes,
    })
}

/// Runs `cmd`, its output captured; a failure quotes its standard error.
fn run_ok(cmd: &mut Command) -> Result<(), PerfError> {
    let what = format!("{cmd:?}");
    let out = cmd
        .output()
        .map_err(PerfError::io(format!("running {what}")))?;
    if !out.status.success() {
        return Err(PerfError::Failed {
            what,
            message: String::from_utf8_lossy(&out.stderr).into_owned(),
        });
    }
    Ok(())
}
