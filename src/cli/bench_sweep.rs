//! `thorarena bench sweep`: what running a sweep as tasks costs next to running the same
//! episodes directly — `sweep run --jobs N` against one `eval --workers N` per
//! (policy, dataset, latency rule) with all the sweep's settings, timed in the same
//! invocation — and how long planning and a status census take for a sweep of thousands
//! of tasks (`thorarena::perf::SweepBench`).

use std::path::PathBuf;
use thorarena::perf::SweepBench;

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

/// `bench sweep`: the library times each round and hands over each line as it is
/// measured.
pub(super) fn run(args: &Args) -> anyhow::Result<()> {
    let bench = SweepBench {
        exe: std::env::current_exe()?,
        spec: args.spec.clone(),
        jobs: args.jobs,
        repeats: args.repeats,
        plan_tasks: args.plan_tasks,
    };
    bench.run(&mut super::bench_eval::print)?;
    Ok(())
}
