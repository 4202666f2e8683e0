//! `thorarena sweep …`: plan a sweep from a spec, run its tasks (locally N at a time, or
//! one per process on a Slurm array or a Kubernetes Indexed Job), show its status, and
//! collect the cells into one comparison.
//!
//! A task is one `thorarena eval` process with the plan's exact arguments and
//! `--out DIR/tasks/<I>/run --resume`, so a sweep's episodes are those of separate `eval`
//! runs bit for bit, a killed task resumes, and shards merge with `merge`'s rules. A task
//! is marked done (`done.json`, atomic rename) only after its run holds every planned
//! episode and is flushed to disk; an advisory lock on `tasks/<I>/lock`, held by the task
//! and inherited by its eval process, keeps two copies of one task from running at once.

use super::merge::read_shards;
use super::run_output::{sort_records, write_header, write_results};
use crate::motion::Dataset;
use crate::sweep::{
    compact_ranges, diff_plans, task_state, DatasetInfo, DoneRecord, FailedRecord, Plan, SweepSpec,
    Task, TaskState, PLAN_FILE,
};
use anyhow::{bail, Context};
use clap::Parser;
use std::collections::{BTreeMap, VecDeque};
use std::fs::File;
use std::io::{BufRead, Write};
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// `thorarena sweep …`
#[derive(Debug, clap::Subcommand)]
pub enum SweepCommand {
    /// Validate a sweep spec and write its plan (cells, numbered tasks, exact eval
    /// arguments) into a sweep directory. Planning the same spec again is a no-op; a
    /// changed spec against an existing plan is refused with what changed.
    Plan(PlanArgs),
    /// Run every task that is not done, N at a time, with a progress bar over the sweep.
    Run(RunArgs),
    /// Run exactly one task (the index defaults to SLURM_ARRAY_TASK_ID, else
    /// JOB_COMPLETION_INDEX): skipped when done, resumed when half-done.
    Task(TaskArgs),
    /// Done, failed and not-started tasks, failure reasons, and the not-done set as a
    /// Slurm --array expression.
    Status(StatusArgs),
    /// Write DIR/slurm/sweep.sbatch, an array job over the not-done tasks; --submit hands
    /// it to sbatch.
    Slurm(SlurmArgs),
    /// Write DIR/k8s/job.yaml, a Kubernetes Indexed Job over all tasks.
    K8s(K8sArgs),
    /// Merge each cell's shards and write DIR/results.csv and DIR/report.html.
    Collect(CollectArgs),
}

/// Arguments of `sweep plan`.
#[derive(Debug, clap::Args)]
pub struct PlanArgs {
    /// The sweep spec (TOML; see sweeps/*.toml).
    pub spec: PathBuf,
    /// The sweep directory (created; on every node of a cluster it must be the same
    /// path, on a shared file system).
    #[arg(long)]
    pub out: PathBuf,
}

/// Arguments of `sweep run`.
#[derive(Debug, clap::Args)]
pub struct RunArgs {
    /// The sweep directory.
    pub dir: PathBuf,
    /// Tasks at a time [default: the cores]; each task's eval gets cores / jobs workers.
    #[arg(long)]
    pub jobs: Option<usize>,
}

/// Arguments of `sweep task`.
#[derive(Debug, clap::Args)]
pub struct TaskArgs {
    /// The sweep directory.
    pub dir: PathBuf,
    /// Task index [default: $SLURM_ARRAY_TASK_ID, else $JOB_COMPLETION_INDEX].
    #[arg(long)]
    pub index: Option<usize>,
    /// Worker threads of the evaluation [default: $SLURM_CPUS_PER_TASK, else all cores].
    #[arg(long)]
    pub workers: Option<usize>,
}

/// Arguments of `sweep status`.
#[derive(Debug, clap::Args)]
pub struct StatusArgs {
    /// The sweep directory.
    pub dir: PathBuf,
}

/// Arguments of `sweep slurm`.
#[derive(Debug, clap::Args)]
pub struct SlurmArgs {
    /// The sweep directory.
    pub dir: PathBuf,
    /// Slurm partition.
    #[arg(long)]
    pub partition: Option<String>,
    /// Time limit per task, in Slurm's syntax (e.g. `01:00:00`).
    #[arg(long)]
    pub time: Option<String>,
    /// CPUs per task (the evaluation's worker threads).
    #[arg(long, default_value_t = 1)]
    pub cpus_per_task: usize,
    /// At most this many tasks at once (`%K` of --array).
    #[arg(long)]
    pub max_parallel: Option<usize>,
    /// The thorarena binary the nodes run [default: this one; it must exist at that path
    /// on every node].
    #[arg(long)]
    pub thorarena: Option<PathBuf>,
    /// Submit with sbatch.
    #[arg(long)]
    pub submit: bool,
    /// With --submit: return when the array has finished; non-zero if a task failed.
    #[arg(long, requires = "submit")]
    pub wait: bool,
}

/// Arguments of `sweep k8s`.
#[derive(Debug, clap::Args)]
pub struct K8sArgs {
    /// The sweep directory.
    pub dir: PathBuf,
    /// Container image with `thorarena` on its PATH.
    #[arg(long)]
    pub image: String,
    /// PersistentVolumeClaim holding the sweep directory and its datasets, mounted at the
    /// same absolute paths as here.
    #[arg(long)]
    pub claim: String,
    /// Path inside the claim's volume that is mounted [default: the volume root].
    #[arg(long)]
    pub sub_path: Option<String>,
    /// Pods at once [default: all tasks].
    #[arg(long)]
    pub parallelism: Option<usize>,
    /// CPUs per pod (request and the evaluation's workers).
    #[arg(long, default_value_t = 1)]
    pub cpus_per_task: usize,
}

