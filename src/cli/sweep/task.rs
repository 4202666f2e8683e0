//! One task: a child `thorarena eval` (and a launched policy process), its lock, and the
//! records that say it is done or why it failed.

use super::verify::{check_task_run, RunProblem};
use super::TaskArgs;
use anyhow::{bail, Context};
use std::fs::File;
use std::io::Write;
use std::os::unix::process::CommandExt;
use std::path::Path;
use std::process::{Child, Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};
use thorarena::motion::Dataset;
use thorarena::results::RunDir;
use thorarena::sweep::{
    log_tail as log_tail_of, printable, shell_quote, task_state, truncated, DoneRecord,
    FailedRecord, Plan, Task, TaskState, LOG_LINE_MAX_BYTES, LOG_TAIL_MAX_BYTES,
};
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
    let tdir = Plan::task_dir(dir, index);
    std::fs::create_dir_all(&tdir).with_context(|| format!("creating {}", tdir.display()))?;
    // One copy at a time; a second one waits, then finds the task done.
    let lock = lock_task(&tdir)?;
    if let TaskState::Done(_) = task_state(dir, index)? {
        return Ok(Outcome::AlreadyDone);
    }
    let _ = std::fs::remove_file(tdir.join("failed.json"));
    let started = Instant::now();
    let fail = |reason: String, logs: &[&str]| record_failure(&tdir, index, reason, logs);

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
    let run_dir = tdir.join("run");
    let mut eval_cmd = eval_command(task, &session, &run_dir, workers, &tdir)?;
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
                &["policy.log", "eval.log"],
            )
        }
    };
    if !eval_status.success() {
        return fail(
            format!("thorarena eval failed ({eval_status})"),
            &["eval.log", "policy.log"],
        );
    }
    // Complete, this task's, and on disk before it counts as done: `eval` exits 0 when
    // a dying policy cut short every episode still in flight.
    let records = match check_task_run(plan, task, &run_dir)? {
        Ok(records) => records,
        Err(RunProblem::Incomplete(why)) => {
            return fail(
                format!("{why}; `sweep run` again resumes the task"),
                &["eval.log", "policy.log"],
            )
        }
        Err(RunProblem::NotThisTask(why)) => {
            return fail(
                format!("{why}; remove {} and run the task again", run_dir.display()),
                &["eval.log"],
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
    write_atomic(
        &tdir.join("done.json"),
        serde_json::to_string_pretty(&done)?.as_bytes(),
    )?;
    drop(lock);
    Ok(Outcome::Done)
}

/// Records why the task failed in `failed.json`, with the tails of its `logs` (bounded
/// and printable however much, and whatever, the processes wrote).
fn record_failure(
    tdir: &Path,
    index: usize,
    reason: String,
    logs: &[&str],
) -> anyhow::Result<Outcome> {
    let reason = truncated(&printable(&reason), LOG_LINE_MAX_BYTES);
    let mut log_tail = Vec::new();
    let mut budget = LOG_TAIL_MAX_BYTES;
    for name in logs {
        let mut lines = log_tail_of(&tdir.join(name), 12);
        let mut bytes: usize = lines.iter().map(String::len).sum();
        while bytes > budget {
            bytes -= lines.remove(0).len();
        }
        if !lines.is_empty() {
            budget -= bytes;
            log_tail.push(format!("--- {name}"));
            log_tail.extend(lines);
        }
    }
    let record = FailedRecord {
        task: index,
        reason: reason.clone(),
        log_tail,
    };
    write_atomic(
        &tdir.join("failed.json"),
        serde_json::to_string_pretty(&record)?.as_bytes(),
    )?;
    Ok(Outcome::Failed(reason))
}

/// The task's `eval` process: the plan's arguments into `run_dir`, resuming, its output
/// in `eval.log`, dying with this process.
fn eval_command(
    task: &Task,
    session: &str,
    run_dir: &Path,
    workers: usize,
    tdir: &Path,
) -> anyhow::Result<Command> {
    let eval_log = create_log(&tdir.join("eval.log"))?;
    let mut eval_cmd = Command::new(std::env::current_exe()?);
    eval_cmd
        .args(task.eval_argv(session))
        .arg("--out")
        .arg(run_dir)
        .args(["--resume", "--workers", &workers.to_string()])
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
    tdir: &Path,
) -> anyhow::Result<Result<Child, String>> {
    let line = policy_command_line(command, session)?;
    let log = create_log(&tdir.join("policy.log"))?;
    let mut c = Command::new("sh");
    c.args(["-c", &line])
        .current_dir(&plan.workdir)
        .stdin(Stdio::null())
        .stdout(log.try_clone()?)
        .stderr(log)
        .process_group(0);
    die_with_parent(&mut c);
    Ok(c.spawn()
        .map_err(|e| format!("cannot start the policy command `{line}`: {e}")))
}

/// A policy command with its placeholders filled in as single shell words: the binary's
/// path and the session are data, whatever characters they hold (`$(…)` in a directory
/// name is not run).
pub(super) fn policy_command_line(command: &str, session: &str) -> anyhow::Result<String> {
    let exe = std::env::current_exe()?;
    let exe = exe.to_str().with_context(|| {
        format!(
            "{}: not UTF-8, which `{{thorarena}}` cannot name",
            exe.display()
        )
    })?;
    Ok(command
        .replace("{session}", &shell_quote(session))
        .replace("{thorarena}", &shell_quote(exe)))
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

/// A child that is killed when the thread that started it dies (a `sweep run` killed
/// with SIGKILL leaves no evaluation writing behind it).
pub(super) fn die_with_parent(cmd: &mut Command) {
    // SAFETY: prctl is async-signal-safe and touches only the calling (child) process.
    unsafe {
        cmd.pre_exec(|| {
            if libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
}

/// Ends a launched policy's whole process group: SIGTERM, then SIGKILL after 2 s.
pub(super) fn stop_group(child: &mut Child) {
    let pgid = child.id() as libc::pid_t;
    // SAFETY: signalling a process group we created.
    unsafe { libc::kill(-pgid, libc::SIGTERM) };
    let deadline = Instant::now() + Duration::from_secs(2);
    while Instant::now() < deadline {
        if matches!(child.try_wait(), Ok(Some(_))) {
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    // SAFETY: as above; the group may already be gone.
    unsafe { libc::kill(-pgid, libc::SIGKILL) };
    let _ = child.wait();
}

/// An exclusive advisory lock on `tdir/lock`, waiting for another holder to finish.
pub(super) fn lock_task(tdir: &Path) -> anyhow::Result<File> {
    let path = tdir.join("lock");
    let file = File::create(&path).with_context(|| format!("creating {}", path.display()))?;
    use std::os::fd::AsRawFd;
    loop {
        // SAFETY: flock on a descriptor we own.
        if unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX) } == 0 {
            return Ok(file);
        }
        let e = std::io::Error::last_os_error();
        if e.kind() != std::io::ErrorKind::Interrupted {
            return Err(e).with_context(|| format!("locking {}", path.display()));
        }
    }
}

/// A task's log file, created (truncated) for an attempt; the error names it.
fn create_log(path: &Path) -> anyhow::Result<File> {
    File::create(path).with_context(|| format!("creating {}", path.display()))
}

/// Writes `bytes` to `path` through a temporary sibling, synced and renamed; the
/// temporary file is removed if any step fails (a full disk leaves nothing behind).
pub(super) fn write_atomic(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    let tmp = path.with_extension(format!("tmp-{}", std::process::id()));
    let written = (|| -> std::io::Result<()> {
        let mut f = File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if let Err(e) = written {
        let _ = std::fs::remove_file(&tmp);
        return Err(e).with_context(|| format!("writing {}", path.display()));
    }
    if let Some(parent) = path.parent() {
        if let Ok(d) = File::open(parent) {
            let _ = d.sync_all();
        }
    }
    Ok(())
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
            Plan::task_dir(&args.dir, index)
                .join("failed.json")
                .display()
        ),
    }
}
