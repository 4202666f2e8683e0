//! `thorarena bench sweep` as one call: rounds of a sweep run as tasks against the same
//! episodes run directly, alternating which goes first, with the median ratio over the
//! rounds; then planning, a status census and collecting for a sweep of thousands of
//! tasks. Everything it writes is in one scratch directory, gone when it ends.

use super::{time_sweep_at_scale, time_sweep_round, BenchLine, PerfError, ScratchDir};
use std::path::PathBuf;

/// The sweep / direct wall-time ratio the sweep is held to.
const GOAL_RATIO: f64 = 1.05;

/// `bench sweep` as asked for.
#[derive(Debug, Clone)]
pub struct SweepBench {
    /// This binary: the sweeps and evaluations timed are its own commands.
    pub exe: PathBuf,
    /// The sweep spec (`None`: `sweeps/sample.toml` of the checkout).
    pub spec: Option<PathBuf>,
    /// Tasks at a time, and the direct runs' workers.
    pub jobs: usize,
    /// Rounds; each times both.
    pub repeats: usize,
    /// About this many tasks for the planning, status and collect timings (0: skip them).
    pub plan_tasks: usize,
}

impl SweepBench {
    /// Checks the request, then times each round and the large sweep, handing each line
    /// to `say` as it is measured.
    pub fn run(&self, say: &mut dyn FnMut(BenchLine)) -> Result<(), PerfError> {
        if self.jobs == 0 || self.repeats == 0 {
            return Err(PerfError::Precondition(
                "`option.jobs` and `option.repeats` must be at least 1".into(),
            ));
        }
        let spec = self.spec.clone().unwrap_or_else(|| {
            PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/sweeps/sample.toml"))
        });
        let scratch_dir = ScratchDir::new("bench-sweep");
        let scratch = scratch_dir.path();
        let j = self.jobs;
        let mut ratios = Vec::new();
        for round in 0..self.repeats {
            let t = time_sweep_round(&self.exe, &spec, scratch, round, j)?;
            // The two commands timed, as `own_command` runs them.
            say(BenchLine::Figure(format!(
                "round {round}: sweep run --jobs {j}: {:.2} s ({} tasks, {} episodes); {} × eval --workers {j} on the same episodes: {:.2} s; ratio {:.3}",
                t.sweep_s,
                t.tasks,
                t.episodes,
                t.evals,
                t.evals_s,
                t.ratio(),
            )));
            ratios.push(t.ratio());
        }
        ratios.sort_by(f64::total_cmp);
        say(BenchLine::Figure(format!(
            "sweep / eval wall time: median {:.3} over {} round(s) (goal ≤ {GOAL_RATIO})",
            ratios[ratios.len() / 2],
            ratios.len()
        )));
        if self.plan_tasks > 0 {
            // The first round's two shards of its first cell stand in for every task of
            // the large sweep when timing `collect` (rewritten to each task's setting and
            // policy).
            let first_round = scratch.join("sweep-0");
            let t = time_sweep_at_scale(&self.exe, scratch, self.plan_tasks, &first_round)?;
            say(BenchLine::Figure(format!(
                "a sweep of {} tasks: plan {:.2} s, status {:.2} s (every task done, its run checked), collect {:.2} s ({} episodes read and checked, each task's run written from a real run of its shard)",
                t.tasks, t.plan_s, t.status_s, t.collect_s, t.episodes
            )));
        }
        Ok(())
    }
}