/// Arguments of `sweep collect`.
#[derive(Debug, clap::Args)]
pub struct CollectArgs {
    /// The sweep directory.
    pub dir: PathBuf,
    /// Collect although some cells are unfinished; their rows say how many episodes
    /// they hold.
    #[arg(long)]
    pub partial: bool,
}

/// Runs a sweep subcommand.
pub(super) fn run(cmd: &SweepCommand) -> anyhow::Result<()> {
    match cmd {
        SweepCommand::Plan(a) => plan(a),
        SweepCommand::Run(a) => run_all(a),
        SweepCommand::Task(a) => task(a),
        SweepCommand::Status(a) => status(a),
        SweepCommand::Slurm(a) => slurm(a),
        SweepCommand::K8s(a) => k8s(a),
        SweepCommand::Collect(a) => collect(a),
    }
}

// ---------------------------------------------------------------------------------------
// plan

fn plan(args: &PlanArgs) -> anyhow::Result<()> {
    let spec_path = std::fs::canonicalize(&args.spec)
        .with_context(|| format!("reading the sweep spec {}", args.spec.display()))?;
    let spec = SweepSpec::load(&spec_path)?;
    let base = spec_path.parent().unwrap_or(Path::new("/"));
    let robot = super::load_robot(&spec.robot).context("`robot` of the sweep spec")?;
    let mut datasets = Vec::new();
    for d in &spec.datasets {
        let dir = std::fs::canonicalize(base.join(d)).with_context(|| {
            format!(
                "`datasets`: {d} (relative to {}) does not exist",
                base.display()
            )
        })?;
        let ds = Dataset::open(&dir, &robot).with_context(|| format!("`datasets`: {d}"))?;
        let sequences = ds.load_all().with_context(|| format!("`datasets`: {d}"))?;
        if sequences.is_empty() {
            bail!("`datasets`: {d} holds no sequence");
        }
        datasets.push(DatasetInfo {
            dir,
            sha256: ds.content_hash(),
            durations_s: sequences.iter().map(|s| s.duration_s()).collect(),
        });
    }
    let plan = Plan::expand(&spec, &spec_path, &datasets)?;
    validate(&plan)?;

    let plan_path = args.out.join(PLAN_FILE);
    if plan_path.exists() {
        let existing = Plan::load(&args.out)?;
        match diff_plans(&existing, &plan) {
            None => {
                println!(
                    "{} already holds this plan: nothing to do ({})",
                    args.out.display(),
                    plan_summary(&plan)
                );
                return Ok(());
            }
            Some(change) => bail!(
                "{} holds another plan ({change}); tasks may be running under its numbering, so it is not replaced: plan into a new directory",
                args.out.display()
            ),
        }
    }
    std::fs::create_dir_all(args.out.join("tasks"))
        .with_context(|| format!("creating {}", args.out.display()))?;
    write_atomic(&plan_path, serde_json::to_string(&plan)?.as_bytes())?;
    println!(
        "planned {} into {}",
        plan_summary(&plan),
        args.out.display()
    );
    Ok(())
}

fn plan_summary(plan: &Plan) -> String {
    let s = plan.simulated_s();
    format!(
        "{} cells, {} tasks, {} episodes, {:.0} simulated s ({:.2} h)",
        plan.cells.len(),
        plan.tasks.len(),
        plan.episodes(),
        s,
        s / 3600.0
    )
}

/// Checks every cell's evaluation before anything is written: its arguments parse as
/// `eval`'s, its profile and keypoint set exist for the robot, its setting parses, and
/// each network file loads.
fn validate(plan: &Plan) -> anyhow::Result<()> {
    use std::collections::HashSet;
    let mut checked: HashSet<String> = HashSet::new();
    for task in plan.tasks.iter().filter(|t| t.shard.0 == 0) {
        let cell = &plan.cells[task.cell];
        let args = eval_cli(task, "plan-check")
            .with_context(|| format!("cell {} (policy `{}`)", cell.index, cell.policy.name))?;
        if crate::runner::Setting::parse(&cell.setting).is_none() {
            bail!(
                "cell {}: setting `{}` is not force, no-force, a number or push:<N>",
                cell.index,
                cell.setting
            );
        }
        // Loading the dataset, profile and keypoints once per combination keeps planning
        // a sweep of thousands of cells fast.
        let key = format!(
            "{}|{}|{}|{}",
            cell.policy.policy,
            cell.policy.profile,
            cell.policy.keypoints,
            cell.dataset.display()
        );
        if !checked.insert(key) {
            continue;
        }
        let ctx = super::eval::EvalContext::load(&args.run)
            .with_context(|| format!("cell {} (policy `{}`)", cell.index, cell.policy.name))?;
        if cell.policy.command.is_none() && checked.insert(format!("policy|{}", cell.policy.policy))
        {
            super::policy_arg::make_policy(
                &cell.policy.policy,
                &ctx.robot,
                &ctx.profile,
                &args.run.io,
                1,
            )
            .with_context(|| format!("policy `{}`", cell.policy.name))?;
        }
    }
    Ok(())
}

/// A task's `eval` arguments as `eval` parses them (`session` fills `{session}`).
fn eval_cli(task: &Task, session: &str) -> anyhow::Result<super::eval::Args> {
    let argv = std::iter::once("thorarena".to_string()).chain(
        task.eval_args
            .iter()
            .map(|a| a.replace("{session}", session)),
    );
    match super::Cli::try_parse_from(argv) {
        Ok(super::Cli {
            command: super::Command::Eval(a),
        }) => Ok(a),
        Ok(_) => bail!("not an eval command"),
        Err(e) => bail!("{}", e.render().to_string().trim()),
    }
}

