//! How a sequence moves and loads its hands, measured from the motion itself — the
//! per-sequence numbers a data card shows as distributions, so a synthetic dataset's
//! variety can be set beside recorded people's on the same measures (docs/data-card.md).
//!
//! Every measure is read off the check's frames (root smoothed at the check's cutoff, sole
//! points, recorded hand forces), never off a generator's parameters, so it applies to any
//! dataset the importers produce.

use super::frames::FrameState;
use super::zero_phase::low_pass_zero_phase;
use super::{sorted, LOADED_N};
use crate::eval::metrics::percentile;
use serde::Serialize;

/// The force's slow part is what a 1 Hz zero-phase low-pass keeps; the rest of a loaded
/// hand's force is tremble (hand shake, an object's wobble). 1 Hz sits below a hand's
/// physiological tremor (8–12 Hz) and below gait's step frequency (about 1.2–2.5 Hz), above
/// the build-up of a push or a lift (rise times of 0.2–2 s).
const TREMBLE_CUTOFF_HZ: f64 = 1.0;
/// A loaded stretch shorter than this is a touch, not a hold: it has no build-up to time, s.
const MIN_HOLD_S: f64 = 0.5;
/// The build-up ends when the force first reaches this share of its hold's peak.
const RISE_SHARE: f64 = 0.8;
/// The root moves when its horizontal speed is above this, m/s.
pub(super) const MOVING_M_S: f64 = 0.1;

/// One sequence's style: how fast and how straight it walks, how it stands, how deep it
/// squats, which hand does the work and how its force builds and trembles.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct SequenceStyle {
    /// Mean horizontal root speed over the frames it moves (above 0.1 m/s), m/s; 0 when it
    /// never moves.
    pub speed_mean_m_s: f64,
    /// 90th percentile of the horizontal root speed over all frames, m/s.
    pub speed_p90_m_s: f64,
    /// Share of frames the root moves (above 0.1 m/s).
    pub moving_share: f64,
    /// Mean absolute yaw rate of the root over the frames it moves, deg/s.
    pub turn_deg_s: f64,
    /// 90th percentile of the absolute yaw rate over the frames it moves: how sharp its
    /// corners are, where the mean says how much of the way it turns, deg/s.
    pub turn_p90_deg_s: f64,
    /// Mean lateral distance between the two feet in the root's heading frame, over frames
    /// with both feet on the ground, m.
    pub stance_width_m: f64,
    /// Mean fore-aft distance between the two feet in the root's heading frame, over
    /// frames with both feet on the ground and the root still: a staggered stance, m.
    pub stagger_m: f64,
    /// Highest root height minus lowest: how deep it squats or bobs, m.
    pub root_height_range_m: f64,
    /// The left hand's share of the hands' force impulse (1 left only, 0 right only);
    /// `None` without any hand force.
    pub left_share: Option<f64>,
    /// Median build-up of its holds (both hands' force above 2 N for at least 0.5 s): from
    /// loading to 80 % of the hold's peak, s; `None` without a hold.
    pub rise_s: Option<f64>,
    /// RMS of both hands' force minus its 1 Hz low-pass over the loaded frames, over their
    /// mean force; `None` without a loaded frame.
    pub tremble: Option<f64>,
}

