//! Walking: footholds, swing-foot arcs and the pelvis trajectory, kinematic only.
//!
//! A stance foot is exactly its foothold (flat, on the ground, not sliding); a swing foot
//! travels on a smooth arc with zero velocity at lift-off and touch-down and lands flat.
//! With a roll-off ([`GaitParams::roll_off_rad`], version 2, walking forward) the trailing
//! foot rolls through double support about its toe's edge, so the sole points it still
//! stands on neither lift nor slide, and levels out again in the first half of its swing:
//! the trailing ankle no longer caps the step where it meets its dorsiflexion limit with a
//! flat foot.
//! The pelvis follows the midpoint of the feet, piecewise linear in time between step
//! ends, then smoothed by a moving average one step period wide: that gives a gentle
//! start and stop and a constant speed in between. Leg IK turns this into joint angles.

use super::skeleton::Skeleton;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector2, Vector3};

/// One walking bout.
#[derive(Debug, Clone, serde::Serialize)]
pub struct GaitParams {
    /// +1 walks forward, −1 backward.
    pub direction: f64,
    /// Distance between successive contralateral footholds along the path, m.
    pub step_length_m: f64,
    /// Duration of one step (double support then swing), s.
    pub step_period_s: f64,
    /// Peak swing-foot lift, m.
    pub lift_m: f64,
    /// Steps including the final one that brings the feet together.
    pub n_steps: usize,
    /// Heading change per step, rad (positive turns left).
    pub turn_per_step_rad: f64,
    /// Standing time before the first step, s.
    pub start_s: f64,
    /// The left foot swings first.
    pub left_first: bool,
    /// Pelvis height while standing, m.
    pub height_m: f64,
    /// Pelvis dip at double support while walking, m.
    pub bob_m: f64,
    /// Pelvis shift toward the stance foot at mid-swing, m.
    pub sway_m: f64,
    /// Lateral distance of each ankle from the path centre, m.
    pub half_width_m: f64,
    /// Pitch of the trailing foot about its toe when it lifts, rad: 0 keeps it flat
    /// (version 1, and walking backward).
    #[serde(skip_serializing_if = "is_zero")]
    pub roll_off_rad: f64,
    /// A sharper turn within the bout (version 2): a corner taken in a few steps.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub turn_bout: Option<TurnBout>,
}

/// Steps `first ..< first + steps` each turn by `rad_per_step` more.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct TurnBout {
    /// The first turning step (1 is the bout's first step).
    pub first: usize,
    /// How many steps turn.
    pub steps: usize,
    /// Heading change each of them adds, rad (positive turns left).
    pub rad_per_step: f64,
}

fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

/// Kinematic targets of one frame.
#[derive(Debug, Clone, Copy)]
pub struct GaitFrame {
    /// Pelvis pose (level, yawed).
    pub pelvis: Isometry3<f64>,
    /// Ankle-roll frame poses, left then right.
    pub feet: [Isometry3<f64>; 2],
    /// 0 standing … 1 walking, smoothed.
    pub walking: f64,
    /// Unit walking direction in the world (sign of `direction` included).
    pub dir_world: Vector3<f64>,
}

impl GaitParams {
    /// End of the last step, s.
    pub fn end_s(&self) -> f64 {
        self.start_s + self.n_steps as f64 * self.step_period_s
    }
}

/// Fraction of each step spent in double support before the swing.
const DOUBLE_SUPPORT: f64 = 0.2;

#[derive(Clone, Copy)]
struct Foothold {
    pos: Vector2<f64>,
    yaw: f64,
}

fn rot2(yaw: f64) -> nalgebra::Rotation2<f64> {
    nalgebra::Rotation2::new(yaw)
}

/// Footholds per side after each step (index 0 = the initial stance).
fn footholds(sk: &Skeleton, p: &GaitParams) -> Vec<[Foothold; 2]> {
    let place = |c: Vector2<f64>, yaw: f64, side: usize| {
        let y = if side == 0 {
            p.half_width_m
        } else {
            -p.half_width_m
        };
        Foothold {
            pos: c + rot2(yaw) * Vector2::new(sk.foot_x_m, y),
            yaw,
        }
    };
    let (mut c, mut yaw) = (Vector2::zeros(), 0.0);
    let mut out = vec![[place(c, yaw, 0), place(c, yaw, 1)]];
    for i in 1..=p.n_steps {
        if i < p.n_steps {
            yaw += p.turn_per_step_rad;
            if let Some(b) = p
                .turn_bout
                .filter(|b| (b.first..b.first + b.steps).contains(&i))
            {
                yaw += b.rad_per_step;
            }
            c += rot2(yaw) * Vector2::new(p.direction * p.step_length_m, 0.0);
        }
        let side = swing_side(p, i);
        let mut next = out[i - 1];
        next[side] = place(c, yaw, side);
        out.push(next);
    }
    out
}