// ---------------------------------------------------------------------------------------
// one task

/// What became of one attempt at a task.
#[derive(Debug)]
enum Outcome {
    /// Finished now.
    Done,
    /// It was done before.
    AlreadyDone,
    /// Failed; `failed.json` says why.
    Failed(String),
}

/// Runs task `index` of `plan` in sweep directory `dir` with `workers` threads.
fn run_task(dir: &Path, plan: &Plan, index: usize, workers: usize) -> anyhow::Result<Outcome> {
    let task = plan
        .tasks
        .get(index)
        .with_context(|| format!("task {index}: the plan has tasks 0..{}", plan.tasks.len()))?;
    let cell = &plan.cells[task.cell];
    let tdir = Plan::task_dir(dir, index);
    std::fs::create_dir_all(&tdir).with_context(|| format!("creating {}", tdir.display()))?;
    // One copy at a time; a second one waits, then finds the task done.
    let lock = lock_task(&tdir)?;
    if let TaskState::Done(_) = task_state(dir, index)? {
        return Ok(Outcome::AlreadyDone);
    }
    let _ = std::fs::remove_file(tdir.join("failed.json"));
    let started = Instant::now();
    let fail = |reason: String, logs: &[&str]| -> anyhow::Result<Outcome> {
        let mut log_tail = Vec::new();
        for name in logs {
            let lines = tail(&tdir.join(name), 12);
            if !lines.is_empty() {
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
    };

    // The dataset must be the one planned.
    let robot = super::load_robot(&plan_robot(task))?;
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
    let eval_log = File::create(tdir.join("eval.log"))?;
    let mut eval_cmd = Command::new(std::env::current_exe()?);
    eval_cmd
        .args(
            task.eval_args
                .iter()
                .map(|a| a.replace("{session}", &session)),
        )
        .arg("--out")
        .arg(&run_dir)
        .args(["--resume", "--workers", &workers.to_string()])
        .stdin(Stdio::null())
        .stdout(eval_log.try_clone()?)
        .stderr(eval_log);
    die_with_parent(&mut eval_cmd);

    let mut policy: Option<Child> = None;
    if let Some(command) = &cell.policy.command {
        let exe = std::env::current_exe()?;
        let line = command
            .replace("{session}", &session)
            .replace("{thorarena}", &exe.display().to_string());
        let log = File::create(tdir.join("policy.log"))?;
        let mut c = Command::new("sh");
        c.args(["-c", &line])
            .current_dir(&plan.workdir)
            .stdin(Stdio::null())
            .stdout(log.try_clone()?)
            .stderr(log)
            .process_group(0);
        die_with_parent(&mut c);
        match c.spawn() {
            Ok(child) => policy = Some(child),
            Err(e) => {
                return fail(
                    format!("cannot start the policy command `{line}`: {e}"),
                    &[],
                )
            }
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
    // Complete and on disk before it counts as done.
    let episodes_path = run_dir.join("episodes.jsonl");
    let (records, _) = crate::runner::read_records(&episodes_path)
        .with_context(|| format!("reading {}", episodes_path.display()))?;
    if records.len() != task.episodes {
        return fail(
            format!(
                "the run holds {} episodes, the plan {}",
                records.len(),
                task.episodes
            ),
            &["eval.log"],
        );
    }
    for name in ["episodes.jsonl", "run.json", "summary.json", "tables.md"] {
        let path = run_dir.join(name);
        File::open(&path)
            .and_then(|f| f.sync_all())
            .with_context(|| format!("flushing {}", path.display()))?;
    }
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

/// The robot named in a task's arguments.
fn plan_robot(task: &Task) -> String {
    task.eval_args
        .iter()
        .position(|a| a == "--robot")
        .and_then(|i| task.eval_args.get(i + 1))
        .cloned()
        .unwrap_or_else(|| "g1_29dof".into())
}

/// How an evaluation ended.
enum EvalEnd {
    Exited(ExitStatus),
    /// The launched policy exited while the evaluation still ran (it was stopped).
    PolicyGone(ExitStatus),
}

/// Waits for the evaluation; if the policy process exits first and the evaluation has
/// not ended 3 s later (it waits for a policy that will not come), stops it.
fn wait_eval(eval: &mut Child, mut policy: Option<&mut Child>) -> anyhow::Result<EvalEnd> {
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
fn die_with_parent(cmd: &mut Command) {
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
fn stop_group(child: &mut Child) {
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
fn lock_task(tdir: &Path) -> anyhow::Result<File> {
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

/// Writes `bytes` to `path` through a temporary sibling, synced and renamed.
fn write_atomic(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    let tmp = path.with_extension(format!("tmp-{}", std::process::id()));
    let mut f = File::create(&tmp).with_context(|| format!("creating {}", tmp.display()))?;
    f.write_all(bytes)?;
    f.sync_all()?;
    std::fs::rename(&tmp, path).with_context(|| format!("writing {}", path.display()))?;
    if let Some(parent) = path.parent() {
        if let Ok(d) = File::open(parent) {
            let _ = d.sync_all();
        }
    }
    Ok(())
}

/// The last `n` non-empty lines of a log file.
fn tail(path: &Path, n: usize) -> Vec<String> {
    let Ok(f) = File::open(path) else {
        return Vec::new();
    };
    let lines: Vec<String> = std::io::BufReader::new(f)
        .lines()
        .map_while(Result::ok)
        .map(|l| l.rsplit('\r').next().unwrap_or("").trim_end().to_string())
        .filter(|l| !l.is_empty())
        .collect();
    lines[lines.len().saturating_sub(n)..].to_vec()
}

fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

fn env_usize(name: &str) -> anyhow::Result<Option<usize>> {
    match std::env::var(name) {
        Ok(v) if !v.is_empty() => {
            Ok(Some(v.trim().parse().with_context(|| {
                format!("${name} = `{v}` is not a task index")
            })?))
        }
        _ => Ok(None),
    }
}

fn task(args: &TaskArgs) -> anyhow::Result<()> {
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

// ---------------------------------------------------------------------------------------
// the local pool

fn run_all(args: &RunArgs) -> anyhow::Result<()> {
    let plan = Arc::new(Plan::load(&args.dir)?);
    let jobs = match args.jobs {
        Some(0) => bail!("--jobs must be at least 1"),
        Some(j) => j,
        None => cores(),
    };
    let workers = (cores() / jobs).max(1);
    let mut pending = VecDeque::new();
    let mut done_episodes = 0usize;
    for t in &plan.tasks {
        match task_state(&args.dir, t.index)? {
            TaskState::Done(_) => done_episodes += t.episodes,
            _ => pending.push_back(t.index),
        }
    }
    let to_run = pending.len();
    eprintln!(
        "sweep {}: {} of {} tasks to run, {jobs} at a time, {workers} worker(s) each",
        args.dir.display(),
        to_run,
        plan.tasks.len()
    );
    let queue = Arc::new(Mutex::new(pending));
    let running: Arc<Mutex<Vec<usize>>> = Arc::new(Mutex::new(Vec::new()));
    let results: Arc<Mutex<Vec<TaskResult>>> = Arc::new(Mutex::new(Vec::new()));
    let handles: Vec<_> = (0..jobs.min(to_run.max(1)))
        .map(|_| {
            let (queue, running, results, plan) = (
                queue.clone(),
                running.clone(),
                results.clone(),
                plan.clone(),
            );
            let dir = args.dir.clone();
            std::thread::spawn(move || loop {
                let Some(i) = queue.lock().expect("queue").pop_front() else {
                    return;
                };
                running.lock().expect("running").push(i);
                let r = run_task(&dir, &plan, i, workers).map_err(|e| format!("{e:#}"));
                running.lock().expect("running").retain(|&x| x != i);
                results.lock().expect("results").push((i, r));
            })
        })
        .collect();

    let bar = indicatif::ProgressBar::new(plan.episodes() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{bar:40} {pos}/{len} episodes  {elapsed} elapsed, ~{eta} left  {msg}",
        )
        .expect("valid template"),
    );
    loop {
        let finished = handles.iter().all(|h| h.is_finished());
        let (mut episodes, mut failed, mut tasks_done) = (done_episodes, 0usize, 0usize);
        for (i, r) in results.lock().expect("results").iter() {
            match r {
                Ok(Outcome::Done | Outcome::AlreadyDone) => {
                    episodes += plan.tasks[*i].episodes;
                    tasks_done += 1;
                }
                _ => failed += 1,
            }
        }
        for &i in running.lock().expect("running").iter() {
            episodes += count_lines(&Plan::task_dir(&args.dir, i).join("run/episodes.jsonl"));
        }
        bar.set_position(episodes as u64);
        bar.set_message(format!(
            "tasks: {tasks_done}/{to_run} done, {failed} failed"
        ));
        if finished {
            break;
        }
        std::thread::sleep(Duration::from_millis(250));
    }
    bar.finish_and_clear();
    for h in handles {
        h.join()
            .map_err(|_| anyhow::anyhow!("a task thread panicked"))?;
    }
    let results = results.lock().expect("results");
    let failures: Vec<String> = results
        .iter()
        .filter_map(|(i, r)| match r {
            Ok(Outcome::Failed(reason)) => Some(format!("task {i}: {reason}")),
            Err(e) => Some(format!("task {i}: {e}")),
            _ => None,
        })
        .collect();
    eprintln!(
        "sweep {}: {} tasks run, {} failed",
        args.dir.display(),
        results.len(),
        failures.len()
    );
    if !failures.is_empty() {
        for f in &failures {
            eprintln!("  {f}");
        }
        bail!(
            "{} task(s) failed; `thorarena sweep status {}` shows why, `sweep run` again retries them",
            failures.len(),
            args.dir.display()
        );
    }
    Ok(())
}

/// A task index and how its attempt ended (an error is the sweep's, not the task's).
type TaskResult = (usize, Result<Outcome, String>);

fn count_lines(path: &Path) -> usize {
    std::fs::read(path)
        .map(|b| b.iter().filter(|&&c| c == b'\n').count())
        .unwrap_or(0)
}

// ---------------------------------------------------------------------------------------
// status

/// Tasks by state: (done, failed with reasons, started, not started).
struct Census {
    done: Vec<usize>,
    failed: Vec<FailedRecord>,
    started: Vec<usize>,
    not_started: Vec<usize>,
}

fn census(dir: &Path, plan: &Plan) -> anyhow::Result<Census> {
    let mut c = Census {
        done: Vec::new(),
        failed: Vec::new(),
        started: Vec::new(),
        not_started: Vec::new(),
    };
    for t in &plan.tasks {
        match task_state(dir, t.index)? {
            TaskState::Done(_) => c.done.push(t.index),
            TaskState::Failed(f) => c.failed.push(f),
            TaskState::Started => c.started.push(t.index),
            TaskState::NotStarted => c.not_started.push(t.index),
        }
    }
    Ok(c)
}

impl Census {
    fn not_done(&self) -> Vec<usize> {
        let mut v: Vec<usize> = self.failed.iter().map(|f| f.task).collect();
        v.extend(&self.started);
        v.extend(&self.not_started);
        v.sort_unstable();
        v
    }
}

fn status(args: &StatusArgs) -> anyhow::Result<()> {
    let plan = Plan::load(&args.dir)?;
    let c = census(&args.dir, &plan)?;
    println!(
        "{}: {} tasks — {} done, {} failed, {} started (running or interrupted), {} not started",
        args.dir.display(),
        plan.tasks.len(),
        c.done.len(),
        c.failed.len(),
        c.started.len(),
        c.not_started.len()
    );
    for f in &c.failed {
        let cell = &plan.cells[plan.tasks[f.task].cell];
        println!(
            "failed: task {} (cell {}, policy `{}`, setting `{}`): {}",
            f.task, cell.index, cell.policy.name, cell.setting, f.reason
        );
        for l in &f.log_tail {
            println!("    {l}");
        }
    }
    let not_done = c.not_done();
    if not_done.is_empty() {
        println!("not done: none");
    } else {
        println!("not done (--array): {}", compact_ranges(&not_done));
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------
// cluster engines

fn absolute(p: &Path) -> anyhow::Result<PathBuf> {
    std::fs::canonicalize(p).with_context(|| format!("{} does not exist", p.display()))
}

fn slurm(args: &SlurmArgs) -> anyhow::Result<()> {
    let plan = Plan::load(&args.dir)?;
    let dir = absolute(&args.dir)?;
    if args.cpus_per_task == 0 {
        bail!("--cpus-per-task must be at least 1");
    }
    let not_done = census(&dir, &plan)?.not_done();
    if not_done.is_empty() {
        println!("every task of {} is done: nothing to submit", dir.display());
        return Ok(());
    }
    let exe = match &args.thorarena {
        Some(p) => absolute(p)?,
        None => std::env::current_exe()?,
    };
    let sdir = dir.join("slurm");
    std::fs::create_dir_all(sdir.join("logs"))?;
    let mut array = compact_ranges(&not_done);
    if let Some(k) = args.max_parallel {
        if k == 0 {
            bail!("--max-parallel must be at least 1");
        }
        array += &format!("%{k}");
    }
    let mut s = String::from("#!/bin/bash\n");
    s += "# ThorArena sweep: one array task per sweep task (`thorarena sweep task`).\n";
    s += "# Generated by `thorarena sweep slurm`; the sweep directory and the datasets must\n";
    s += "# be at the same paths on every node (a shared file system).\n";
    s += "#SBATCH --job-name=thorarena-sweep\n";
    s += &format!("#SBATCH --array={array}\n");
    s += &format!("#SBATCH --cpus-per-task={}\n", args.cpus_per_task);
    s += &format!(
        "#SBATCH --output={}\n",
        sdir.join("logs/task-%a.log").display()
    );
    if let Some(p) = &args.partition {
        s += &format!("#SBATCH --partition={p}\n");
    }
    if let Some(t) = &args.time {
        s += &format!("#SBATCH --time={t}\n");
    }
    s += &format!(
        "exec {} sweep task {}\n",
        shell_quote(&exe.display().to_string()),
        shell_quote(&dir.display().to_string())
    );
    let script = sdir.join("sweep.sbatch");
    std::fs::write(&script, &s).with_context(|| format!("writing {}", script.display()))?;
    println!(
        "wrote {} ({} tasks: --array={array})",
        script.display(),
        not_done.len()
    );
    if !args.submit {
        println!("submit with: sbatch {}", script.display());
        return Ok(());
    }
    let mut cmd = Command::new("sbatch");
    if args.wait {
        cmd.arg("--wait");
    }
    let status = cmd
        .arg(&script)
        .status()
        .context("running sbatch (is Slurm's client installed and configured?)")?;
    if !status.success() {
        let c = census(&dir, &plan)?;
        bail!(
            "sbatch {}: {status}; {} task(s) failed, {} not done (`thorarena sweep status {}`)",
            if args.wait { "--wait" } else { "" },
            c.failed.len(),
            c.not_done().len(),
            dir.display()
        );
    }
    if args.wait {
        let c = census(&dir, &plan)?;
        if !c.not_done().is_empty() {
            bail!(
                "the array finished with {} task(s) not done: {}",
                c.not_done().len(),
                compact_ranges(&c.not_done())
            );
        }
        println!("all {} tasks done", plan.tasks.len());
    }
    Ok(())
}

fn shell_quote(s: &str) -> String {
    if s.chars()
        .all(|c| c.is_ascii_alphanumeric() || "/._-+=:,".contains(c))
    {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', "'\\''"))
    }
}

/// A YAML scalar: JSON's string syntax is YAML's double-quoted style.
fn yaml_str(s: &str) -> String {
    serde_json::to_string(s).expect("a string serializes")
}

/// The Indexed Job manifest running every task of `plan` (done ones are skipped by
/// `sweep task` itself, so the manifest never needs regenerating).
pub(crate) fn k8s_manifest(
    plan: &Plan,
    dir: &Path,
    image: &str,
    claim: &str,
    sub_path: Option<&str>,
    parallelism: usize,
    cpus: usize,
) -> String {
    let name = format!(
        "thorarena-sweep-{}",
        &sha_hex(dir.display().to_string().as_bytes())[..10]
    );
    let n = plan.tasks.len();
    let mount = dir.display().to_string();
    let mut y = String::new();
    y += "# ThorArena sweep as a Kubernetes Indexed Job: pod I runs `thorarena sweep task DIR`\n";
    y += "# with JOB_COMPLETION_INDEX = I. The claim holds the sweep directory, mounted at the\n";
    y += "# same absolute path as where it was planned (datasets likewise).\n";
    y += "apiVersion: batch/v1\nkind: Job\nmetadata:\n";
    y += &format!("  name: {name}\n");
    y += "spec:\n  completionMode: Indexed\n";
    y += &format!("  completions: {n}\n  parallelism: {parallelism}\n");
    y += &format!("  backoffLimitPerIndex: 2\n  maxFailedIndexes: {n}\n");
    y += "  template:\n    spec:\n      restartPolicy: Never\n      containers:\n";
    y += "        - name: task\n";
    y += &format!("          image: {}\n", yaml_str(image));
    y += &format!(
        "          command: [{}, {}, {}, {}, {}, {}]\n",
        yaml_str("thorarena"),
        yaml_str("sweep"),
        yaml_str("task"),
        yaml_str(&mount),
        yaml_str("--workers"),
        yaml_str(&cpus.to_string())
    );
    y += &format!(
        "          resources:\n            requests:\n              cpu: {}\n",
        yaml_str(&cpus.to_string())
    );
    y += "          volumeMounts:\n            - name: sweep\n";
    y += &format!("              mountPath: {}\n", yaml_str(&mount));
    if let Some(sp) = sub_path {
        y += &format!("              subPath: {}\n", yaml_str(sp));
    }
    y += "      volumes:\n        - name: sweep\n          persistentVolumeClaim:\n";
    y += &format!("            claimName: {}\n", yaml_str(claim));
    y
}

fn sha_hex(bytes: &[u8]) -> String {
    use sha2::{Digest, Sha256};
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

fn k8s(args: &K8sArgs) -> anyhow::Result<()> {
    let plan = Plan::load(&args.dir)?;
    let dir = absolute(&args.dir)?;
    if args.cpus_per_task == 0 {
        bail!("--cpus-per-task must be at least 1");
    }
    let parallelism = args.parallelism.unwrap_or(plan.tasks.len());
    if parallelism == 0 {
        bail!("--parallelism must be at least 1");
    }
    let y = k8s_manifest(
        &plan,
        &dir,
        &args.image,
        &args.claim,
        args.sub_path.as_deref(),
        parallelism,
        args.cpus_per_task,
    );
    let kdir = dir.join("k8s");
    std::fs::create_dir_all(&kdir)?;
    let path = kdir.join("job.yaml");
    std::fs::write(&path, y).with_context(|| format!("writing {}", path.display()))?;
    println!(
        "wrote {} ({} tasks); run with: kubectl apply -f {}",
        path.display(),
        plan.tasks.len(),
        path.display()
    );
    Ok(())
}

// ---------------------------------------------------------------------------------------
// collect

/// What a cell's collected run holds.
struct CellResult {
    dir: PathBuf,
    episodes: usize,
    complete: bool,
    summary: serde_json::Value,
    /// Summed over shards: deadline misses, invalid actions, policy failures.
    faults: [u64; 3],
    /// p50, p99, p99.9 µs of a single-shard cell (shards keep separate histograms).
    latency_us: Option<[f64; 3]>,
}

fn collect(args: &CollectArgs) -> anyhow::Result<()> {
    let plan = Plan::load(&args.dir)?;
    let c = census(&args.dir, &plan)?;
    let done: std::collections::HashSet<usize> = c.done.iter().copied().collect();
    let mut by_cell: BTreeMap<usize, Vec<&Task>> = BTreeMap::new();
    for t in &plan.tasks {
        by_cell.entry(t.cell).or_default().push(t);
    }
    let unfinished: Vec<usize> = by_cell
        .iter()
        .filter(|(_, ts)| ts.iter().any(|t| !done.contains(&t.index)))
        .map(|(&c, _)| c)
        .collect();
    if !unfinished.is_empty() && !args.partial {
        bail!(
            "{} of {} cells are unfinished (cells {}; tasks not done: {}): run them, or collect with --partial",
            unfinished.len(),
            plan.cells.len(),
            compact_ranges(&unfinished),
            compact_ranges(&c.not_done())
        );
    }
    let robot = super::load_robot(&plan_robot(&plan.tasks[0]))?;
    let mut results: Vec<Option<CellResult>> = Vec::new();
    // Loaded once per dataset, however many cells share it.
    let mut datasets: BTreeMap<PathBuf, Vec<crate::motion::Sequence>> = BTreeMap::new();
    for cell in &plan.cells {
        let tasks = &by_cell[&cell.index];
        let runs: Vec<PathBuf> = tasks
            .iter()
            .filter(|t| done.contains(&t.index))
            .map(|t| Plan::task_dir(&args.dir, t.index).join("run"))
            .collect();
        if runs.is_empty() {
            results.push(None);
            continue;
        }
        let (mut header, by_key) = read_shards(&runs)?;
        header.shard = None;
        if !datasets.contains_key(&cell.dataset) {
            let ds = Dataset::open(&cell.dataset, &robot)?;
            datasets.insert(cell.dataset.clone(), ds.load_all()?);
        }
        let sequences = &datasets[&cell.dataset];
        let mut records: Vec<_> = by_key.into_values().collect();
        sort_records(&mut records, &header, sequences);
        let out = Plan::cell_dir(&args.dir, cell.index);
        std::fs::create_dir_all(&out)?;
        let mut w = std::io::BufWriter::new(File::create(out.join("episodes.jsonl"))?);
        for r in &records {
            crate::runner::write_record(&mut w, r)?;
        }
        w.flush()?;
        write_header(&out, &header)?;
        write_results(&out, &header, &records, sequences, None)?;
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json"))?)?;
        let mut faults = [0u64; 3];
        let mut latency_us = None;
        for run in &runs {
            let s: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(run.join("summary.json"))?)?;
            let io = &s["policy_io"];
            faults[0] += io["deadline_misses"].as_u64().unwrap_or(0);
            faults[1] += io["invalid_actions"].as_u64().unwrap_or(0);
            faults[2] += io["transport"]["policy_failures"].as_u64().unwrap_or(0);
            if runs.len() == 1 {
                let l = &io["latency"];
                latency_us = Some([
                    l["p50_us"].as_f64().unwrap_or(f64::NAN),
                    l["p99_us"].as_f64().unwrap_or(f64::NAN),
                    l["p999_us"].as_f64().unwrap_or(f64::NAN),
                ]);
            }
        }
        results.push(Some(CellResult {
            dir: out,
            episodes: records.len(),
            complete: records.len() == cell.episodes,
            summary,
            faults,
            latency_us,
        }));
    }
    let csv = results_csv(&plan, &results);
    let csv_path = args.dir.join("results.csv");
    std::fs::write(&csv_path, csv).with_context(|| format!("writing {}", csv_path.display()))?;
    let cell_dirs: Vec<PathBuf> = results.iter().flatten().map(|r| r.dir.clone()).collect();
    let report = args.dir.join("report.html");
    let runs = crate::report::load_runs(&cell_dirs)?;
    let charts = sweep_charts(&plan, &results);
    let script = crate::report::WebBundle::locate()?.script(crate::report::Page::Report)?;
    let html = crate::report::sweep_report_html(&runs, &charts, &script);
    std::fs::write(&report, html).with_context(|| format!("writing {}", report.display()))?;
    eprintln!(
        "collected {} cells{}: {} and {}",
        results.iter().flatten().count(),
        if unfinished.is_empty() {
            String::new()
        } else {
            format!(" ({} partial)", unfinished.len())
        },
        csv_path.display(),
        report.display()
    );
    Ok(())
}

/// Columns of `results.csv`, one row per cell (a cell has one setting).
const CSV_COLUMNS: [&str; 31] = [
    "cell",
    "policy",
    "dataset",
    "setting",
    "force_coefficient",
    "push_n",
    "latency_rule",
    "budget",
    "latency_mode",
    "miss_rule",
    "profile",
    "keypoints",
    "episodes",
    "episodes_expected",
    "complete",
    "fats",
    "survival",
    "kp_error_mm",
    "low_kp_mm",
    "high_kp_mm",
    "robustness_rho",
    "power_overhead_eta",
    "upper_kp_mm",
    "lower_kp_mm",
    "fats_std",
    "latency_p50_us",
    "latency_p99_us",
    "latency_p999_us",
    "deadline_misses",
    "invalid_actions",
    "policy_failures",
];

fn results_csv(plan: &Plan, results: &[Option<CellResult>]) -> String {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(CSV_COLUMNS).expect("in memory");
    let num = |v: Option<f64>| {
        v.filter(|x| x.is_finite())
            .map_or(String::new(), |x| x.to_string())
    };
    for (cell, r) in plan.cells.iter().zip(results) {
        let setting = crate::runner::Setting::parse(&cell.setting);
        let avg = r.as_ref().and_then(|r| {
            r.summary["settings"]
                .as_object()
                .and_then(|m| m.values().next())
                .map(|s| s["average"].clone())
        });
        let d = |key: &str| num(avg.as_ref().and_then(|a| a[key].as_f64()));
        let row = vec![
            cell.index.to_string(),
            cell.policy.name.clone(),
            cell.dataset.display().to_string(),
            cell.setting.clone(),
            num(setting.as_ref().map(|s| s.coefficient)),
            num(setting.as_ref().map(|s| s.push_n)),
            cell.latency.name.clone(),
            cell.latency.budget.clone(),
            cell.latency.mode.clone(),
            cell.latency.miss_rule.clone(),
            cell.policy.profile.clone(),
            cell.policy.keypoints.clone(),
            r.as_ref().map_or(0, |r| r.episodes).to_string(),
            cell.episodes.to_string(),
            r.as_ref().is_some_and(|r| r.complete).to_string(),
            d("fats"),
            d("survival"),
            d("kp_mm"),
            d("low_kp_mm"),
            d("high_kp_mm"),
            d("robustness"),
            d("power_overhead"),
            d("upper_kp_mm"),
            d("lower_kp_mm"),
            d("fats_std"),
            num(r.as_ref().and_then(|r| r.latency_us.map(|l| l[0]))),
            num(r.as_ref().and_then(|r| r.latency_us.map(|l| l[1]))),
            num(r.as_ref().and_then(|r| r.latency_us.map(|l| l[2]))),
            r.as_ref()
                .map_or(String::new(), |r| r.faults[0].to_string()),
            r.as_ref()
                .map_or(String::new(), |r| r.faults[1].to_string()),
            r.as_ref()
                .map_or(String::new(), |r| r.faults[2].to_string()),
        ];
        w.write_record(&row).expect("in memory");
    }
    String::from_utf8(w.into_inner().expect("in memory")).expect("UTF-8")
}

/// A latency budget (`5ms`, `500us`, `0.01s`) in ms; `None` for `none`.
fn budget_ms(budget: &str) -> Option<f64> {
    let (num, factor) = if let Some(n) = budget.strip_suffix("ms") {
        (n, 1.0)
    } else if let Some(n) = budget.strip_suffix("us").or(budget.strip_suffix("µs")) {
        (n, 1e-3)
    } else if let Some(n) = budget.strip_suffix('s') {
        (n, 1e3)
    } else {
        return None;
    };
    num.trim().parse::<f64>().ok().map(|v| v * factor)
}

/// The curves a sweep is for, from its cells' averages: FATS and survival against the
/// force coefficient (and against a constant push), one line per policy, and FATS against
/// the latency budget under `--latency-mode measured`. A quantity that takes fewer than
/// two values is not plotted; labels name only the axes that vary.
fn sweep_charts(plan: &Plan, results: &[Option<CellResult>]) -> Vec<crate::report::SweepChart> {
    use crate::report::{CurveSeries, SweepChart};
    use std::collections::BTreeSet;
    let varies = |f: &dyn Fn(&crate::sweep::Cell) -> String| {
        plan.cells.iter().map(f).collect::<BTreeSet<_>>().len() > 1
    };
    let many_datasets = varies(&|c| c.dataset.display().to_string());
    let many_latency = varies(&|c| c.latency.name.clone());
    let many_settings = varies(&|c| c.setting.clone());
    let label = |c: &crate::sweep::Cell, with_latency: bool, with_setting: bool| {
        let mut l = c.policy.name.clone();
        if many_datasets {
            l += &format!(
                " · {}",
                c.dataset
                    .file_name()
                    .map_or(String::new(), |n| n.to_string_lossy().into())
            );
        }
        if with_latency && many_latency {
            l += &format!(" · {}", c.latency.name);
        }
        if with_setting && many_settings {
            l += &format!(" · {}", c.setting);
        }
        l
    };
    // (cell, fats, survival) of every cell with results.
    let points: Vec<(&crate::sweep::Cell, f64, f64)> = plan
        .cells
        .iter()
        .zip(results)
        .filter_map(|(c, r)| {
            let avg = r.as_ref()?.summary["settings"]
                .as_object()?
                .values()
                .next()?["average"]
                .clone();
            Some((c, avg["fats"].as_f64()?, avg["survival"].as_f64()?))
        })
        .collect();
    // Lines of (label → sorted points) for the cells `x` maps to a value.
    let lines = |x: &dyn Fn(&crate::sweep::Cell) -> Option<f64>,
                 y: &dyn Fn(f64, f64) -> f64,
                 with_latency: bool,
                 with_setting: bool| {
        let mut by_label: BTreeMap<String, Vec<[f64; 2]>> = BTreeMap::new();
        let mut xs = BTreeSet::new();
        for &(c, fats, survival) in &points {
            if let Some(xv) = x(c) {
                xs.insert(xv.to_bits());
                by_label
                    .entry(label(c, with_latency, with_setting))
                    .or_default()
                    .push([xv, y(fats, survival)]);
            }
        }
        let series: Vec<CurveSeries> = by_label
            .into_iter()
            .map(|(label, mut points)| {
                points.sort_by(|a, b| a[0].total_cmp(&b[0]));
                CurveSeries { label, points }
            })
            .collect();
        (xs.len() >= 2).then_some(series)
    };
    let setting = |c: &crate::sweep::Cell| crate::runner::Setting::parse(&c.setting);
    let coefficient = |c: &crate::sweep::Cell| {
        setting(c)
            .filter(|s| s.push_n == 0.0)
            .map(|s| s.coefficient)
    };
    let push = |c: &crate::sweep::Cell| {
        setting(c)
            .filter(|s| s.coefficient == 0.0)
            .map(|s| s.push_n)
    };
    let budget = |c: &crate::sweep::Cell| {
        (c.latency.mode == "measured")
            .then(|| budget_ms(&c.latency.budget))
            .flatten()
    };
    let fats = |f: f64, _s: f64| f;
    let survival = |_f: f64, s: f64| s;
    let mut charts = Vec::new();
    let mut chart =
        |id: &str, title: &str, x_label: &str, y_label: &str, series: Option<Vec<CurveSeries>>| {
            if let Some(series) = series {
                charts.push(SweepChart {
                    id: id.into(),
                    title: title.into(),
                    x_label: x_label.into(),
                    y_label: y_label.into(),
                    series,
                });
            }
        };
    chart(
        "sweep-fats-vs-coefficient",
        "FATS against the force replay coefficient (0 = no force, 1 = the recorded forces)",
        "force replay coefficient",
        "FATS",
        lines(&coefficient, &fats, true, false),
    );
    chart(
        "sweep-survival-vs-coefficient",
        "Survival against the force replay coefficient",
        "force replay coefficient",
        "survival",
        lines(&coefficient, &survival, true, false),
    );
    if points
        .iter()
        .any(|(c, _, _)| push(c).is_some_and(|p| p > 0.0))
    {
        chart(
            "sweep-fats-vs-push",
            "FATS against a constant push on each hand",
            "push per hand (N)",
            "FATS",
            lines(&push, &fats, true, false),
        );
        chart(
            "sweep-survival-vs-push",
            "Survival against a constant push on each hand",
            "push per hand (N)",
            "survival",
            lines(&push, &survival, true, false),
        );
    }
    chart(
        "sweep-fats-vs-budget",
        "FATS against the latency budget (latency mode measured: the policy's latency delays its action)",
        "latency budget (ms)",
        "FATS",
        lines(&budget, &fats, false, true),
    );
    charts
}
