//! `thorarena bench eval` as one call: a whole evaluation of one policy — every
//! (sequence, setting) on every worker, nothing written — once per pipeline depth, the
//! policy in process or a process started afresh for each run; the first run against its
//! physics floor, the later ones against the first (wall time, and whether every record is
//! the same).

use super::timed_policy::TimedPolicy;
use super::{physics_floor, time_run, BenchLine, PerfError, RunTiming};
use crate::eval::{EvalRequest, EvalSpec};
use std::time::Duration;

/// `bench eval` as asked for.
#[derive(Debug, Clone)]
pub struct EvalBench {
    /// The evaluation to time (its `pipeline_depth` set per run from `pipeline_depths`);
    /// its `policy` runs in process, or is a command started afresh for each run.
    pub request: EvalRequest,
    /// Pipeline depths, one run each; the later runs are compared with the first.
    pub pipeline_depths: Vec<usize>,
}

impl EvalBench {
    /// Times one run per pipeline depth, handing its lines to `say` as each run ends (the
    /// spec's advice and each run's start as notes).
    pub fn run(&self, say: &mut dyn FnMut(BenchLine)) -> Result<(), PerfError> {
        if self.pipeline_depths.is_empty() {
            return Err(PerfError::Precondition(
                "`option.pipeline_depths`: give at least one depth".into(),
            ));
        }
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        let mut first: Option<(usize, RunTiming)> = None;
        for &depth in &self.pipeline_depths {
            let spec = self.spec(depth)?;
            for advice in &spec.advice {
                say(BenchLine::Note(advice.to_string()));
            }
            let (label, mut timed) =
                TimedPolicy::start(&self.request.policy, &spec, depth, &mut |note| {
                    say(BenchLine::Note(note.to_string()))
                })?;
            say(BenchLine::Note(format!(
                "timing {label} on {:?}: {} sequences × {} settings, {} workers, {} slots, pipeline depth {depth}, {cores} cores…",
                self.request.engine,
                spec.sequences.len(),
                spec.settings.len(),
                spec.workers,
                spec.envs
            )));
            let run = time_run(&spec, timed.policy());
            let policy_cpu = timed.cpu_time();
            drop(timed); // a process stops before the floor is timed
            for line in run_lines(&run, policy_cpu, cores, depth) {
                say(BenchLine::Figure(line));
            }
            match &first {
                None => {
                    let floor = physics_floor(&spec, run.physics_steps)?;
                    for line in floor_lines(&spec, &run, floor) {
                        say(BenchLine::Figure(line));
                    }
                    first = Some((depth, run));
                }
                Some((base_depth, base)) => {
                    say(BenchLine::Figure(versus_line(&run, *base_depth, base)))
                }
            }
        }
        Ok(())
    }

    /// The evaluation of the run at `pipeline_depth`.
    fn spec(&self, pipeline_depth: usize) -> Result<EvalSpec, PerfError> {
        let mut request = self.request.clone();
        request.pipeline_depth = pipeline_depth;
        Ok(EvalSpec::load(&request)?)
    }
}

/// A run's figures: episodes and steps, simulated seconds per wall second; the CPU it
/// took (a policy process's included) as a share of `cores`, and the policy's latency.
fn run_lines(
    run: &RunTiming,
    policy_cpu: Option<Duration>,
    cores: usize,
    depth: usize,
) -> [String; 2] {
    let cpu = run.cpu + policy_cpu.unwrap_or_default();
    let busy = cpu.as_secs_f64() / (run.wall.as_secs_f64() * cores as f64).max(f64::MIN_POSITIVE);
    let policy_part = policy_cpu
        .map(|c| format!(" (of it the policy process {:.2} s)", c.as_secs_f64()))
        .unwrap_or_default();
    [
        format!(
            "run (depth {depth}): {} episodes, {} control steps ({} physics steps), {:.1} s simulated in {:.2} s wall = {:.1} simulated s per wall s",
            run.episodes,
            run.control_steps,
            run.physics_steps,
            run.simulated_s,
            run.wall.as_secs_f64(),
            run.real_time_factor()
        ),
        format!(
            "       CPU {:.2} s{policy_part} = {:.0} % of {cores} cores busy; policy act p50 {:.0} µs per step",
            cpu.as_secs_f64(),
            100.0 * busy,
            run.act_p50_us
        ),
    ]
}

/// The first run against its physics floor: the slowest worker inside its physics steps
/// in the run, the same number of steps of a robot standing still (`floor`), and the
/// run's wall time over the first of them.
fn floor_lines(spec: &EvalSpec, run: &RunTiming, floor: Duration) -> [String; 3] {
    let floor_s = floor.as_secs_f64();
    let in_run = run.physics_wall_slowest_worker.as_secs_f64();
    let per_step_us = |s: f64| s * 1e6 * spec.workers as f64 / run.physics_steps.max(1) as f64;
    [
        format!(
            "floor: the slowest worker inside its physics steps in this run: {in_run:.2} s ({:.1} µs per step)",
            per_step_us(in_run)
        ),
        format!(
            "       the same {} steps of a robot standing still, on {} workers: {floor_s:.2} s ({:.1} µs per step)",
            run.physics_steps,
            spec.workers,
            per_step_us(floor_s)
        ),
        format!(
            "ratio: run / floor = {:.2} (1.00: the run costs what its physics costs)",
            run.wall.as_secs_f64() / in_run.max(f64::MIN_POSITIVE)
        ),
    ]
}

/// A later run against the first (at `base_depth`): wall-time ratio, and whether every
/// record is the same.
fn versus_line(run: &RunTiming, base_depth: usize, base: &RunTiming) -> String {
    format!(
        "versus depth {base_depth}: wall {:.2} s / {:.2} s = {:.2}; records {}",
        run.wall.as_secs_f64(),
        base.wall.as_secs_f64(),
        run.wall.as_secs_f64() / base.wall.as_secs_f64().max(f64::MIN_POSITIVE),
        if run.records_fingerprint == base.records_fingerprint {
            "identical"
        } else {
            "DIFFER"
        }
    )
}