impl SequenceStyle {
    /// The style of a sequence's check frames, `rate_hz` apart.
    pub fn of(frames: &[FrameState], rate_hz: f64) -> Self {
        let dt = 1.0 / rate_hz;
        let n = frames.len();
        let mut speeds = Vec::with_capacity(n);
        let mut turns = Vec::new();
        for w in frames.windows(2) {
            let v = (w[1].root_w - w[0].root_w).xy().norm() / dt;
            speeds.push(v);
            if v > MOVING_M_S {
                let d = wrap_pi(w[1].root_heading_rad - w[0].root_heading_rad);
                turns.push(d.abs().to_degrees() / dt);
            }
        }
        let moving: Vec<f64> = speeds.iter().copied().filter(|v| *v > MOVING_M_S).collect();
        let (mut widths, mut staggers) = (Vec::new(), Vec::new());
        for (i, f) in frames.iter().enumerate() {
            let Some([a, b]) = feet_on_ground(f) else {
                continue;
            };
            let (s, c) = f.root_heading_rad.sin_cos();
            let d = b - a;
            let (fore, lateral) = (c * d.x + s * d.y, -s * d.x + c * d.y);
            widths.push(lateral.abs());
            let still = speeds.get(i.min(speeds.len().saturating_sub(1)));
            if still.is_some_and(|v| *v <= MOVING_M_S) {
                staggers.push(fore.abs());
            }
        }
        let heights = frames.iter().map(|f| f.root_w.z);
        let (lo, hi) = heights.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), z| {
            (lo.min(z), hi.max(z))
        });
        let impulse = [0, 1].map(|s| frames.iter().map(|f| f.hand_force_n[s]).sum::<f64>());
        let both: Vec<f64> = frames
            .iter()
            .map(|f| f.hand_force_n[0] + f.hand_force_n[1])
            .collect();
        Self {
            speed_mean_m_s: mean(&moving).unwrap_or(0.0),
            speed_p90_m_s: percentile(&sorted(speeds.clone()), 90.0),
            moving_share: moving.len() as f64 / speeds.len().max(1) as f64,
            turn_deg_s: mean(&turns).unwrap_or(0.0),
            turn_p90_deg_s: if turns.is_empty() {
                0.0
            } else {
                percentile(&sorted(turns), 90.0)
            },
            stance_width_m: mean(&widths).unwrap_or(0.0),
            stagger_m: mean(&staggers).unwrap_or(0.0),
            root_height_range_m: if n > 0 { hi - lo } else { 0.0 },
            left_share: (impulse[0] + impulse[1] > 0.0)
                .then(|| impulse[0] / (impulse[0] + impulse[1])),
            rise_s: median(holds(&both, rate_hz)),
            tremble: tremble(&both, rate_hz),
        }
    }
}

/// One measure over a task's sequences.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Spread {
    /// Sequences that have the measure.
    pub sequences: usize,
    /// 10th percentile.
    pub p10: f64,
    /// Median.
    pub median: f64,
    /// 90th percentile.
    pub p90: f64,
}

impl Spread {
    fn of(values: Vec<f64>) -> Option<Self> {
        let v = sorted(values);
        (!v.is_empty()).then(|| Self {
            sequences: v.len(),
            p10: percentile(&v, 10.0),
            median: percentile(&v, 50.0),
            p90: percentile(&v, 90.0),
        })
    }
}

/// A task's styles as distributions over its sequences (`None`: no sequence has it).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct TaskStyle {
    /// Task name.
    pub task: String,
    /// See [`SequenceStyle::speed_mean_m_s`].
    pub speed_mean_m_s: Option<Spread>,
    /// See [`SequenceStyle::speed_p90_m_s`].
    pub speed_p90_m_s: Option<Spread>,
    /// See [`SequenceStyle::moving_share`].
    pub moving_share: Option<Spread>,
    /// See [`SequenceStyle::turn_deg_s`].
    pub turn_deg_s: Option<Spread>,
    /// See [`SequenceStyle::turn_p90_deg_s`].
    pub turn_p90_deg_s: Option<Spread>,
    /// See [`SequenceStyle::stance_width_m`].
    pub stance_width_m: Option<Spread>,
    /// See [`SequenceStyle::stagger_m`].
    pub stagger_m: Option<Spread>,
    /// See [`SequenceStyle::root_height_range_m`].
    pub root_height_range_m: Option<Spread>,
    /// See [`SequenceStyle::left_share`].
    pub left_share: Option<Spread>,
    /// See [`SequenceStyle::rise_s`].
    pub rise_s: Option<Spread>,
    /// See [`SequenceStyle::tremble`].
    pub tremble: Option<Spread>,
}

