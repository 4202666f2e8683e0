//! The walking tasks: `push_chair` (forward), `pull_chair` (backward) and `syn_carry`
//! (forward or backward, sometimes turning), all with both hands on the object.

use super::forces::{level, pulse, rc, Levels, Window, Wobble};
use super::gait::{walk, GaitParams, TurnBout};
use super::skeleton::Skeleton;
use super::style::Style;
use super::tasks::{n_frames, Plan, PlanFrame};
use nalgebra::Vector3;
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use serde_json::json;

/// Which walking task.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WalkTask {
    /// Walk forward pushing a chair by its back.
    PushChair,
    /// Walk backward pulling a chair by its back.
    PullChair,
    /// Carry an object together with a partner.
    Carry,
}

fn gait_params(
    rng: &mut ChaCha8Rng,
    task: WalkTask,
    sk: &Skeleton,
    dur: f64,
    style: &Style,
    version: u32,
) -> GaitParams {
    let direction = match task {
        WalkTask::PushChair => 1.0,
        WalkTask::PullChair => -1.0,
        WalkTask::Carry => {
            if rng.random_bool(0.7) {
                1.0
            } else {
                -1.0
            }
        }
    };
    if version >= 2 {
        return gait_params_v2(rng, task, sk, dur, style, direction);
    }
    // Backward steps are shorter, as people's are. Forward steps stop short of 0.3 m: the
    // trailing foot stays flat (no heel-off), and beyond ~0.27 m its ankle reaches the
    // dorsiflexion limit (−0.87 rad) for some pelvis heights.
    let step_length_m = style.step_length(
        if direction > 0.0 {
            rng.random_range(0.15..0.26)
        } else {
            rng.random_range(0.15..0.22)
        },
        direction,
    );
    let turn = match task {
        WalkTask::Carry if rng.random_bool(0.6) => rng.random_range(-0.12..0.12),
        _ => rng.random_range(-0.03..0.03),
    };
    let step_period_s = rng.random_range(0.7..0.9) / style.tempo;
    let start_s = rng.random_range(1.8..2.6);
    let stop_s = rng.random_range(1.8..2.6);
    let n_steps = (((dur - start_s - stop_s) / step_period_s).floor() as usize).max(4);
    GaitParams {
        direction,
        step_length_m,
        step_period_s,
        lift_m: rng.random_range(0.05..0.08),
        n_steps,
        turn_per_step_rad: turn,
        start_s,
        left_first: rng.random_bool(0.5),
        height_m: sk.stand_height_m - rng.random_range(0.01..0.03),
        bob_m: rng.random_range(0.005..0.015),
        sway_m: rng.random_range(0.01..0.025),
        half_width_m: sk.foot_y_m + rng.random_range(-0.01..0.01) + style.width_m,
        roll_off_rad: 0.0,
        turn_bout: None,
    }
}

/// Version 2's walking: forward, the trailing foot rolls off its toe, so steps and
/// cadence come nearer people's (SOURCES.md, "Walking": people's free cadence is near
/// 0.55 s a step; TWIST2's G1-retargeted walks move at 0.7 m/s), and a bout may take a
/// corner.
fn gait_params_v2(
    rng: &mut ChaCha8Rng,
    task: WalkTask,
    sk: &Skeleton,
    dur: f64,
    style: &Style,
    direction: f64,
) -> GaitParams {
    let step_length_m = style.step_length(
        if direction > 0.0 {
            rng.random_range(0.22..0.36)
        } else {
            rng.random_range(0.15..0.22)
        },
        direction,
    );
    let step_period_s = rng.random_range(0.5..0.75) / style.tempo;
    let turn = rng.random_range(-0.03..0.03);
    let start_s = rng.random_range(1.8..2.6);
    let stop_s = rng.random_range(1.8..2.6);
    let n_steps = (((dur - start_s - stop_s) / step_period_s).floor() as usize).max(4);
    // A corner: most carries, some chair pushes and pulls; 30–90° in 3–6 steps.
    let corner = match task {
        WalkTask::Carry => 0.6,
        _ => 0.3,
    };
    let turn_bout = (n_steps >= 8 && rng.random_bool(corner)).then(|| {
        let steps = rng.random_range(3..7usize).min(n_steps - 3);
        let angle = rng.random_range(30f64..90.0).to_radians();
        let sign = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
        TurnBout {
            first: rng.random_range(2..n_steps - steps),
            steps,
            rad_per_step: sign * angle / steps as f64,
        }
    });
    GaitParams {
        direction,
        step_length_m,
        step_period_s,
        lift_m: rng.random_range(0.05..0.08),
        n_steps,
        turn_per_step_rad: turn,
        start_s,
        left_first: rng.random_bool(0.5),
        height_m: sk.stand_height_m - rng.random_range(0.01..0.03),
        bob_m: rng.random_range(0.005..0.015),
        sway_m: rng.random_range(0.01..0.025),
        half_width_m: sk.foot_y_m + rng.random_range(-0.01..0.01) + style.width_m,
        // Backward, the feet stay flat: rolling the leading foot off its heel left the legs
        // out of reach at the first steps of a pull (most draws failed their IK).
        roll_off_rad: if direction > 0.0 {
            rng.random_range(0.25..0.5)
        } else {
            0.0
        },
        turn_bout,
    }
}

