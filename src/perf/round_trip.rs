//! The shared-memory round trip — observation batch published → action batch received,
//! timed by the simulator side — with an echo policy (action = q for every environment)
//! or with a network adapter on standing observations.

use super::PerfError;
use crate::evaluation::{LatencyRecorder, LatencySummary};
use thorarena_ipc::{
    ActionBatch, EnvHeader, Layout, ObsBatchMut, SimSession, StepOutcome, FLAG_ACTIVE,
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
    timed_round_trips(
        sim,
        warmup,
        steps,
        fill_echo_observations,
        |a, shape, step| {
            let last = shape.n_envs - 1;
            a.env(last)[1] == (last * 100 + 1) as f64 + step as f64
        },
    )
}

/// `warmup` untimed and `steps` timed round trips, each batch written by `fill` and each
/// answer judged by `answer_ok` (a wrong one ends the measurement with an error).
fn timed_round_trips(
    sim: &mut SimSession,
    warmup: usize,
    steps: usize,
    fill: impl Fn(&mut ObsBatchMut, Layout, u64),
    answer_ok: impl Fn(&ActionBatch, Layout, u64) -> bool,
) -> Result<LatencySummary, PerfError> {
    let shape = sim.layout().ok_or(PerfError::WrongEcho {
        step: 0,
        outcome: "no policy connected".into(),
    })?;
    let mut rec = LatencyRecorder::default();
    for step in 0..(warmup + steps) as u64 {
        let mut ok = true;
        let outcome = sim.step(
            |b| fill(b, shape, step),
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
            rec.record(sim.last_round_trip());
        }
    }
    Ok(rec.summary())
}

/// Fills every slot of `batch` as active with a robot standing still on a standing
/// reference: identity rotations, zero velocities, joints at 0 rad, at episode step `step`
/// (0 starts the episode). What a network adapter sees on its first steps, for timing it.
pub fn fill_standing_observations(batch: &mut ObsBatchMut, layout: Layout, step: u64) {
    const IDENTITY_WXYZ: [f64; 4] = [1.0, 0.0, 0.0, 0.0];
    for i in 0..layout.n_envs {
        let mut env = batch.env(i);
        env.set_header(&active_header(i, step));
        env.array("root_quat_wxyz").copy_from_slice(&IDENTITY_WXYZ);
        env.array("root_pos_w")[2] = 0.79;
        for r in 0..layout.n_refs {
            env.reference(r, "root_quat_wxyz")
                .copy_from_slice(&IDENTITY_WXYZ);
            env.reference(r, "root_pos_w")[2] = 0.79;
        }
    }
}

/// `warmup` untimed and `steps` timed round trips with a network adapter connected to
/// `sim`, on standing observations ([`fill_standing_observations`]), one episode running
/// from step 0; every answer must be finite, so an adapter that answers nothing cannot
/// look fast.
pub fn adapter_round_trips(
    sim: &mut SimSession,
    warmup: usize,
    steps: usize,
) -> Result<LatencySummary, PerfError> {
    timed_round_trips(
        sim,
        warmup,
        steps,
        fill_standing_observations,
        |a, shape, _| (0..shape.n_envs).all(|i| a.env(i).iter().all(|x| x.is_finite())),
    )
}