impl TaskStyle {
    /// The distributions of `styles`, a task's sequences.
    pub fn of(task: &str, styles: &[&SequenceStyle]) -> Self {
        let all = |f: fn(&SequenceStyle) -> f64| Spread::of(styles.iter().map(|s| f(s)).collect());
        let some = |f: fn(&SequenceStyle) -> Option<f64>| {
            Spread::of(styles.iter().filter_map(|s| f(s)).collect())
        };
        // A task whose sequences never move has no speed or turn to show.
        let moving: Vec<&&SequenceStyle> = styles.iter().filter(|s| s.moving_share > 0.0).collect();
        let of_moving =
            |f: fn(&SequenceStyle) -> f64| Spread::of(moving.iter().map(|s| f(s)).collect());
        Self {
            task: task.to_string(),
            speed_mean_m_s: of_moving(|s| s.speed_mean_m_s),
            speed_p90_m_s: all(|s| s.speed_p90_m_s),
            moving_share: all(|s| s.moving_share),
            turn_deg_s: of_moving(|s| s.turn_deg_s),
            turn_p90_deg_s: of_moving(|s| s.turn_p90_deg_s),
            stance_width_m: all(|s| s.stance_width_m),
            stagger_m: all(|s| s.stagger_m),
            root_height_range_m: all(|s| s.root_height_range_m),
            left_share: some(|s| s.left_share),
            rise_s: some(|s| s.rise_s),
            tremble: some(|s| s.tremble),
        }
    }
}

/// The tasks' styles as a Markdown section: each measure's median and its 10th–90th
/// percentiles over a task's sequences.
pub fn markdown(styles: &[TaskStyle]) -> String {
    use std::fmt::Write;
    let cell = |x: &Option<Spread>, scale: f64, digits: usize| match x {
        None => "–".to_string(),
        Some(v) => format!(
            "{:.d$} ({:.d$}–{:.d$})",
            scale * v.median,
            scale * v.p10,
            scale * v.p90,
            d = digits
        ),
    };
    let mut s = String::new();
    let _ = writeln!(
        s,
        "\n## Style: median (10th–90th percentile) over each task's sequences\n\n| task | speed while moving, m/s | speed p90, m/s | moving, % | turning, deg/s | turning p90, deg/s | stance width, cm | stagger standing, cm | root height range, cm | left hand's share | force build-up, s | tremble, % |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    );
    for t in styles {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            t.task,
            cell(&t.speed_mean_m_s, 1.0, 2),
            cell(&t.speed_p90_m_s, 1.0, 2),
            cell(&t.moving_share, 100.0, 0),
            cell(&t.turn_deg_s, 1.0, 1),
            cell(&t.turn_p90_deg_s, 1.0, 1),
            cell(&t.stance_width_m, 100.0, 1),
            cell(&t.stagger_m, 100.0, 1),
            cell(&t.root_height_range_m, 100.0, 1),
            cell(&t.left_share, 1.0, 2),
            cell(&t.rise_s, 1.0, 2),
            cell(&t.tremble, 100.0, 1),
        );
    }
    s
}

/// The mean positions of the two feet's touching sole points, when both feet touch.
fn feet_on_ground(f: &FrameState) -> Option<[nalgebra::Vector2<f64>; 2]> {
    let mut bodies: Vec<usize> = f.soles.iter().map(|s| s.body).collect();
    bodies.dedup();
    if bodies.len() != 2 {
        return None;
    }
    let foot = |body: usize| {
        let on: Vec<_> = f
            .soles
            .iter()
            .zip(&f.touching)
            .filter(|(s, t)| s.body == body && **t)
            .map(|(s, _)| s.bottom_w.xy().coords)
            .collect();
        (!on.is_empty()).then(|| on.iter().sum::<nalgebra::Vector2<f64>>() / on.len() as f64)
    };
    Some([foot(bodies[0])?, foot(bodies[1])?])
}

