//! `thorarena bench sweep`: what running a sweep as tasks costs next to running the same
//! episodes directly — `sweep run --jobs N` against one `eval --workers N` per
//! (policy, dataset, latency rule) with all the sweep's settings, timed in the same
//! invocation — and how long planning and a status census take for a sweep of thousands
//! of tasks.

use anyhow::bail;
use std::path::PathBuf;
use thorarena::perf::{time_sweep_at_scale, time_sweep_round};

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
        let t = time_sweep_round(&exe, &spec, scratch, round, args.jobs)?;
        println!(
            "round {round}: sweep run --jobs {j}: {:.2} s ({} tasks, {} episodes); {} × eval --workers {j} on the same episodes: {:.2} s; ratio {:.3}",
            t.sweep_s,
            t.tasks,
            t.episodes,
            t.evals,
            t.evals_s,
            t.ratio(),
            j = args.jobs
        );
        ratios.push(t.ratio());
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
        let t = time_sweep_at_scale(&exe, scratch, args.plan_tasks, &scratch.join("sweep-0"))?;
        println!(
            "a sweep of {} tasks: plan {:.2} s, status {:.2} s (every task done, its run checked), collect {:.2} s ({} episodes read and checked, each task's run written from a real run of its shard)",
            t.tasks, t.plan_s, t.status_s, t.collect_s, t.episodes
        );
    }
    Ok(())
}
