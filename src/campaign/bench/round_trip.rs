//! The shared-memory round trip — observation batch published → action batch received,
//! timed by the simulator side — with an echo policy (action = q for every environment)
//! or with a network adapter on standing observations.

use super::PerfError;
use crate::eval::{LatencyRecorder, LatencySummary};
use crate::policy::inputs::InputBuilder;
use crate::policy::wire::write_observation;
use crate::policy::Observation;
use crate::sim::motion::ReferenceFrame;
use crate::sim::physics::RootState;
use nalgebra::{Isometry3, Vector3};
use std::cell::RefCell;
use std::time::{Duration, Instant};
use thorarena_ipc::{
    ActionBatch, AnswersNoticed, EnvHeader, Layout, ObsBatchMut, SimSession, StepOutcome,
    FLAG_ACTIVE,
};

/// Environment `i` active at episode step `step` (50 Hz control).
fn active_header(i: usize, step: u64) -> EnvHeader {
    EnvHeader {
        episode_id: i as u64,
        step,
        flags: FLAG_ACTIVE,
        reserved: 0,
        time_s: step as f64 * 0.02,
    }
}

/// Fills every slot of `batch` as active with a recognisable q: environment `i`'s joint
/// `j` at step `s` holds `100 i + j + s`, so an echo's answer can be checked.
pub fn fill_echo_observations(batch: &mut ObsBatchMut, layout: Layout, step: u64) {
    for i in 0..layout.n_envs {
        let mut env = batch.env(i);
        env.set_header(&active_header(i, step));
        for (j, q) in env.array("q").iter_mut().enumerate() {
            *q = (i * 100 + j) as f64 + step as f64;
        }
    }
}

/// `warmup` untimed and `steps` timed round trips with the echo policy connected to
/// `sim`; every answer is checked (one slot), so a broken echo cannot look fast.
pub fn echo_round_trips(
    sim: &mut SimSession,
    warmup: usize,
    steps: usize,
) -> Result<LatencySummary, PerfError> {
    let timing = timed_round_trips(
        sim,
        warmup,
        steps,
        |batch, shape, step, _| {
            fill_echo_observations(batch, shape, step);
            Duration::ZERO
        },
        None,
        |a, shape, step| {
            let last = shape.n_envs - 1;
            a.env(last)[1] == (last * 100 + 1) as f64 + step as f64
        },
    )?;
    Ok(timing.round_trip)
}

/// `warmup` untimed and `steps` timed round trips, each batch written by `fill` (which
/// returns how long of that it spent building policy inputs; told whether `prepare` wrote
/// into the batch first) and each answer judged by `answer_ok` (a wrong one ends the
/// measurement with an error). `prepare` writes into the next batch while the policy
/// computes ([`SimSession::step_prepared`]) and returns how long it took.
fn timed_round_trips(
    sim: &mut SimSession,
    warmup: usize,
    steps: usize,
    mut fill: impl FnMut(&mut ObsBatchMut, Layout, u64, bool) -> Duration,
    mut prepare: Option<&mut dyn FnMut(&mut ObsBatchMut) -> Duration>,
    answer_ok: impl Fn(&ActionBatch, Layout, u64) -> bool,
) -> Result<AdapterTiming, PerfError> {
    let shape = sim.layout().ok_or(PerfError::WrongEcho {
        step: 0,
        outcome: "no policy connected".into(),
    })?;
    let has_prepare = prepare.is_some();
    let mut round_trip = LatencyRecorder::default();
    let mut input_build = LatencyRecorder::default();
    let mut input_prepare = LatencyRecorder::default();
    let mut per_step_us = Vec::with_capacity(steps);
    let mut noticed_before_timing = sim.answers_noticed();
    for step in 0..(warmup + steps) as u64 {
        if step == warmup as u64 {
            noticed_before_timing = sim.answers_noticed();
        }
        let mut ok = true;
        let mut build = Duration::ZERO;
        let mut prepared = Duration::ZERO;
        let mut prepare_timed = |next: &mut ObsBatchMut| {
            if let Some(p) = prepare.as_mut() {
                prepared = p(next);
            }
        };
        let prepare_next: Option<&mut dyn FnMut(&mut ObsBatchMut)> = if has_prepare {
            Some(&mut prepare_timed)
        } else {
            None
        };
        let outcome = sim.step_prepared(
            |b, was_prepared| build = fill(b, shape, step, was_prepared),
            prepare_next,
            None,
            |a| ok = answer_ok(a, shape, step),
        )?;
        if outcome != StepOutcome::Answered || !ok {
            return Err(PerfError::WrongEcho {
                step,
                outcome: format!("{outcome:?}, answer as expected: {ok}"),
            });
        }
        if step >= warmup as u64 {
            round_trip.record(sim.last_round_trip());
            input_build.record(build);
            input_prepare.record(prepared);
            per_step_us.push((sim.last_round_trip() + build).as_secs_f64() * 1e6);
        }
    }
    Ok(AdapterTiming {
        round_trip: round_trip.summary(),
        input_build: input_build.summary(),
        input_prepare: input_prepare.summary(),
        per_step_us,
        noticed: sim.answers_noticed().since(&noticed_before_timing),
    })
}