/// Each hold's build-up time: a stretch of at least [`MIN_HOLD_S`] above [`LOADED_N`], from
/// its start to the first frame at [`RISE_SHARE`] of its peak, s.
fn holds(force_n: &[f64], rate_hz: f64) -> Vec<f64> {
    let mut out = Vec::new();
    let mut k = 0;
    while k < force_n.len() {
        if force_n[k] <= LOADED_N {
            k += 1;
            continue;
        }
        let start = k;
        while k < force_n.len() && force_n[k] > LOADED_N {
            k += 1;
        }
        let hold = &force_n[start..k];
        if hold.len() as f64 / rate_hz >= MIN_HOLD_S {
            let peak = hold.iter().copied().fold(0.0, f64::max);
            if let Some(at) = hold.iter().position(|f| *f >= RISE_SHARE * peak) {
                out.push(at as f64 / rate_hz);
            }
        }
    }
    out
}

fn tremble(force_n: &[f64], rate_hz: f64) -> Option<f64> {
    if force_n.len() < 8 {
        return None;
    }
    let slow = low_pass_zero_phase(force_n, TREMBLE_CUTOFF_HZ, rate_hz);
    let loaded: Vec<(f64, f64)> = force_n
        .iter()
        .zip(&slow)
        .filter(|(f, _)| **f > LOADED_N)
        .map(|(f, s)| (*f, *s))
        .collect();
    let level = mean(&loaded.iter().map(|(f, _)| *f).collect::<Vec<_>>())?;
    let rms =
        (loaded.iter().map(|(f, s)| (f - s).powi(2)).sum::<f64>() / loaded.len() as f64).sqrt();
    Some(rms / level)
}

fn wrap_pi(a: f64) -> f64 {
    (a + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI
}

fn mean(v: &[f64]) -> Option<f64> {
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

fn median(v: Vec<f64>) -> Option<f64> {
    let v = sorted(v);
    (!v.is_empty()).then(|| percentile(&v, 50.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_hold_builds_up_over_the_time_it_takes_to_reach_most_of_its_peak() {
        // 100 Hz: 0.2 s unloaded, a linear ramp 0 → 40 N over 1 s, 1 s at 40 N, unloaded.
        let mut f = vec![0.0; 20];
        f.extend((0..100).map(|k| 40.0 * k as f64 / 100.0));
        f.extend(vec![40.0; 100]);
        f.extend(vec![0.0; 20]);
        let rise = holds(&f, 100.0);
        assert_eq!(rise.len(), 1);
        // Loaded from 2 N (k = 5 of the ramp) to 32 N (k = 80): 0.75 s.
        assert!((rise[0] - 0.75).abs() < 0.011, "{rise:?}");
        // A touch shorter than half a second is no hold.
        assert!(holds(&[0.0, 10.0, 10.0, 0.0], 100.0).is_empty());
    }

    #[test]
    fn a_steady_force_does_not_tremble_and_a_shaking_one_does() {
        let steady = vec![30.0; 400];
        assert!(tremble(&steady, 100.0).unwrap() < 1e-6);
        let shaking: Vec<f64> = (0..400)
            .map(|k| 30.0 + 3.0 * (2.0 * std::f64::consts::PI * 8.0 * k as f64 / 100.0).sin())
            .collect();
        // A sine of amplitude 3 N has an RMS of 3/√2 N: 0.0707 of 30 N.
        let t = tremble(&shaking, 100.0).unwrap();
        assert!((t - 0.0707).abs() < 0.01, "{t}");
    }

    #[test]
    fn headings_wrap_across_the_back() {
        assert!((wrap_pi(3.1 - (-3.1)) - (6.2 - std::f64::consts::TAU)).abs() < 1e-12);
        assert!((wrap_pi(0.3) - 0.3).abs() < 1e-12);
    }
}
