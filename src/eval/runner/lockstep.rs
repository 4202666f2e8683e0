//! The batched lock-step loop: N environment slots, one batch of observations per control
//! step handed to the policy on the coordinator thread (a policy process over shared
//! memory, or a built-in), the actions checked and applied, the slots' physics stepped on
//! worker threads.
//!
//! Slot `s` belongs to worker `s mod W`; a worker owns its slots' physics and episodes
//! ([`WorkerSlots`]) and, when a slot's episode ends, starts the next job of the schedule
//! in it. An episode's result depends only on its sequence, setting and policy — never on
//! which slot or worker ran it, nor on N or W — because a reset rebuilds the physics world
//! and every slot's episode sees only its own observations.
//!
//! With a pipeline depth of 2 the slots form two halves: the coordinator sends one half's
//! commands, then waits on the policy's answer for the other half while the workers step
//! the first, so the policy's time hides behind physics. One request is in flight at a
//! time; an episode sees the same observations and actions as in lock-step.
//!
//! A policy that offers copies of itself ([`Policy::worker_copies`], the networks in
//! process) needs no coordinator: [`super::free_running`] runs it, each worker stepping
//! and asking its own copy for its slots' actions without waiting for the others.

use super::EvalPlan;
use crate::eval::episode::{Episode, EpisodeSetup, EpisodeTrace};
use crate::eval::EvalSpec;
use crate::eval::{EpisodeRecord, LatencyMode, MissRule, PolicyFault, Termination};
use crate::eval::{LatencyRecorder, LatencySummary};
use crate::policy::{ActOutcome, Observation, Policy, TransportStats};
use crate::sim::motion::Sequence;
use crate::sim::physics::{make_physics, Physics, PhysicsSettings};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// What an evaluation produced.
#[derive(Debug, Clone)]
pub struct RunOutcome {
    /// Finished episodes, in job order.
    pub records: Vec<EpisodeRecord>,
    /// The policy's per-step latency (remote: observation published to actions received;
    /// in process: the `act` call).
    pub latency: LatencySummary,
    /// Transport counters of a remote policy.
    pub transport: Option<TransportStats>,
    /// Jobs that never ran because the policy failed and did not come back.
    pub not_run: usize,
    /// Per worker, the wall time its finished episodes spent inside physics steps: the
    /// slowest worker's is the least the run could have taken (`thorarena bench eval`).
    pub physics_wall_by_worker: Vec<Duration>,
}

/// What the coordinator tells a slot before the next observation.
pub(super) enum SlotCommand {
    /// No episode ran in the slot: just report.
    Idle,
    /// Apply this action for one control step.
    Act {
        action: Vec<f64>,
        effect_delay_substeps: usize,
        fault: Option<PolicyFault>,
    },
    /// End the episode now.
    Terminate {
        why: Termination,
        fault: Option<PolicyFault>,
    },
}

pub(super) struct Finished {
    pub(super) job: usize,
    /// Wall time the episode spent inside physics steps.
    pub(super) physics_wall: Duration,
    pub(super) record: EpisodeRecord,
    pub(super) trace: Option<EpisodeTrace>,
}

/// A slot's state after its command: the finished episode(s) and the next observation.
pub(super) struct SlotReport {
    pub(super) slot: usize,
    pub(super) observation: Option<Observation>,
    pub(super) finished: Vec<Finished>,
}

/// What every worker shares (read-only, or atomics).
pub(super) struct Shared<'a> {
    pub(super) plan: &'a EvalPlan<'a>,
    setups: &'a [EpisodeSetup<'a>],
    sequences: &'a [Sequence],
    jobs: &'a [(usize, usize)],
    policy_name: String,
    next_job: AtomicUsize,
    /// Jobs to run again from their start (cut short by a policy that then came back).
    retry: std::sync::Mutex<Vec<usize>>,
    stop: AtomicBool,
}

impl Shared<'_> {
    /// Jobs in the schedule.
    pub(super) fn jobs_len(&self) -> usize {
        self.jobs.len()
    }
}

