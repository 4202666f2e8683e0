//! The standing tasks (`clean_table`, `liftup_water`, `liftdown_water`) and the plan type
//! every task produces: per-frame pelvis, feet, waist and hand targets plus world forces.

use super::forces::{level, rc, Levels, Window, Wobble};
use super::skeleton::Skeleton;
use super::style::Style;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use serde_json::json;

/// Kinematic targets of one frame.
#[derive(Debug, Clone, Copy)]
pub struct PlanFrame {
    /// Pelvis (root) pose.
    pub pelvis: Isometry3<f64>,
    /// Ankle-roll frame poses, left then right.
    pub feet: [Isometry3<f64>; 2],
    /// Waist yaw, roll, pitch, rad (set directly, not by IK).
    pub waist: [f64; 3],
    /// Hand positions, world, m.
    pub hands: [Vector3<f64>; 2],
}

/// A task's motion targets and the forces the environment exerts on each hand (world).
#[derive(Debug, Clone)]
pub struct Plan {
    /// One per frame.
    pub frames: Vec<PlanFrame>,
    /// Left and right hand force, world frame, N; one per frame each.
    pub force_world: [Vec<Vector3<f64>>; 2],
    /// The sampled parameters, for provenance.
    pub params: serde_json::Value,
}

/// Frame count of a duration at `fps` (both ends included).
pub fn n_frames(duration_s: f64, fps: f64) -> usize {
    (duration_s * fps).round() as usize + 1
}

/// Both feet at their default stance under a pelvis at the origin.
pub fn stance_feet(sk: &Skeleton) -> [Isometry3<f64>; 2] {
    [1.0, -1.0].map(|s| {
        Isometry3::from_parts(
            Translation3::new(sk.foot_x_m, s * sk.foot_y_m, sk.ankle_height_m),
            sk.foot_rot,
        )
    })
}

/// Pelvis pose: standing height minus `drop`, shifted forward by `dx`, pitched by `pitch`.
pub fn pelvis(sk: &Skeleton, dx: f64, drop: f64, pitch: f64) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(dx, 0.0, sk.stand_height_m - drop),
        UnitQuaternion::from_axis_angle(&Vector3::y_axis(), pitch),
    )
}

/// Default hand position (arms at the sides) for a standing pelvis, world.
pub fn hand_rest(sk: &Skeleton, side: usize) -> Vector3<f64> {
    sk.hand_default[side] + Vector3::new(0.0, 0.0, sk.stand_height_m)
}

/// The most a hand presses and rubs a table with while wiping, N (SOURCES.md, "Task
/// forces": wiping 5–30 N).
const WIPE_MAX_N: f64 = 30.0;