/// A robot standing still on a standing reference in slot `env` at episode step `step`
/// (0 starts the episode): identity rotations, zero velocities, joints at 0 rad, the root
/// 0.79 m up. What a network adapter sees on its first steps, for timing it.
pub fn standing_observation(env: usize, step: u64, n_joints: usize, n_refs: usize) -> Observation {
    let pose = Isometry3::translation(0.0, 0.0, 0.79);
    let frame = ReferenceFrame {
        world_from_root: pose,
        root_lin_vel_w: Vector3::zeros(),
        root_ang_vel_w: Vector3::zeros(),
        joint_pos: vec![0.0; n_joints],
        joint_vel: vec![0.0; n_joints],
        force_sensor: [Vector3::zeros(); 2],
    };
    Observation {
        env,
        episode_id: env as u64,
        step: step as usize,
        time_s: step as f64 * 0.02,
        root: RootState::at_rest(pose),
        q: vec![0.0; n_joints],
        qd: vec![0.0; n_joints],
        last_action: vec![0.0; n_joints],
        reference: vec![frame; n_refs],
    }
}

/// Timings of a network adapter's round trips, µs.
#[derive(Debug, Clone, PartialEq)]
pub struct AdapterTiming {
    /// Observation batch published → actions received.
    pub round_trip: LatencySummary,
    /// Building the policy input in the simulator, before publishing (zero when the
    /// adapter builds its own).
    pub input_build: LatencySummary,
    /// Writing the next batch's policy inputs as far as they are known (TWIST2's history)
    /// while the policy computes: inside the round trip, off the critical path unless
    /// it outlasts the policy (zero when the adapter builds its own).
    pub input_prepare: LatencySummary,
    /// Each timed step's round trip plus its input build, µs, in step order (to pair
    /// with what the adapter timed of the same step).
    pub per_step_us: Vec<f64>,
    /// How the simulator noticed the timed steps' answers: polling, or after blocking.
    pub noticed: AnswersNoticed,
}

/// `warmup` untimed and `steps` timed round trips with a network adapter connected to
/// `sim`, on standing observations ([`standing_observation`]) at `reference_offsets_s`,
/// one episode running from step 0; the policy input the adapter asked for, if any, is
/// built into each batch by `input` — prepared while the policy computes, as
/// `RemotePolicy` does — and both parts timed. Every answer must be finite, so an adapter
/// that answers nothing cannot look fast.
pub fn adapter_round_trips(
    sim: &mut SimSession,
    warmup: usize,
    steps: usize,
    reference_offsets_s: &[f64],
    input: Option<&mut InputBuilder>,
) -> Result<AdapterTiming, PerfError> {
    let has_input = input.is_some();
    let input = RefCell::new(input);
    let mut prepare = |next: &mut ObsBatchMut| {
        let started = Instant::now();
        if let Some(builder) = input.borrow().as_ref() {
            builder.prepare(next);
        }
        started.elapsed()
    };
    timed_round_trips(
        sim,
        warmup,
        steps,
        |batch, shape, step, prepared| {
            let observations: Vec<Observation> = (0..shape.n_envs)
                .map(|i| standing_observation(i, step, shape.n_joints, shape.n_refs))
                .collect();
            for (i, obs) in observations.iter().enumerate() {
                write_observation(obs, reference_offsets_s, &mut batch.env(i), 0);
            }
            // The inputs in one timed pass, as the simulator builds them after the physics
            // step (one clock pair: 64 pairs would add a few µs of their own).
            let mut input = input.borrow_mut();
            let Some(builder) = input.as_mut() else {
                return Duration::ZERO;
            };
            let started = Instant::now();
            for (i, obs) in observations.iter().enumerate() {
                builder.write(obs, batch.policy_input(i), prepared);
            }
            started.elapsed()
        },
        if has_input { Some(&mut prepare) } else { None },
        |a, shape, _| (0..shape.n_envs).all(|i| a.env(i).iter().all(|x| x.is_finite())),
    )
}