/// One episode setup per setting of the plan, for a policy wanting reference frames at
/// `offsets` s ahead.
fn episode_setups<'a>(plan: &EvalPlan<'a>, offsets: Vec<f64>) -> Vec<EpisodeSetup<'a>> {
    let spec: &'a EvalSpec = plan.spec;
    let keypoints = spec
        .robot
        .keypoint_set(&spec.keypoints)
        .expect("keypoint set checked by the caller");
    spec.settings
        .iter()
        .map(|setting| {
            EpisodeSetup::for_setting(
                &spec.robot,
                &spec.profile,
                keypoints,
                spec.termination,
                setting,
                offsets.clone(),
            )
        })
        .collect()
}

/// What each observed slot does with the policy's answer: act on a usable action (after
/// the measured latency, under `--latency-mode measured`), apply the miss rule to an
/// unusable or late one, or end its episode when the policy failed.
pub(super) fn answer_to_commands(
    plan: &EvalPlan,
    outcome: ActOutcome,
    round_trip: std::time::Duration,
    observations: &[Observation],
    actions: &[Vec<f64>],
    commands: &mut [SlotCommand],
    index_of: impl Fn(usize) -> usize,
) {
    let effect_delay_substeps = match plan.spec.io.latency_mode {
        LatencyMode::Ignore => 0,
        LatencyMode::Measured => {
            (round_trip.as_secs_f64() / plan.spec.profile.physics_dt_s).round() as usize
        }
    };
    for (obs, action) in observations.iter().zip(actions) {
        commands[index_of(obs.env)] = match outcome {
            ActOutcome::Acted if action_is_usable(action, plan.spec.io.max_abs_action) => {
                SlotCommand::Act {
                    action: action.clone(),
                    effect_delay_substeps,
                    fault: None,
                }
            }
            ActOutcome::Acted => miss_rule(plan.spec.io.miss_rule, PolicyFault::InvalidAction, obs),
            ActOutcome::Missed => miss_rule(plan.spec.io.miss_rule, PolicyFault::DeadlineMiss, obs),
            ActOutcome::Failed => SlotCommand::Terminate {
                why: Termination::PolicyFailed,
                fault: None,
            },
        };
    }
}