/// `clean_table`: standing, wiping with one or both hands on a table in front; bouts of
/// circles or back-and-forth strokes separated by short pauses with the hand lifted.
/// Forces (SOURCES.md, Task forces wiping 5–30 N, kept light per the push probe): the table pushes the hand up with
/// 5–12 N and friction of 3–8 N opposes the stroke.
pub fn clean_table(
    sk: &Skeleton,
    rng: &mut ChaCha8Rng,
    fps: f64,
    dur: f64,
    lv: &Levels,
    style: &Style,
) -> Plan {
    let n = n_frames(dur, fps);
    let mut hands_used = rng.random_range(0..3usize); // 0 left, 1 right, 2 both
                                                      // One hand wipes: a person uses the dominant one.
    if let (0 | 1, Some(d)) = (hands_used, style.dominant()) {
        hands_used = d;
    }
    let circles = rng.random_bool(0.5);
    let waist_pitch = style.waist_pitch(rng.random_range(0.15..0.35));
    let drop = rng.random_range(0.0..0.04);
    let table_z = sk.stand_height_m + rng.random_range(-0.06..0.0);
    let (cx, cy) = (rng.random_range(0.26..0.32), rng.random_range(0.13..0.18));
    let amp = rng.random_range(0.04..0.08);
    let freq = rng.random_range(0.5..1.0) * style.tempo;
    let press = [0, 1].map(|s| level(rng, lv.press) * style.hand_scale(s));
    let mut fric = [level(rng, lv.friction), level(rng, lv.friction)];
    if lv.version >= 2 {
        // Version 2 draws friction as a fraction of the press.
        fric = [fric[0] * press[0], fric[1] * press[1]];
    }
    let press_wobble = [0, 1].map(|_| Wobble::new(rng, 0.1, 0.6, 0.3 * style.tremble));
    let t_in = rng.random_range(1.0..2.0);
    let t_out = dur - rng.random_range(1.8..2.5);
    // Wiping bouts between reaching in and pulling back, with pauses between them.
    let n_bouts = rng.random_range(2..5usize);
    let span = (t_out - t_in - 1.5) / n_bouts as f64;
    let bouts: Vec<Window> = (0..n_bouts)
        .map(|b| {
            let on = t_in + 1.3 + b as f64 * span;
            let pause = rng.random_range(0.6f64..1.2).min(0.4 * span);
            Window {
                on,
                rise: rng.random_range(0.2..0.5) * style.build,
                off: on + span - pause - 0.4,
                fall: rng.random_range(0.2..0.4),
            }
        })
        .collect();
    let active = |s: usize| hands_used == 2 || hands_used == s;
    let w = 2.0 * std::f64::consts::PI * freq;
    let mut frames = Vec::with_capacity(n);
    let mut force_world = [Vec::with_capacity(n), Vec::with_capacity(n)];
    for k in 0..n {
        let t = k as f64 / fps;
        let reach = rc((t - t_in) / 1.2) * (1.0 - rc((t - t_out) / 1.2));
        let bend = reach;
        let contact = bouts.iter().map(|b| b.at(t)).fold(0.0, f64::max) * reach;
        let mut hands = [Vector3::zeros(); 2];
        for s in 0..2 {
            let side = if s == 0 { 1.0 } else { -1.0 };
            // Mirrored strokes, so both hands move symmetrically when both wipe.
            let (off, vel) = if circles {
                let (sn, cs) = (w * t).sin_cos();
                (
                    Vector3::new(amp * cs, side * amp * sn, 0.0),
                    Vector3::new(-amp * w * sn, side * amp * w * cs, 0.0),
                )
            } else {
                let (sn, cs) = (w * t).sin_cos();
                (
                    Vector3::new(0.0, side * 1.5 * amp * sn, 0.0),
                    Vector3::new(0.0, side * 1.5 * amp * w * cs, 0.0),
                )
            };
            let lift = if active(s) {
                0.05 * (1.0 - contact)
            } else {
                0.08
            };
            let on_table = Vector3::new(cx, side * cy, table_z + lift) + off;
            let rest = hand_rest(sk, s);
            let r = if active(s) { reach } else { 0.0 };
            hands[s] = rest + (on_table - rest) * r;
            let f = if active(s) {
                let speed = vel.norm().max(0.05);
                let p = press[s] * (1.0 + press_wobble[s].at(t));
                let f = Vector3::new(0.0, 0.0, p) - vel / speed * fric[s];
                // A strong hand trembling hard could pass what people wipe with: held at
                // the cited top (v1's forces never reach it).
                f * (WIPE_MAX_N / f.norm()).min(1.0)
            } else {
                Vector3::zeros()
            };
            force_world[s].push(f * contact);
        }
        frames.push(PlanFrame {
            pelvis: pelvis(sk, -0.02 * bend, drop * bend, 0.0),
            feet: style.stance_feet(sk),
            waist: [0.0, 0.0, waist_pitch * bend],
            hands,
        });
    }
    let which = ["left", "right", "both"][hands_used];
    let params = json!({"hands": which,
        "stroke": if circles { "circle" } else { "back_and_forth" },
        "stroke_amplitude_m": amp, "stroke_hz": freq, "waist_pitch_rad": waist_pitch,
        "table_height_m": table_z, "press_n": press, "friction_n": fric, "bouts": bouts});
    Plan {
        frames,
        force_world,
        params,
    }
}

