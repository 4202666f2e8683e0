//! One task: a child `thorarena eval` (and a launched policy process), its lock, and the
//! records that say it is done or why it failed.

use super::verify::{check_task_run, RunProblem};
use super::TaskArgs;
use anyhow::{bail, Context};
use std::path::Path;
use std::process::{Child, Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};
use thorarena::motion::Dataset;
use thorarena::results::RunDir;
use thorarena::sweep::process_group::{
    die_with_parent, policy_command_line, shell_in_own_group, stop_group,
};
use thorarena::sweep::{DoneRecord, Plan, Task, TaskDir, TaskLog, TaskState};
/// What became of one attempt at a task.
#[derive(Debug)]
pub(super) enum Outcome {
    /// Finished now.
    Done,
    /// It was done before.
    AlreadyDone,
    /// Failed; `failed.json` says why.
    Failed(String),
}

/// Runs task `index` of `plan` in sweep directory `dir` with `workers` threads.
pub(super) fn run_task(
    dir: &Path,
    plan: &Plan,
    index: usize,
    workers: usize,
) -> anyhow::Result<Outcome> {
    let task = plan
        .tasks
        .get(index)
        .with_context(|| format!("task {index}: the plan has tasks 0..{}", plan.tasks.len()))?;
    let cell = &plan.cells[task.cell]; // in range: the plan was checked when loaded
    let tdir = TaskDir::of(dir, index);
    // One copy at a time; a second one waits, then finds the task done.
    let lock = tdir.lock()?;
    let fail = |reason: String, logs: &[TaskLog]| -> anyhow::Result<Outcome> {
        Ok(Outcome::Failed(tdir.write_failed(&reason, logs)?))
    };
    // done.json is only a claim about the run when it was written: the run counts again,
    // here, before the task is skipped (`status` and `collect` check the same).
    if let TaskState::Done(_) = tdir.state()? {
        let run_dir = tdir.run_dir();
        match check_task_run(plan, task, &run_dir) {
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

    // The dataset must be the one planned.
    let robot = thorarena::registry::robot(&plan.robot)?;
    let ds = match Dataset::open(&cell.dataset, &robot) {
        Ok(ds) => ds,
        Err(e) => return fail(format!("dataset {}: {e}", cell.dataset.display()), &[]),
    };
    if ds.content_hash() != cell.dataset_sha256 {
        return fail(
            format!(
                "dataset {} changed since the sweep was planned (content hash differs)",
                cell.dataset.display()
            ),
            &[],
        );
    }

    let session = format!("sweep-{index}-{}", std::process::id());
    let run_dir = tdir.run_dir();
    let mut eval_cmd = eval_command(plan, task, &session, workers, &tdir)?;
    let mut policy: Option<Child> = None;
    if let Some(command) = &cell.policy.command {
        match start_policy(plan, command, &session, &tdir)? {
            Ok(child) => policy = Some(child),
            Err(why) => return fail(why, &[]),
        }
    }
    let mut eval = eval_cmd.spawn().context("starting thorarena eval")?;
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
    let records = match check_task_run(plan, task, &run_dir)? {
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
    RunDir::new(&run_dir)
        .sync()
        .context("flushing the task's run")?;
    let done = DoneRecord {
        task: index,
        episodes: records.len(),
        wall_s: started.elapsed().as_secs_f64(),
    };
    tdir.write_done(&done)?;
    drop(lock);
    Ok(Outcome::Done)
}

/// The task's `eval` process: the plan's request (this attempt's session filled in, in
/// the task's `request.json`) into the task's run, resuming, its output in `eval.log`,
/// dying with this process.
fn eval_command(
    plan: &Plan,
    task: &Task,
    session: &str,
    workers: usize,
    tdir: &TaskDir,
) -> anyhow::Result<Command> {
    let request = tdir.write_request(&task.request_for(session))?;
    let eval_log = tdir.create_log(TaskLog::Eval)?;
    let mut eval_cmd = Command::new(std::env::current_exe()?);
    eval_cmd
        .arg("eval")
        .arg("--request")
        .arg(request)
        .arg("--out")
        .arg(tdir.run_dir())
        .args(["--resume", "--workers", &workers.to_string()]);
    if plan.cells[task.cell].policy.command.is_some() {
        let timeout = plan.cells[task.cell].policy.connect_timeout_s;
        eval_cmd.arg(format!("--connect-timeout={timeout}"));
    }
    eval_cmd
        .stdin(Stdio::null())
        .stdout(eval_log.try_clone()?)
        .stderr(eval_log);
    die_with_parent(&mut eval_cmd);
    Ok(eval_cmd)
}

/// Starts the cell's policy command in its own process group (so the whole group can be
/// stopped), its output in `policy.log`; the inner `Err` says why it could not start.
fn start_policy(
    plan: &Plan,
    command: &str,
    session: &str,
    tdir: &TaskDir,
) -> anyhow::Result<Result<Child, String>> {
    let line = policy_command_line(command, session)?;
    let log = tdir.create_log(TaskLog::Policy)?;
    Ok(shell_in_own_group(&line, &plan.workdir, log)?
        .spawn()
        .map_err(|e| format!("cannot start the policy command `{line}`: {e}")))
}

/// How an evaluation ended.
pub(super) enum EvalEnd {
    Exited(ExitStatus),
    /// The launched policy exited while the evaluation still ran (it was stopped).
    PolicyGone(ExitStatus),
}

/// Waits for the evaluation; if the policy process exits first and the evaluation has
/// not ended 3 s later (it waits for a policy that will not come), stops it.
pub(super) fn wait_eval(
    eval: &mut Child,
    mut policy: Option<&mut Child>,
) -> anyhow::Result<EvalEnd> {
    let mut policy_exit: Option<(ExitStatus, Instant)> = None;
    loop {
        if let Some(s) = eval.try_wait()? {
            return Ok(EvalEnd::Exited(s));
        }
        if let (Some(p), None) = (policy.as_deref_mut(), policy_exit) {
            if let Some(s) = p.try_wait()? {
                policy_exit = Some((s, Instant::now()));
            }
        }
        if let Some((s, at)) = policy_exit {
            if at.elapsed() > Duration::from_secs(3) {
                let _ = eval.kill();
                let _ = eval.wait();
                return Ok(EvalEnd::PolicyGone(s));
            }
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

pub(super) fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

pub(super) fn env_usize(name: &str) -> anyhow::Result<Option<usize>> {
    match std::env::var(name) {
        Ok(v) if !v.is_empty() => {
            Ok(Some(v.trim().parse().with_context(|| {
                format!("${name} = `{v}` is not a task index")
            })?))
        }
        _ => Ok(None),
    }
}

pub(super) fn task(args: &TaskArgs) -> anyhow::Result<()> {
    let index = match args.index {
        Some(i) => i,
        None => env_usize("SLURM_ARRAY_TASK_ID")?
            .or(env_usize("JOB_COMPLETION_INDEX")?)
            .context(
                "no task index: give --index I, or run under a Slurm array \
                 (SLURM_ARRAY_TASK_ID) or a Kubernetes Indexed Job (JOB_COMPLETION_INDEX)",
            )?,
    };
    let plan = Plan::load(&args.dir)?;
    let workers = match args.workers {
        Some(0) => bail!("--workers must be at least 1"),
        Some(w) => w,
        None => env_usize("SLURM_CPUS_PER_TASK")?.unwrap_or_else(cores),
    };
    match run_task(&args.dir, &plan, index, workers)? {
        Outcome::Done => {
            println!("task {index}: done");
            Ok(())
        }
        Outcome::AlreadyDone => {
            println!("task {index}: already done, skipped");
            Ok(())
        }
        Outcome::Failed(reason) => bail!(
            "task {index} failed: {reason} (details: {})",
            TaskDir::of(&args.dir, index).failed_file().display()
        ),
    }
}