/// Runs the given jobs (from [`crate::eval::schedule`]) with one policy over `plan.spec.envs` slots;
/// `on_record` sees each finished episode as it ends (stream it, count it).
pub fn run_eval(
    plan: &EvalPlan,
    sequences: &[Sequence],
    jobs: &[(usize, usize)],
    policy: &mut dyn Policy,
    on_record: &mut dyn FnMut(&EpisodeRecord, Option<&EpisodeTrace>),
) -> RunOutcome {
    let n_slots = plan.spec.envs.max(1);
    let n_workers = plan.spec.workers.clamp(1, n_slots);
    let setups = episode_setups(plan, policy.reference_offsets_s());
    let shared = Shared {
        plan,
        setups: &setups,
        sequences,
        jobs,
        policy_name: policy.name().to_string(),
        next_job: AtomicUsize::new(0),
        retry: std::sync::Mutex::new(Vec::new()),
        stop: AtomicBool::new(false),
    };
    if let Some(copies) = policy.worker_copies(n_workers) {
        return super::free_running::run(&shared, n_slots, copies, on_record);
    }
    let mut results: Vec<Option<EpisodeRecord>> = vec![None; jobs.len()];
    let mut latency = LatencyRecorder::default();
    let mut physics_wall_by_worker = vec![Duration::ZERO; n_workers];
    let groups = slot_groups(n_slots, plan.spec.pipeline_depth.max(1));

    std::thread::scope(|scope| {
        let mut pipe = Pipeline::start(scope, &shared, n_workers, n_slots, groups.len());

        let mut commands: Vec<SlotCommand> = (0..n_slots).map(|_| SlotCommand::Idle).collect();
        // Set once a failed policy has been replaced (`--on-policy-failure wait`).
        let mut requeue_failed = false;
        // Groups whose episodes the policy was answering when it failed in another group:
        // they end without asking it (a replacement must never continue them).
        let mut fails_unasked = vec![false; groups.len()];
        // Whether a group's last round had no episode running.
        let mut idle = vec![false; groups.len()];
        let mut actions: Vec<Vec<f64>> = Vec::new();
        for (g, group) in groups.iter().enumerate() {
            pipe.dispatch(g, group, &mut commands); // every slot takes its first job
        }
        // Group g's reports are collected, its policy call made and its commands sent
        // while the workers step the other group (the group sent last round).
        for g in (0..groups.len()).cycle() {
            let mut reports = pipe.collect(g);
            reports.sort_by_key(|r| r.slot);
            let mut observations = Vec::with_capacity(groups[g].len());
            for report in reports {
                for f in report.finished {
                    physics_wall_by_worker[report.slot % n_workers] += f.physics_wall;
                    policy.episode_ended(report.slot, f.record.termination.is_some());
                    if requeue_failed && f.record.termination == Some(Termination::PolicyFailed) {
                        // The policy came back: the episode it left runs again from its
                        // start, as `--resume` would run it, instead of being scored.
                        shared.retry.lock().expect("retry queue").push(f.job);
                        continue;
                    }
                    on_record(&f.record, f.trace.as_ref());
                    results[f.job] = Some(f.record);
                }
                observations.extend(report.observation);
            }
            if observations.is_empty() {
                fails_unasked[g] = false;
                idle[g] = true;
                let retrying = !shared.retry.lock().expect("retry queue").is_empty()
                    && !shared.stop.load(Ordering::SeqCst);
                if retrying {
                    pipe.dispatch(g, &groups[g], &mut commands); // its slots take the jobs to run again
                } else if idle.iter().all(|i| *i) && pipe.replies_due.iter().all(|d| *d == 0) {
                    break; // every job ran (or the policy failed for good)
                }
                continue;
            }
            idle[g] = false;
            if std::mem::take(&mut fails_unasked[g]) {
                // The policy failed while answering the other group: end these episodes
                // as it would have ended them.
                for o in &observations {
                    commands[o.env] = SlotCommand::Terminate {
                        why: Termination::PolicyFailed,
                        fault: None,
                    };
                }
            } else {
                let outcome = ask_policy(
                    plan,
                    policy,
                    &observations,
                    &mut actions,
                    &mut commands,
                    &mut latency,
                );
                if outcome == ActOutcome::Failed {
                    for (other, fails) in fails_unasked.iter_mut().enumerate() {
                        *fails = other != g && !idle[other];
                    }
                    if policy.recover() {
                        requeue_failed = true;
                    } else {
                        shared.stop.store(true, Ordering::SeqCst);
                    }
                }
            }
            pipe.dispatch(g, &groups[g], &mut commands);
        }
        drop(pipe); // the workers' loops end
    });

    let records: Vec<EpisodeRecord> = results.into_iter().flatten().collect();
    RunOutcome {
        not_run: jobs.len() - records.len(),
        records,
        latency: latency.summary(),
        transport: policy.transport_stats(),
        physics_wall_by_worker,
    }
}

/// One policy call for a group's `observations` (a slot starting its episode reset
/// first), its round trip recorded and its answers turned into the slots' commands.
fn ask_policy(
    plan: &EvalPlan,
    policy: &mut dyn Policy,
    observations: &[Observation],
    actions: &mut Vec<Vec<f64>>,
    commands: &mut [SlotCommand],
    latency: &mut LatencyRecorder,
) -> ActOutcome {
    for o in observations.iter().filter(|o| o.step == 0) {
        policy.reset(o.env);
    }
    let n_joints = plan.spec.robot.n_joints();
    actions.resize_with(observations.len(), || vec![0.0; n_joints]);
    let started = Instant::now();
    let outcome = policy.act(observations, &mut actions[..observations.len()]);
    let round_trip = policy
        .last_round_trip()
        .unwrap_or_else(|| started.elapsed());
    latency.record(round_trip);
    answer_to_commands(
        plan,
        outcome,
        round_trip,
        observations,
        actions,
        commands,
        |slot| slot,
    );
    outcome
}

/// Finite and within the plan's bound: safe to hand to the physics.
fn action_is_usable(action: &[f64], max_abs: f64) -> bool {
    action.iter().all(|a| a.is_finite() && a.abs() <= max_abs)
}

/// The command for a slot whose action is missing or unusable.
fn miss_rule(rule: MissRule, fault: PolicyFault, obs: &Observation) -> SlotCommand {
    match rule {
        MissRule::Hold => SlotCommand::Act {
            action: obs.last_action.clone(),
            effect_delay_substeps: 0,
            fault: Some(fault),
        },
        MissRule::Zero => SlotCommand::Act {
            action: vec![0.0; obs.last_action.len()],
            effect_delay_substeps: 0,
            fault: Some(fault),
        },
        MissRule::Fail => SlotCommand::Terminate {
            why: fault.termination(),
            fault: Some(fault),
        },
    }
}