/// `liftup_water` (`up = true`) and `liftdown_water`: squat and bend to a container on a
/// low surface, grasp it with both hands and stand up holding it — or the reverse. Forces
/// (SOURCES.md, Task forces: 20–40 N per hand for a 4–5 L container; version 1 scaled down
/// per the push probe to 12–22 N): the container's weight pulls each hand down while held,
/// zero before grasp and after release, no hand above [`super::forces::Levels::lift_hand_max`].
pub fn lift(
    sk: &Skeleton,
    rng: &mut ChaCha8Rng,
    fps: f64,
    dur: f64,
    up: bool,
    lv: &Levels,
    style: &Style,
) -> Plan {
    let n = n_frames(dur, fps);
    let drop = rng.random_range(0.10..0.20);
    let pelvis_pitch = style.pelvis_pitch(rng.random_range(0.1..0.3));
    let waist_pitch = style.waist_pitch(rng.random_range(0.2..0.45));
    let back = rng.random_range(0.02..0.06);
    let (t_bend, t_grip) = (
        rng.random_range(1.5..2.5) / style.tempo,
        rng.random_range(0.3..0.6) * style.build,
    );
    let slack = dur - 2.0 * t_bend - t_grip - 1.0;
    let share = rng.random_range(0.2..0.4);
    // liftup: wait, bend, grip, rise, hold; liftdown: hold, bend, release, rise, wait.
    let t0 = 0.5 + if up { share } else { 1.0 - share } * slack;
    let (t_low, t_rise) = (t0 + t_bend, t0 + t_bend + t_grip);
    let weight = level(rng, lv.lift);
    let split = rng.random_range(0.45..0.55) + style.left_bias();
    let low_x = rng.random_range(0.26..0.32);
    let low_z = sk.stand_height_m - drop + rng.random_range(-0.06..0.0);
    let half = rng.random_range(0.12..0.16);
    let carry = Vector3::new(
        rng.random_range(0.22..0.28),
        half,
        sk.stand_height_m + rng.random_range(0.02..0.1) + style.hand_height_m,
    );
    let wob = [0, 1, 2].map(|_| Wobble::new(rng, 0.1, 0.5, 1.0));
    let grip = Window {
        on: if up { t_low } else { -1.0 },
        rise: t_grip,
        off: if up { dur + 1.0 } else { t_low },
        fall: t_grip,
    };
    let mut frames = Vec::with_capacity(n);
    let mut force_world = [Vec::with_capacity(n), Vec::with_capacity(n)];
    for k in 0..n {
        let t = k as f64 / fps;
        let bend = rc((t - t0) / t_bend) * (1.0 - rc((t - t_rise) / t_bend));
        // Hands move with the body: rest → container when empty, carry ↔ container loaded.
        let loaded_before = !up;
        let before = t < t_low;
        let mut hands = [Vector3::zeros(); 2];
        for (s, hand) in hands.iter_mut().enumerate() {
            let side = if s == 0 { 1.0 } else { -1.0 };
            let low = Vector3::new(low_x, side * half, low_z);
            let high = if before == loaded_before {
                Vector3::new(carry.x, side * carry.y, carry.z)
                    + Vector3::new(0.01 * wob[0].at(t), 0.0, 0.015 * wob[1].at(t))
            } else {
                hand_rest(sk, s)
            };
            *hand = high + (low - high) * bend;
        }
        let held = grip.at(t);
        // Extra pull while the container is accelerated upward or braked downward.
        let accel = 0.15 * (std::f64::consts::PI * ((t - t_rise) / t_bend).clamp(0.0, 1.0)).sin();
        let total =
            weight * (1.0 + 0.08 * style.tremble * wob[2].at(t) + if up { accel } else { 0.0 });
        let load = super::forces::shared_within(
            [2.0 * split * total, 2.0 * (1.0 - split) * total],
            lv.lift_hand_max,
        );
        for (s, f) in force_world.iter_mut().enumerate() {
            let lateral = if s == 0 { -1.0 } else { 1.0 } * 0.8;
            f.push(Vector3::new(0.5 * wob[1].at(t), lateral, -load[s]) * held);
        }
        frames.push(PlanFrame {
            pelvis: pelvis(sk, -back * bend, drop * bend, pelvis_pitch * bend),
            feet: style.stance_feet(sk),
            waist: [0.0, 0.0, waist_pitch * bend],
            hands,
        });
    }
    let params = json!({"pelvis_drop_m": drop, "pelvis_pitch_rad": pelvis_pitch,
        "waist_pitch_rad": waist_pitch, "container_weight_share_n": weight,
        "left_share": split, "bend_start_s": t0, "bend_s": t_bend, "grip_s": t_grip});
    Plan {
        frames,
        force_world,
        params,
    }
}