fn swing_side(p: &GaitParams, step: usize) -> usize {
    usize::from((step % 2 == 1) != p.left_first)
}

fn smooth5(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    x * x * x * (10.0 - 15.0 * x + 6.0 * x * x)
}

fn moving_average(v: &[f64], half: usize) -> Vec<f64> {
    let n = v.len();
    (0..n)
        .map(|i| {
            let (a, b) = (i.saturating_sub(half), (i + half).min(n - 1));
            // Symmetric window, shrunk at the ends so the average stays centred.
            let h = (i - a).min(b - i);
            v[i - h..=i + h].iter().sum::<f64>() / (2 * h + 1) as f64
        })
        .collect()
}

/// Targets for `n_frames` frames at `fps`; standing still before and after the bout.
pub fn walk(sk: &Skeleton, p: &GaitParams, fps: f64, n_frames: usize) -> Vec<GaitFrame> {
    let holds = footholds(sk, p);
    let step_of = |t: f64| -> Option<(usize, f64)> {
        let x = (t - p.start_s) / p.step_period_s;
        (x >= 0.0 && x < p.n_steps as f64).then(|| (x.floor() as usize + 1, x.fract()))
    };
    let after = |t: f64| -> usize {
        (((t - p.start_s) / p.step_period_s).floor().max(0.0) as usize).min(p.n_steps)
    };
    // Raw pelvis track: midpoint of the footholds, linear between step ends.
    let mid = |h: &[Foothold; 2]| {
        let yaw = 0.5 * (h[0].yaw + h[1].yaw);
        let c = 0.5 * (h[0].pos + h[1].pos) - rot2(yaw) * Vector2::new(sk.foot_x_m, 0.0);
        (c, yaw)
    };
    let mut raw = [vec![], vec![], vec![], vec![]];
    for k in 0..n_frames {
        let t = k as f64 / fps;
        let (i, f) = match step_of(t) {
            Some((i, f)) => (i - 1, f),
            None => (after(t), 0.0),
        };
        let (c0, y0) = mid(&holds[i]);
        let (c1, y1) = mid(&holds[(i + 1).min(p.n_steps)]);
        let c = c0.lerp(&c1, f);
        let moving = step_of(t).map_or(0.0, |_| 1.0);
        for (r, v) in raw.iter_mut().zip([c.x, c.y, y0 + (y1 - y0) * f, moving]) {
            r.push(v);
        }
    }
    let half = (0.5 * p.step_period_s * fps).round() as usize;
    let [xs, ys, yaws, walking] = raw.map(|r| moving_average(&r, half));
    let foot_pose = |h: &Foothold, lift: f64, roll: f64| {
        let yaw = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), h.yaw);
        let flat = Isometry3::from_parts(
            Translation3::new(h.pos.x, h.pos.y, sk.ankle_height_m + lift),
            yaw * sk.foot_rot,
        );
        if roll == 0.0 {
            return flat;
        }
        // Pitch about the toe's edge across the foot (the foot's lateral axis): a positive
        // angle about it turns the toe down and lifts the heel.
        let pivot = flat * nalgebra::Point3::from(sk.toe_m);
        let lateral = nalgebra::Unit::new_normalize(yaw * Vector3::y());
        let pitch = UnitQuaternion::from_axis_angle(&lateral, roll);
        let about = Translation3::from(pivot.coords);
        about * pitch * about.inverse() * flat
    };
    (0..n_frames)
        .map(|k| {
            let t = k as f64 / fps;
            let mut feet_h = holds[after(t)];
            let (mut lift, mut roll, mut sway, mut phase) = ([0.0; 2], [0.0; 2], 0.0, None);
            if let Some((i, f)) = step_of(t) {
                feet_h = holds[i - 1];
                let side = swing_side(p, i);
                let phi = ((f - DOUBLE_SUPPORT) / (1.0 - DOUBLE_SUPPORT)).clamp(0.0, 1.0);
                let s = smooth5(phi);
                let (a, b) = (holds[i - 1][side], holds[i][side]);
                feet_h[side] = Foothold {
                    pos: a.pos.lerp(&b.pos, s),
                    yaw: a.yaw + (b.yaw - a.yaw) * s,
                };
                lift[side] = p.lift_m * 16.0 * phi * phi * (1.0 - phi) * (1.0 - phi);
                // Rolls up through double support, levels out by mid-swing.
                roll[side] = p.roll_off_rad
                    * if f < DOUBLE_SUPPORT {
                        smooth5(f / DOUBLE_SUPPORT)
                    } else {
                        1.0 - smooth5(phi / 0.5)
                    };
                // Toward the stance foot (the other side) during the swing.
                let toward = if side == 0 { -1.0 } else { 1.0 };
                sway = toward * p.sway_m * (std::f64::consts::PI * phi).sin();
                phase = Some(phi);
            }
            let yaw = yaws[k];
            let xy = Vector2::new(xs[k], ys[k]) + rot2(yaw) * Vector2::new(0.0, sway);
            let swing = phase.map_or(0.0, |phi| (std::f64::consts::PI * phi).sin());
            let z = p.height_m - p.bob_m * walking[k] * (1.0 - swing);
            let rot = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), yaw);
            GaitFrame {
                pelvis: Isometry3::from_parts(Translation3::new(xy.x, xy.y, z), rot),
                feet: [0, 1].map(|s| foot_pose(&feet_h[s], lift[s], roll[s])),
                walking: walking[k],
                dir_world: rot * Vector3::new(p.direction, 0.0, 0.0),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point3;

    fn params(direction: f64, roll_off_rad: f64, turn_bout: Option<TurnBout>) -> GaitParams {
        GaitParams {
            direction,
            step_length_m: 0.34,
            step_period_s: 0.6,
            lift_m: 0.06,
            n_steps: 12,
            turn_per_step_rad: 0.0,
            start_s: 1.0,
            left_first: true,
            height_m: 0.75,
            bob_m: 0.01,
            sway_m: 0.02,
            half_width_m: 0.12,
            roll_off_rad,
            turn_bout,
        }
    }

    #[test]
    fn a_rolling_foot_keeps_its_toe_edge_on_the_ground_and_lifts_its_heel() {
        let robot = crate::sim::robot::load_bundled("g1_29dof").unwrap();
        let sk = Skeleton::new(&robot).unwrap();
        let fps = 50.0;
        let p = params(1.0, 0.4, None);
        let frames = walk(&sk, &p, fps, 500);
        // Step 3's double support: the swinging side rolls about its toe's edge.
        let (step, side) = (3, swing_side(&p, 3));
        let at = |f: f64| ((p.start_s + (step as f64 - 1.0 + f) * p.step_period_s) * fps) as usize;
        let (k0, k1) = (at(0.0) + 1, at(DOUBLE_SUPPORT) - 1);
        let toe = |k: usize| frames[k].feet[side] * Point3::from(sk.toe_m);
        let heel = |k: usize| frames[k].feet[side] * Point3::new(-0.05, 0.0, sk.toe_m.z);
        for k in k0..=k1 {
            assert!(
                (toe(k) - toe(k0)).norm() < 1e-9,
                "frame {k}: the toe's edge moved"
            );
            assert!((toe(k).z - (sk.ankle_height_m + sk.toe_m.z)).abs() < 1e-9);
        }
        assert!(
            heel(k1).z - heel(k0).z > 0.03,
            "the heel rose {} m",
            heel(k1).z - heel(k0).z
        );
        // It lands flat: the foot's orientation at the next foothold is yaw only.
        let land = at(1.0) - 1;
        let tilt = (frames[land].feet[side].rotation * sk.foot_rot.inverse()).euler_angles();
        assert!(tilt.0.abs() < 1e-6 && tilt.1.abs() < 1e-6, "{tilt:?}");
    }

    #[test]
    fn version_1s_gait_never_rolls_and_a_corner_turns_the_heading_by_its_angle() {
        let robot = crate::sim::robot::load_bundled("g1_29dof").unwrap();
        let sk = Skeleton::new(&robot).unwrap();
        let flat = walk(&sk, &params(1.0, 0.0, None), 50.0, 500);
        for f in &flat {
            for foot in &f.feet {
                let tilt = (foot.rotation * sk.foot_rot.inverse()).euler_angles();
                assert!(tilt.0.abs() < 1e-9 && tilt.1.abs() < 1e-9);
            }
        }
        let bout = TurnBout {
            first: 4,
            steps: 3,
            rad_per_step: 0.3,
        };
        let turned = walk(&sk, &params(1.0, 0.4, Some(bout)), 50.0, 500);
        let yaw = |f: &GaitFrame| f.pelvis.rotation.euler_angles().2;
        let turn = yaw(turned.last().unwrap()) - yaw(flat.last().unwrap());
        assert!((turn - 0.9).abs() < 1e-6, "turned {turn} rad");
    }
}
