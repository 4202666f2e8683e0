//! The shared-memory round trip with an echo policy (action = q for every environment):
//! observation batch published → action batch received, timed by the simulator side.

use super::PerfError;
use crate::evaluation::{LatencyRecorder, LatencySummary};
use thorarena_ipc::{EnvHeader, Layout, ObsBatchMut, SimSession, StepOutcome, FLAG_ACTIVE};

/// Fills every slot of `batch` as active with a recognisable q: environment `i`'s joint
/// `j` at step `s` holds `100 i + j + s`, so an echo's answer can be checked.
pub fn fill_echo_observations(batch: &mut ObsBatchMut, layout: Layout, step: u64) {
    for i in 0..layout.n_envs {
        let mut env = batch.env(i);
        env.set_header(&EnvHeader {
            episode_id: i as u64,
            step,
            flags: FLAG_ACTIVE,
            reserved: 0,
            time_s: step as f64 * 0.02,
        });
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
    let shape = sim.layout().ok_or(PerfError::WrongEcho {
        step: 0,
        outcome: "no policy connected".into(),
    })?;
    let mut rec = LatencyRecorder::default();
    for step in 0..(warmup + steps) as u64 {
        let mut answer_ok = true;
        let outcome = sim.step(
            |b| fill_echo_observations(b, shape, step),
            None,
            |a| {
                let last = shape.n_envs - 1;
                answer_ok = a.env(last)[1] == (last * 100 + 1) as f64 + step as f64;
            },
        )?;
        if outcome != StepOutcome::Answered || !answer_ok {
            return Err(PerfError::WrongEcho {
                step,
                outcome: format!("{outcome:?}"),
            });
        }
        if step >= warmup as u64 {
            rec.record(sim.last_round_trip());
        }
    }
    Ok(rec.summary())
}