/// Builds the plan of a walking task.
pub fn walking(
    sk: &Skeleton,
    rng: &mut ChaCha8Rng,
    fps: f64,
    dur: f64,
    task: WalkTask,
    lv: &Levels,
    style: &Style,
) -> Plan {
    let g = gait_params(rng, task, sk, dur, style, lv.version);
    let n = n_frames(dur, fps);
    let gait = walk(sk, &g, fps, n);
    let chair = task != WalkTask::Carry;
    // Hands on a chair back at the robot's hip height, or holding a carried object.
    let grip = Vector3::new(
        rng.random_range(0.24..0.3),
        rng.random_range(if chair { 0.17..0.21 } else { 0.13..0.17 }),
        sk.stand_height_m + rng.random_range(0.0..0.1) + style.hand_height_m,
    );
    let waist_pitch = style.waist_pitch(rng.random_range(0.0..0.12));
    let hold = Window {
        on: g.start_s - rng.random_range(1.3..1.7),
        rise: rng.random_range(0.2..0.6) * style.build,
        off: g.end_s() + rng.random_range(0.2..0.6),
        fall: rng.random_range(0.2..0.6) * style.build,
    };
    // Chair: SOURCES.md, Task forces 15–50 N sustained, 50–100 N break-away, in peaks of
    // 0.2–0.5 s. Carry: 10–50 N, a share of the weight plus a partner's fluctuating push or
    // pull along the walk and a few tugs. Each version's levels: `forces::Levels`.
    let sustained =
        [0, 1].map(|s| lv.per_hand(level(rng, lv.chair_sustained)) * style.hand_scale(s));
    let idle = level(rng, (1.0, 4.0));
    let mut peaks = vec![(
        g.start_s + rng.random_range(0.0..0.3),
        rng.random_range(0.2..0.5) * style.break_width,
    )];
    if rng.random_bool(0.5) {
        let t = rng.random_range(g.start_s + 2.0..g.end_s().max(g.start_s + 2.5));
        peaks.push((t, rng.random_range(0.2..0.5) * style.break_width));
    }
    let peak_n = [0, 1].map(|s| lv.per_hand(level(rng, lv.chair_peak)) * style.hand_scale(s));
    let vertical = [0, 1].map(|s| lv.per_hand(level(rng, lv.carry_vertical)) * style.hand_scale(s));
    let partner_amp = lv.per_hand(level(rng, lv.carry_partner));
    let partner = Wobble::new(rng, 0.1, 0.5, partner_amp);
    let tremble = style.tremble;
    // The partner's tugs: a second or so of a firmer push or pull.
    let tugs: Vec<(f64, f64, f64)> = (0..rng.random_range(2..5))
        .map(|_| {
            let t = rng.random_range(hold.on + 1.0..(hold.off - 1.0).max(hold.on + 1.5));
            let sign = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
            (
                t,
                rng.random_range(0.8..1.5),
                sign * lv.per_hand(level(rng, lv.carry_tug)),
            )
        })
        .collect();
    let wob = [0, 1, 2].map(|_| Wobble::new(rng, 0.2, 1.0, 1.0));
    let mut frames = Vec::with_capacity(n);
    let mut force_world = [Vec::with_capacity(n), Vec::with_capacity(n)];
    for (k, gf) in gait.iter().enumerate() {
        let t = k as f64 / fps;
        let reach = rc((t - hold.on + 1.2) / 1.2) * (1.0 - rc((t - hold.off - hold.fall) / 1.2));
        let contact = hold.at(t);
        let mut hands = [Vector3::zeros(); 2];
        for (s, hand) in hands.iter_mut().enumerate() {
            let side = if s == 0 { 1.0 } else { -1.0 };
            // Relative to the walking pelvis, at a fixed world height (objects don't bob).
            let mut on = gf.pelvis * nalgebra::Point3::new(grip.x, side * grip.y, 0.0);
            on.z = grip.z + 0.01 * wob[s].at(t);
            let rest = (gf.pelvis * nalgebra::Point3::from(sk.hand_default[s])).coords;
            *hand = rest + (on.coords - rest) * reach;
        }
        let lateral = gf.pelvis.rotation * Vector3::y();
        let mut f = [Vector3::zeros(); 2];
        for s in 0..2 {
            f[s] = if chair {
                let gait_ripple =
                    1.0 + 0.25 * (2.0 * std::f64::consts::PI * t / g.step_period_s).sin();
                let base = (sustained[s] * gf.walking * gait_ripple + idle)
                    * (1.0 + 0.1 * tremble * wob[2].at(t));
                // A break-away peak replaces the sustained level, it does not add to it.
                let p = peaks
                    .iter()
                    .map(|&(t0, w)| pulse(t, t0, w))
                    .fold(0.0, f64::max);
                let along = base + (peak_n[s] - base).max(0.0) * p;
                -gf.dir_world * along + lateral * (tremble * wob[s].at(t)) - Vector3::z() * 1.5
            } else {
                let tug: f64 = tugs.iter().map(|&(t0, w, a)| a * pulse(t, t0, w)).sum();
                let f = gf.pelvis.rotation * Vector3::x() * (partner.at(t) + tug)
                    - Vector3::z() * vertical[s] * (1.0 + 0.1 * tremble * wob[2].at(t))
                    + lateral * 1.5 * (tremble * wob[s].at(t));
                // A tug on top of the partner's push: held at the hand's bound.
                match lv.carry_hand_max {
                    Some(max) => f * (max / f.norm().max(1e-9)).min(1.0),
                    None => f,
                }
            } * contact;
        }
        force_world[0].push(f[0]);
        force_world[1].push(f[1]);
        frames.push(PlanFrame {
            pelvis: gf.pelvis,
            feet: gf.feet,
            waist: [0.0, 0.0, waist_pitch * reach],
            hands,
        });
    }
    let params = json!({"gait": g, "grip_m": [grip.x, grip.y, grip.z], "hold": hold,
        "sustained_n": sustained, "idle_n": idle, "peaks_s": peaks, "peak_n": peak_n,
        "carry_vertical_n": vertical, "tugs": tugs, "waist_pitch_rad": waist_pitch});
    Plan {
        frames,
        force_world,
        params,
    }
}
