//! Workers without a coordinator, for policies that act on the workers
//! ([`Policy::worker_copies`]: the networks in process).
//!
//! Each worker owns its slots and its own copy of the policy, and loops on its own: apply
//! the last actions and step the physics, start the next jobs in free slots, ask its copy
//! for its slots' actions in one batch. No worker ever waits for another (the lock-step
//! loop's per-step barrier made the whole machine wait for the slowest worker's step,
//! every step), so the run costs what the slowest worker's physics and inference cost.
//! Finished episodes go to the calling thread over a channel as they end.
//!
//! Records are those of the lock-step loop: an episode's actions come from its own
//! observations through a copy of the same policy, whichever worker runs it.

use super::lockstep::{answer_to_commands, Finished, Shared, SlotCommand, SlotReport, WorkerSlots};
use super::RunOutcome;
use crate::eval::episode::EpisodeTrace;
use crate::eval::{EpisodeRecord, LatencyRecorder};
use crate::policy::{ActOutcome, Observation, Policy};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// What a worker sends while it runs.
enum Progress {
    /// An episode ended on worker `worker`.
    Finished {
        worker: usize,
        finished: Box<Finished>,
    },
    /// The worker ran out of jobs; its copy's `act` calls, timed.
    Done { latency: LatencyRecorder },
}

/// Runs `shared.jobs` over `n_slots` slots, worker `w` owning slots `w, w + W, …` and
/// acting with `copies[w]` (W = `copies.len()`).
pub(super) fn run(
    shared: &Shared,
    n_slots: usize,
    copies: Vec<Box<dyn Policy + Send>>,
    on_record: &mut dyn FnMut(&EpisodeRecord, Option<&EpisodeTrace>),
) -> RunOutcome {
    let n_workers = copies.len();
    let mut results: Vec<Option<EpisodeRecord>> = vec![None; shared.jobs_len()];
    let mut latency = LatencyRecorder::default();
    let mut physics_wall_by_worker = vec![Duration::ZERO; n_workers];
    std::thread::scope(|scope| {
        let (tx, rx) = mpsc::channel::<Progress>();
        for (w, copy) in copies.into_iter().enumerate() {
            let slots: Vec<usize> = (w..n_slots).step_by(n_workers).collect();
            let tx = tx.clone();
            scope.spawn(move || worker(shared, w, slots, copy, tx));
        }
        drop(tx);
        // Ends when every worker has hung up.
        for progress in rx {
            match progress {
                Progress::Finished { worker, finished } => {
                    physics_wall_by_worker[worker] += finished.physics_wall;
                    on_record(&finished.record, finished.trace.as_ref());
                    results[finished.job] = Some(finished.record);
                }
                Progress::Done { latency: l } => latency.merge(&l),
            }
        }
    });
    let records: Vec<EpisodeRecord> = results.into_iter().flatten().collect();
    RunOutcome {
        not_run: shared.jobs_len() - records.len(),
        records,
        latency: latency.summary(),
        transport: None,
        physics_wall_by_worker,
    }
}

/// One worker's loop, until no job is left and none of its slots runs an episode.
fn worker<'a>(
    shared: &'a Shared<'a>,
    w: usize,
    slots: Vec<usize>,
    mut policy: Box<dyn Policy + Send>,
    tx: mpsc::Sender<Progress>,
) {
    let mut mine = WorkerSlots::new(shared.plan, slots);
    let n = mine.slots.len();
    let mut commands: Vec<SlotCommand> = (0..n).map(|_| SlotCommand::Idle).collect();
    let mut latency = LatencyRecorder::default();
    loop {
        let mut out = Vec::with_capacity(n);
        for (k, command) in commands.iter_mut().enumerate() {
            let command = std::mem::replace(command, SlotCommand::Idle);
            let mut report = mine.advance(shared, k, command, Some(policy.as_mut()));
            for finished in report.finished.drain(..) {
                if tx
                    .send(Progress::Finished {
                        worker: w,
                        finished: Box::new(finished),
                    })
                    .is_err()
                {
                    return; // the caller is gone
                }
            }
            out.push(report);
        }
        let Some(acted) = act_here(policy.as_mut(), &mut out) else {
            break; // no slot has an episode: the schedule is exhausted
        };
        latency.record(acted.took);
        answer_to_commands(
            shared.plan,
            acted.outcome,
            acted.took,
            &acted.observations,
            &acted.actions,
            &mut commands,
            |slot| mine.index_of(slot),
        );
    }
    let _ = tx.send(Progress::Done { latency });
}

/// A worker's policy copy's answer for its slots.
struct Acted {
    observations: Vec<Observation>,
    actions: Vec<Vec<f64>>,
    outcome: ActOutcome,
    /// The `act` call.
    took: Duration,
}

/// The worker's policy copy acts on its slots' observations (taken out of `out`) in one
/// batch; `None` when no slot has one.
fn act_here(policy: &mut dyn Policy, out: &mut [SlotReport]) -> Option<Acted> {
    let observations: Vec<Observation> = out
        .iter_mut()
        .filter_map(|r| r.observation.take())
        .collect();
    if observations.is_empty() {
        return None;
    }
    for o in observations.iter().filter(|o| o.step == 0) {
        policy.reset(o.env);
    }
    let n_joints = observations[0].q.len();
    let mut actions = vec![vec![0.0; n_joints]; observations.len()];
    let started = Instant::now();
    let outcome = policy.act(&observations, &mut actions);
    let took = policy
        .last_round_trip()
        .unwrap_or_else(|| started.elapsed());
    Some(Acted {
        observations,
        actions,
        outcome,
        took,
    })
}