/// A worker of the lock-step loop: applies the commands of its slots in one group (local
/// slot index, command), starts new jobs in free slots, reports their observations to the
/// coordinator under the group's number.
fn worker(
    shared: &Shared,
    slots: Vec<usize>,
    commands: mpsc::Receiver<GroupCommands>,
    reports: mpsc::Sender<(usize, Vec<SlotReport>)>,
) {
    let mut mine = WorkerSlots::new(shared.plan, slots);
    while let Ok((group, batch)) = commands.recv() {
        let out = batch
            .into_iter()
            .map(|(k, command)| mine.advance(shared, k, command, None))
            .collect();
        if reports.send((group, out)).is_err() {
            return;
        }
    }
}

/// The slots in `depth` contiguous groups of (nearly) equal size: with slot `s` on worker
/// `s mod W`, each group spans the workers as evenly as the counts allow.
fn slot_groups(n_slots: usize, depth: usize) -> Vec<Vec<usize>> {
    let depth = depth.clamp(1, n_slots.max(1));
    (0..depth)
        .map(|g| (g * n_slots / depth..(g + 1) * n_slots / depth).collect())
        .collect()
}

/// A group's commands to one worker: (group, [(local slot index, command)]).
type GroupCommands = (usize, Vec<(usize, SlotCommand)>);

/// The coordinator's channels to the workers, and the groups' reports on their way.
struct Pipeline {
    n_workers: usize,
    command_txs: Vec<mpsc::Sender<GroupCommands>>,
    report_rx: mpsc::Receiver<(usize, Vec<SlotReport>)>,
    /// Per group, the workers that have not answered its last dispatch.
    replies_due: Vec<usize>,
    /// Per group, reports that arrived while another group's were awaited.
    reports: Vec<Vec<SlotReport>>,
}

impl Pipeline {
    /// Starts `n_workers` workers in `scope`, worker `w` owning slots `w`, `w + n_workers`,
    /// … of `n_slots`, and the pipeline of `n_groups` slot groups that drives them.
    fn start<'scope>(
        scope: &'scope std::thread::Scope<'scope, '_>,
        shared: &'scope Shared<'_>,
        n_workers: usize,
        n_slots: usize,
        n_groups: usize,
    ) -> Self {
        let (report_tx, report_rx) = mpsc::channel::<(usize, Vec<SlotReport>)>();
        let mut command_txs = Vec::with_capacity(n_workers);
        for w in 0..n_workers {
            let (command_tx, command_rx) = mpsc::channel::<GroupCommands>();
            command_txs.push(command_tx);
            let report_tx = report_tx.clone();
            let slots: Vec<usize> = (w..n_slots).step_by(n_workers).collect();
            scope.spawn(move || worker(shared, slots, command_rx, report_tx));
        }
        Self {
            n_workers,
            command_txs,
            report_rx,
            replies_due: vec![0; n_groups],
            reports: (0..n_groups).map(|_| Vec::new()).collect(),
        }
    }

    /// Sends group `g`'s commands (taken from `commands`, leaving `Idle`) to the workers
    /// that own its slots.
    fn dispatch(&mut self, g: usize, group: &[usize], commands: &mut [SlotCommand]) {
        let mut per_worker: Vec<Vec<(usize, SlotCommand)>> =
            (0..self.n_workers).map(|_| Vec::new()).collect();
        for &slot in group {
            let command = std::mem::replace(&mut commands[slot], SlotCommand::Idle);
            per_worker[slot % self.n_workers].push((slot / self.n_workers, command));
        }
        for (w, batch) in per_worker.into_iter().enumerate() {
            if !batch.is_empty() {
                self.command_txs[w].send((g, batch)).expect("worker alive");
                self.replies_due[g] += 1;
            }
        }
    }

    /// Group `g`'s reports, once every worker it was sent to has answered.
    fn collect(&mut self, g: usize) -> Vec<SlotReport> {
        while self.replies_due[g] > 0 {
            let (from, reports) = self.report_rx.recv().expect("worker alive");
            self.reports[from].extend(reports);
            self.replies_due[from] -= 1;
        }
        std::mem::take(&mut self.reports[g])
    }
}

