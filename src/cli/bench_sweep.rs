//! `thorarena bench sweep`: what running a sweep as tasks costs next to running the same
//! episodes directly — `sweep run --jobs N` against one `eval --workers N` per
//! (policy, dataset, latency rule) with all the sweep's settings, timed in the same
//! invocation — and how long planning and a status census take for a sweep of thousands
//! of tasks.

use anyhow::{bail, Context};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;
use thorarena::sweep::{finish_with_shard_runs, write_large_spec, Plan, TaskDir};

/// Arguments of `bench sweep`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The sweep spec [default: sweeps/sample.toml of the checkout].
    #[arg(long)]
    pub spec: Option<PathBuf>,
    /// Tasks at a time (and the baseline's workers).
    #[arg(long, default_value_t = 2)]
    pub jobs: usize,
    /// Rounds; each times both, in alternating order.
    #[arg(long, default_value_t = 1)]
    pub repeats: usize,
    /// Also plan a sweep of about this many tasks over the bundled sample and time
    /// planning and `sweep status` (0: skip).
    #[arg(long, default_value_t = 10_000)]
    pub plan_tasks: usize,
}

pub(super) fn run(args: &Args) -> anyhow::Result<()> {
    if args.jobs == 0 || args.repeats == 0 {
        bail!("--jobs and --repeats must be at least 1");
    }
    let spec = args.spec.clone().unwrap_or_else(|| {
        PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/sweeps/sample.toml"))
    });
    let exe = std::env::current_exe()?;
    let scratch_dir = thorarena::perf::ScratchDir::new("bench-sweep");
    let scratch = scratch_dir.path();
    let mut ratios = Vec::new();
    for round in 0..args.repeats {
        let dir = scratch.join(format!("sweep-{round}"));
        run_ok(
            Command::new(&exe)
                .args(["sweep", "plan"])
                .arg(&spec)
                .arg("--out")
                .arg(&dir),
        )?;
        let plan = Plan::load(&dir)?;
        let baseline = baseline_commands(&plan, args.jobs, &scratch.join(format!("eval-{round}")))?;
        let time_sweep = || -> anyhow::Result<f64> {
            let t = Instant::now();
            run_ok(
                Command::new(&exe)
                    .args(["sweep", "run"])
                    .arg(&dir)
                    .args(["--jobs", &args.jobs.to_string()]),
            )?;
            Ok(t.elapsed().as_secs_f64())
        };
        let time_evals = || -> anyhow::Result<f64> {
            let t = Instant::now();
            for argv in &baseline {
                run_ok(Command::new(&exe).args(argv))?;
            }
            Ok(t.elapsed().as_secs_f64())
        };
        let (sweep_s, eval_s) = if round % 2 == 0 {
            let s = time_sweep()?;
            (s, time_evals()?)
        } else {
            let e = time_evals()?;
            (time_sweep()?, e)
        };
        let ratio = sweep_s / eval_s;
        println!(
            "round {round}: sweep run --jobs {j}: {sweep_s:.2} s ({} tasks, {} episodes); {} × eval --workers {j} on the same episodes: {eval_s:.2} s; ratio {ratio:.3}",
            plan.tasks.len(),
            plan.episodes(),
            baseline.len(),
            j = args.jobs
        );
        ratios.push(ratio);
    }
    ratios.sort_by(f64::total_cmp);
    println!(
        "sweep / eval wall time: median {:.3} over {} round(s) (goal ≤ 1.05)",
        ratios[ratios.len() / 2],
        ratios.len()
    );

    if args.plan_tasks > 0 {
        // The first round's two shards of its first cell stand in for every task of the
        // large sweep when timing `collect` (rewritten to each task's setting and policy).
        let first = scratch.join("sweep-0");
        let plan = Plan::load(&first)?;
        let shards: Vec<PathBuf> = plan
            .tasks
            .iter()
            .filter(|t| t.cell == 0)
            .map(|t| TaskDir::of(&first, t.index).run_dir())
            .collect();
        if shards.len() != 2 || plan.cells[0].episodes != 12 {
            bail!("--plan-tasks needs a spec whose first cell is 2 shards of the bundled sample (sweeps/sample.toml)");
        }
        plan_at_scale(
            &exe,
            scratch,
            args.plan_tasks,
            &plan.cells[0].dataset,
            &shards,
        )?;
    }
    Ok(())
}

