//! One attempt at a task: a child `thorarena eval` of the task's request (and, for a
//! `command` policy, the launched policy process in its own process group), under the
//! task's lock, ending in `done.json` only when the run counts, or in `failed.json`
//! saying why. Whoever executes tasks — the local pool, a Slurm array, a Kubernetes
//! Indexed Job — runs this.

use super::verify::{check_task_run, RunProblem};
use super::{Cell, DoneRecord, Plan, SweepError, Task, TaskDir, TaskLog, TaskState};
use crate::campaign::own_command;
use crate::eval::results::RunDir;
use crate::policy::launched::{die_with_parent, stop_group};
use crate::policy::network_file::short_hash;
use crate::sim::motion::Dataset;
use std::path::Path;
use std::process::{Child, Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

/// What became of one attempt at a task.
#[derive(Debug)]
pub enum Outcome {
    /// Finished now.
    Done,
    /// It was done before.
    AlreadyDone,
    /// Failed; `failed.json` says why.
    Failed(String),
}

/// How long an evaluation may go on after its launched policy exited before it is
/// stopped (it would wait for a policy that will not come).
const AFTER_POLICY_EXIT: Duration = Duration::from_secs(3);

/// Runs task `index` of `plan` in sweep directory `dir` with `workers` threads; `exe` is
/// the `thorarena` binary whose `eval` runs it.
pub fn run_task(
    exe: &Path,
    dir: &Path,
    plan: &Plan,
    index: usize,
    workers: usize,
) -> Result<Outcome, SweepError> {
    let task = plan.tasks.get(index).ok_or(SweepError::NoTask {
        index,
        tasks: plan.tasks.len(),
    })?;
    let cell = &plan.cells[task.cell]; // in range: the plan was checked when loaded
    let tdir = TaskDir::of(dir, index);
    // One copy at a time; a second one waits, then finds the task done.
    let lock = tdir.lock()?;
    let fail = |reason: String, logs: &[TaskLog]| -> Result<Outcome, SweepError> {
        Ok(Outcome::Failed(tdir.write_failed(&reason, logs)?))
    };
    // done.json is only a claim about the run when it was written: the run counts again,
    // here, before the task is skipped (`status` and `collect` check the same).
    if let TaskState::Done(_) = tdir.state()? {
        let run_dir = tdir.run_dir();
        match check_task_run(plan, task, &RunDir::new(&run_dir)) {
            Ok(Ok(_)) => return Ok(Outcome::AlreadyDone),
            Ok(Err(RunProblem::NotThisTask(why))) => {
                tdir.clear_done()?;
                return fail(
                    format!("{why}; remove {} and run the task again", run_dir.display()),
                    &[],
                );
            }
            // Missing or policy-failed episodes, or an unreadable run: `eval --resume`
            // runs what is missing, or says why it cannot.
            Ok(Err(RunProblem::Incomplete(_))) | Err(_) => tdir.clear_done()?,
        }
    }
    tdir.clear_failed();
    let started = Instant::now();

    if let Some(why) = changed_since_planned(plan, cell)? {
        return fail(why, &[]);
    }

    let session = format!("sweep-{index}-{}", std::process::id());
    let run_dir = tdir.run_dir();
    // The run's directory, made here inside the task's (a planted link is not entered):
    // the eval it starts takes it as its `--out`, which it follows.
    crate::files::no_follow::make_dir(&run_dir).map_err(|source| SweepError::Io {
        path: run_dir.clone(),
        source,
    })?;
    let mut eval_cmd = eval_command(exe, plan, task, &session, workers, &tdir)?;
    let mut policy: Option<Child> = None;
    if let Some(command) = cell.policy.policy.command() {
        let log = tdir.create_log(TaskLog::Policy)?;
        match command.spawn(&session, log, &tdir.log_file(TaskLog::Policy)) {
            Ok(child) => policy = Some(child),
            Err(why) => return fail(why, &[]),
        }
    }
    let mut eval = eval_cmd
        .spawn()
        .map_err(SweepError::process("starting thorarena eval"))?;
    let status = wait_eval(&mut eval, policy.as_mut())?;
    if let Some(p) = policy.as_mut() {
        stop_group(p);
    }
    let eval_status = match status {
        EvalEnd::Exited(s) => s,
        EvalEnd::PolicyGone(ps) => {
            return fail(
                format!("the policy command exited ({ps}) before the evaluation finished"),
                &[TaskLog::Policy, TaskLog::Eval],
            )
        }
    };
    if !eval_status.success() {
        return fail(
            format!("thorarena eval failed ({eval_status})"),
            &[TaskLog::Eval, TaskLog::Policy],
        );
    }
    // Complete, this task's, and on disk before it counts as done: `eval` exits 0 when
    // a dying policy cut short every episode still in flight.
    let run = RunDir::new(&run_dir);
    let records = match check_task_run(plan, task, &run)? {
        Ok(records) => records,
        Err(RunProblem::Incomplete(why)) => {
            return fail(
                format!("{why}; `sweep run` again resumes the task"),
                &[TaskLog::Eval, TaskLog::Policy],
            )
        }
        Err(RunProblem::NotThisTask(why)) => {
            return fail(
                format!("{why}; remove {} and run the task again", run_dir.display()),
                &[TaskLog::Eval],
            )
        }
    };
    run.sync()?;
    let done = DoneRecord {
        task: index,
        episodes: records.len(),
        wall_s: started.elapsed().as_secs_f64(),
    };
    tdir.write_done(&done)?;
    drop(lock);
    Ok(Outcome::Done)
}

/// Why the cell's inputs are not the ones planned — the dataset unreadable or changed, the
/// network changed (a curve over cells is one network's) — or `None`.
fn changed_since_planned(plan: &Plan, cell: &Cell) -> Result<Option<String>, SweepError> {
    let robot = crate::policy::registry::robot(&plan.robot)?;
    let ds = match Dataset::open(&cell.dataset, &robot) {
        Ok(ds) => ds,
        Err(e) => return Ok(Some(format!("dataset {}: {e}", cell.dataset.display()))),
    };
    if ds.content_hash() != cell.dataset_sha256 {
        return Ok(Some(format!(
            "dataset {} changed since the sweep was planned (content hash differs)",
            cell.dataset.display()
        )));
    }
    if let Some(planned) = &cell.policy.network_sha256 {
        let now = super::plan::planned_network(&cell.policy.policy);
        if now.as_ref() != Some(planned) {
            return Ok(Some(format!(
                "the network of `{}` changed since the sweep was planned (sha256 {} planned, {} now): plan the sweep again in a new directory",
                cell.policy.name,
                short_hash(planned),
                now.as_deref().map_or("unreadable", short_hash)
            )));
        }
    }
    Ok(None)
}

/// The task's `eval` process: the plan's request (this attempt's session filled in, in
/// the task's `request.json`) into the task's run, resuming, its output in `eval.log`,
/// dying with this process.
fn eval_command(
    exe: &Path,
    plan: &Plan,
    task: &Task,
    session: &str,
    workers: usize,
    tdir: &TaskDir,
) -> Result<Command, SweepError> {
    let request = tdir.write_request(&task.request_for(session))?;
    let eval_log = tdir.create_log(TaskLog::Eval)?;
    let log_path = tdir.log_file(TaskLog::Eval);
    let policy = &plan.cells[task.cell].policy;
    let connect_timeout_s = policy
        .policy
        .command()
        .map(|command| command.connect_timeout_s());
    let mut eval_cmd = Command::new(exe);
    eval_cmd.args(own_command::eval_of_request(
        &request,
        &tdir.run_dir(),
        workers,
        connect_timeout_s,
    ));
    let stdout = eval_log.try_clone().map_err(|source| SweepError::Io {
        path: log_path,
        source,
    })?;
    eval_cmd
        .stdin(Stdio::null())
        .stdout(stdout)
        .stderr(eval_log);
    die_with_parent(&mut eval_cmd);
    Ok(eval_cmd)
}

/// How an evaluation ended.
enum EvalEnd {
    Exited(ExitStatus),
    /// The launched policy exited while the evaluation still ran (it was stopped).
    PolicyGone(ExitStatus),
}

/// Waits for the evaluation; if the policy process exits first and the evaluation has
/// not ended [`AFTER_POLICY_EXIT`] later, stops it.
fn wait_eval(eval: &mut Child, mut policy: Option<&mut Child>) -> Result<EvalEnd, SweepError> {
    let waiting = |source| SweepError::Process {
        what: "waiting for the task's processes".into(),
        source,
    };
    let mut policy_exit: Option<(ExitStatus, Instant)> = None;
    loop {
        match eval.try_wait() {
            Ok(Some(s)) => return Ok(EvalEnd::Exited(s)),
            Ok(None) => {}
            Err(e) => return Err(waiting(e)),
        }
        if let (Some(p), None) = (policy.as_deref_mut(), policy_exit) {
            match p.try_wait() {
                Ok(Some(s)) => policy_exit = Some((s, Instant::now())),
                Ok(None) => {}
                Err(e) => return Err(waiting(e)),
            }
        }
        if let Some((s, at)) = policy_exit {
            if at.elapsed() > AFTER_POLICY_EXIT {
                let _ = eval.kill();
                let _ = eval.wait();
                return Ok(EvalEnd::PolicyGone(s));
            }
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}