/// A worker's environment slots: their physics worlds and running episodes.
pub(super) struct WorkerSlots<'a> {
    /// Global slot indices, ascending.
    pub(super) slots: Vec<usize>,
    physics: Vec<Box<dyn Physics + Send>>,
    running: Vec<Option<(usize, Episode<'a>)>>,
}

impl<'a> WorkerSlots<'a> {
    pub(super) fn new(plan: &EvalPlan, slots: Vec<usize>) -> Self {
        let robot = Arc::new(plan.spec.robot.clone());
        let settings = PhysicsSettings {
            dt_s: plan.spec.profile.physics_dt_s,
            ..Default::default()
        };
        let physics = slots
            .iter()
            .map(|_| {
                make_physics(
                    &plan.spec.engine,
                    robot.clone(),
                    settings.clone(),
                    plan.spec.profile.gains.clone(),
                )
                .expect("the engine was checked before the run (EvalPlan::engine)")
            })
            .collect();
        let running = slots.iter().map(|_| None).collect();
        Self {
            slots,
            physics,
            running,
        }
    }

    /// The local index of global slot `slot`.
    pub(super) fn index_of(&self, slot: usize) -> usize {
        self.slots
            .binary_search(&slot)
            .expect("an observation of one of this worker's slots")
    }

    /// Applies local slot `k`'s command, collects its episode if that ended, starts the
    /// next jobs of the schedule in it while it is free, and reports its next observation.
    /// `local`, the worker's own policy copy, hears of the ended episodes before it sees
    /// the slot's next observation, as the coordinator's policy would.
    pub(super) fn advance(
        &mut self,
        shared: &'a Shared<'a>,
        k: usize,
        command: SlotCommand,
        local: Option<&mut dyn Policy>,
    ) -> SlotReport {
        let plan = shared.plan;
        let mut finished = Vec::new();
        if let Some((job, ep)) = self.running[k].as_mut() {
            match command {
                SlotCommand::Idle => {}
                SlotCommand::Act {
                    action,
                    effect_delay_substeps,
                    fault,
                } => {
                    if let Some(f) = fault {
                        ep.count_fault(f);
                    }
                    ep.advance_delayed(self.physics[k].as_mut(), &action, effect_delay_substeps);
                }
                SlotCommand::Terminate { why, fault } => {
                    if let Some(f) = fault {
                        ep.count_fault(f);
                    }
                    ep.terminate(why);
                }
            }
            if ep.is_done() {
                let job = *job;
                let (_, ep) = self.running[k].take().expect("checked above");
                finished.push(finish(shared, job, ep));
            }
        }
        while self.running[k].is_none() && !shared.stop.load(Ordering::SeqCst) {
            let retried = shared.retry.lock().expect("retry queue").pop();
            let j = retried.unwrap_or_else(|| shared.next_job.fetch_add(1, Ordering::SeqCst));
            let Some(&(q, s)) = shared.jobs.get(j) else {
                break;
            };
            let seq = &shared.sequences[q];
            let mut ep = Episode::start(&shared.setups[s], seq, self.physics[k].as_mut());
            if plan
                .spec
                .trace
                .contains(&format!("{}/{}", seq.task, seq.sequence_id))
            {
                ep.record_trace();
            } else if let Some(seconds) = plan.trace_first_s {
                ep.record_trace_for(seconds);
            }
            if ep.is_done() {
                finished.push(finish(shared, j, ep)); // a reference shorter than one step
            } else {
                self.running[k] = Some((j, ep));
            }
        }
        if let Some(p) = local {
            for f in &finished {
                p.episode_ended(self.slots[k], f.record.termination.is_some());
            }
        }
        let observation = self.running[k]
            .as_ref()
            .map(|(job, ep)| ep.observation_in(self.slots[k], *job as u64));
        SlotReport {
            slot: self.slots[k],
            observation,
            finished,
        }
    }
}

fn finish(shared: &Shared, job: usize, mut ep: Episode) -> Finished {
    let (q, s) = shared.jobs[job];
    let seq = &shared.sequences[q];
    let setting = &shared.plan.spec.settings[s];
    let trace = ep.take_trace();
    let physics_wall = ep.physics_wall();
    Finished {
        job,
        physics_wall,
        record: ep.into_record(seq, setting, &shared.policy_name),
        trace,
    }
}