/// One `eval` per (policy, dataset, latency rule) of the plan, with all its settings and
/// `workers` workers, writing under `out`.
fn baseline_commands(plan: &Plan, workers: usize, out: &Path) -> anyhow::Result<Vec<Vec<String>>> {
    let mut groups: Vec<(String, Vec<String>, Vec<String>)> = Vec::new();
    for task in plan.tasks.iter().filter(|t| t.shard.0 == 0) {
        let cell = &plan.cells[task.cell];
        if cell.policy.command.is_some() {
            bail!(
                "policy `{}` runs as a command: the baseline needs in-process policies",
                cell.policy.name
            );
        }
        let key = format!(
            "{}|{}|{:?}",
            cell.policy.name,
            cell.dataset.display(),
            cell.latency
        );
        match groups.iter_mut().find(|g| g.0 == key) {
            Some(g) => g.2.push(cell.setting.clone()),
            None => groups.push((key, task.eval_args.clone(), vec![cell.setting.clone()])),
        }
    }
    Ok(groups
        .into_iter()
        .enumerate()
        .map(|(i, (_, args, settings))| {
            // A plan's arguments are `--flag=value`, one argument each.
            let mut argv = Vec::new();
            for a in args {
                if a.starts_with("--settings=") {
                    argv.push(format!("--settings={}", settings.join(",")));
                } else if !a.starts_with("--shard=") {
                    argv.push(a);
                }
            }
            argv.extend([
                "--workers".into(),
                workers.to_string(),
                "--out".into(),
                out.join(i.to_string()).display().to_string(),
            ]);
            argv
        })
        .collect())
}

/// Plans ≈ `tasks` tasks (the sample × many force coefficients × 2 shards) and times the
/// plan, and `sweep status` and `collect` with every task finished — each task's run
/// written from `shards` (one real run of each shard), its header and records renamed to
/// the task's setting and policy, so `collect` reads, checks and merges as much as real
/// runs of that size, without simulating them.
fn plan_at_scale(
    exe: &Path,
    scratch: &Path,
    tasks: usize,
    sample: &Path,
    shards: &[PathBuf],
) -> anyhow::Result<()> {
    let spec = write_large_spec(scratch, sample, tasks, shards.len())?;
    let dir = scratch.join("large");
    let t = Instant::now();
    run_ok(
        Command::new(exe)
            .args(["sweep", "plan"])
            .arg(&spec)
            .arg("--out")
            .arg(&dir),
    )?;
    let plan_s = t.elapsed().as_secs_f64();
    let plan = Plan::load(&dir)?;
    let episodes = finish_with_shard_runs(&dir, shards)?;
    // With every task done, each run is read and checked: status's worst case.
    let t = Instant::now();
    run_ok(Command::new(exe).args(["sweep", "status"]).arg(&dir))?;
    let status_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    run_ok(Command::new(exe).args(["sweep", "collect"]).arg(&dir))?;
    let collect_s = t.elapsed().as_secs_f64();
    println!(
        "a sweep of {} tasks: plan {plan_s:.2} s, status {status_s:.2} s (every task done, its run checked), collect {collect_s:.2} s ({episodes} episodes read and checked, each task's run written from a real run of its shard)",
        plan.tasks.len()
    );
    Ok(())
}

fn run_ok(cmd: &mut Command) -> anyhow::Result<()> {
    let out = cmd.output().with_context(|| format!("running {cmd:?}"))?;
    if !out.status.success() {
        bail!("{cmd:?} failed:\n{}", String::from_utf8_lossy(&out.stderr));
    }
    Ok(())
}
