//! Closing the loop between a plan and the data check (generator version 2): plan, solve
//! to joints, check the ground's centre of pressure against the feet's support with the
//! hand forces acting and without them (the benchmark replays both), shift the pelvis (and
//! the body with it) where either CoP is outside, repeat.
//!
//! The shift comes from the cart-table model of the whole body: a horizontal CoM offset
//! `Δ(t)` moves the CoP by `Δ − (z/g)·Δ̈` (z the CoM height), so to move the CoP by `−e(t)`
//! the offsets solve `Δ − (z/g)·Δ̈ = −e` over the whole sequence — a tridiagonal system,
//! diagonally dominant, solved in one sweep, zero at both ends. It is a non-causal
//! smoothing of `−e` with a time constant of `√(z/g)` ≈ 0.25 s: the body starts to lean
//! before a push builds up, as people brace for a load they see coming. The model is
//! approximate (the arms and the feet do not move with the pelvis, the CoM is not a
//! point); the check's own inverse dynamics closes the loop, so the approximation costs
//! iterations, not accuracy. Feet and hand targets stay where the plan put them.

use super::skeleton::Skeleton;
use super::solve::{realize, Solved};
use super::tasks::Plan;
use super::SynthError;
use crate::sim::motion::check::frames::frame_states;
use crate::sim::motion::check::support::{distance_outside, SolePoints};
use crate::sim::motion::check::CheckOptions;
use crate::sim::motion::{Sequence, LEFT, RIGHT};
use crate::sim::robot::RobotModel;
use nalgebra::{Point2, Vector2, Vector3};

/// The CoP is kept at least this far inside the support, m.
pub const MARGIN_M: f64 = 0.015;
/// Iterations of plan–check–shift at most.
pub const MAX_ITERATIONS: usize = 8;
/// The loop stops once no stance frame's CoP is further out than this, m.
pub const DONE_M: f64 = 0.005;
/// Largest horizontal shift of the pelvis from its planned path, m: beyond it the legs
/// leave their workspace, and a motion that needs more is not one to balance this way.
pub const MAX_SHIFT_M: f64 = 0.2;

/// How the loop ended, for the provenance.
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct BalanceStats {
    /// Iterations run.
    pub iterations: usize,
    /// Largest distance of the CoP outside the support before the loop, m.
    pub outside_before_m: f64,
    /// … and after it, m.
    pub outside_after_m: f64,
    /// Largest pelvis shift applied, m.
    pub shift_max_m: f64,
}

/// The plan's motion as a sequence whose sensor frames are its hand frames, with the
/// planned world forces: what the check reads.
fn as_sequence(robot: &RobotModel, plan: &Plan, solved: &Solved, fps: f64) -> Sequence {
    let force_sensor = [LEFT, RIGHT].map(|s| {
        plan.force_world[s]
            .iter()
            .zip(&solved.hand_rot[s])
            .map(|(f, r)| {
                let f = r.inverse_transform_vector(f);
                [f.x, f.y, f.z]
            })
            .collect()
    });
    Sequence {
        task: "balance".into(),
        sequence_id: "plan".into(),
        fps,
        joint_names: robot.joints.iter().map(|j| j.name.clone()).collect(),
        root_pos: plan
            .frames
            .iter()
            .map(|f| f.pelvis.translation.vector.into())
            .collect(),
        root_quat_wxyz: plan
            .frames
            .iter()
            .map(|f| {
                let q = f.pelvis.rotation;
                [q.w, q.i, q.j, q.k]
            })
            .collect(),
        joint_pos: solved.joint_pos.clone(),
        joint_vel: None,
        force_sensor,
        hand_from_sensor_wxyz: [[1.0, 0.0, 0.0, 0.0]; 2],
        force_point_hand: [LEFT, RIGHT].map(|s| robot.hands[s].point_hand.coords.into()),
        forces_recorded: true,
        force_frame: Default::default(),
        provenance: serde_json::Value::Null,
    }
}

/// Signed distance of `x` from the convex polygon `hull` (negative inside), m.
fn signed_distance(hull: &[Point2<f64>], x: &Point2<f64>) -> f64 {
    let outside = distance_outside(hull, x);
    if outside > 0.0 || hull.len() < 3 {
        return outside;
    }
    let n = hull.len();
    let inside = (0..n)
        .map(|i| {
            let (a, b) = (hull[i], hull[(i + 1) % n]);
            let edge = b - a;
            edge.perp(&(x - a)) / edge.norm().max(1e-12)
        })
        .fold(f64::INFINITY, f64::min);
    -inside
}

/// How far `cop` must move (toward the support's centre) to sit [`MARGIN_M`] inside
/// `support`, and its signed distance from it (negative inside).
fn move_inside(support: &[Point2<f64>], cop: &Point2<f64>) -> (Vector2<f64>, f64) {
    let sd = signed_distance(support, cop);
    if sd + MARGIN_M <= 0.0 {
        return (Vector2::zeros(), sd);
    }
    let centre = support.iter().map(|p| p.coords).sum::<Vector2<f64>>() / support.len() as f64;
    let away = cop.coords - centre;
    let along = away.norm();
    if along <= 1e-9 {
        return (Vector2::zeros(), sd);
    }
    (away / along * (sd + MARGIN_M).min(along), sd)
}

/// Per frame, how far the body's CoP must move to sit [`MARGIN_M`] inside the support
/// both with the hand forces acting and without them (the benchmark replays the motion
/// both ways): the sum of the two moves, so that where they disagree the shift settles
/// between them. Zero where both already sit inside, where no foot is down, or where the
/// ground would have to pull. Also the largest distance outside, with force or without.
fn cop_errors(
    robot: &RobotModel,
    seq: &Sequence,
    soles: &SolePoints,
    opts: &CheckOptions,
) -> Result<(Vec<Vector2<f64>>, f64), SynthError> {
    let check = |e: crate::sim::motion::check::CheckError| SynthError::Robot(e.to_string());
    let frames = frame_states(seq, robot, soles, opts).map_err(check)?;
    let mut errors = vec![Vector2::zeros(); seq.n_frames()];
    let mut worst: f64 = 0.0;
    for f in &frames {
        if f.support.is_empty() {
            continue;
        }
        for ground in [&f.ground_with_force, &f.ground_without_force] {
            let Some(cop) = ground.centre_of_pressure() else {
                continue;
            };
            let (error, sd) = move_inside(&f.support, &cop);
            worst = worst.max(sd);
            errors[f.frame] += error;
        }
    }
    Ok((errors, worst))
}

/// Solves `Δ_k − c·(Δ_{k+1} − 2Δ_k + Δ_{k−1})/dt² = r_k` with `Δ = 0` beyond both ends
/// (Thomas algorithm on a diagonally dominant system).
fn cart_table_offsets(r: &[f64], c_s2: f64, dt: f64) -> Vec<f64> {
    let n = r.len();
    let w = c_s2 / (dt * dt);
    let (lower, diag, upper) = (-w, 1.0 + 2.0 * w, -w);
    let mut cp = vec![0.0; n];
    let mut dp = vec![0.0; n];
    for k in 0..n {
        let denom = diag - if k > 0 { lower * cp[k - 1] } else { 0.0 };
        cp[k] = upper / denom;
        dp[k] = (r[k] - if k > 0 { lower * dp[k - 1] } else { 0.0 }) / denom;
    }
    let mut x = vec![0.0; n];
    for k in (0..n).rev() {
        x[k] = dp[k] - if k + 1 < n { cp[k] * x[k + 1] } else { 0.0 };
    }
    x
}

/// Balances `plan` under its own hand forces by shifting its pelvis path, and returns the
/// joints of the balanced plan (the plan is changed in place).
pub fn balance(
    robot: &RobotModel,
    sk: &Skeleton,
    plan: &mut Plan,
    fps: f64,
    task: &str,
    sequence: &str,
) -> Result<(Solved, BalanceStats), SynthError> {
    let soles = SolePoints::of(robot);
    let opts = CheckOptions::default();
    let g = -opts.gravity_w[2];
    let original: Vec<Vector3<f64>> = plan
        .frames
        .iter()
        .map(|f| f.pelvis.translation.vector)
        .collect();
    let mut stats = BalanceStats::default();
    let mut solved = realize(robot, sk, plan, task, sequence)?;
    for iteration in 0..=MAX_ITERATIONS {
        let seq = as_sequence(robot, plan, &solved, fps);
        let (errors, worst) = cop_errors(robot, &seq, &soles, &opts)?;
        if iteration == 0 {
            stats.outside_before_m = worst.max(0.0);
        }
        stats.outside_after_m = worst.max(0.0);
        stats.iterations = iteration;
        if worst <= DONE_M || iteration == MAX_ITERATIONS {
            break;
        }
        // CoM height: the pelvis's, lowered to the G1's CoM (about 0.1 m below it).
        let z = plan
            .frames
            .iter()
            .map(|f| f.pelvis.translation.z)
            .sum::<f64>()
            / plan.frames.len() as f64
            - 0.1;
        let c = z / g;
        let dt = 1.0 / fps;
        let dx = cart_table_offsets(&errors.iter().map(|e| -e.x).collect::<Vec<_>>(), c, dt);
        let dy = cart_table_offsets(&errors.iter().map(|e| -e.y).collect::<Vec<_>>(), c, dt);
        // A shift that takes a leg out of its workspace is halved, up to three times;
        // then the loop ends with the last plan the legs could follow.
        let before: Vec<Vector3<f64>> = plan
            .frames
            .iter()
            .map(|f| f.pelvis.translation.vector)
            .collect();
        let mut step = 1.0;
        let mut next = None;
        for _ in 0..4 {
            for (k, f) in plan.frames.iter_mut().enumerate() {
                let p = &mut f.pelvis.translation.vector;
                let mut shift = Vector2::new(
                    before[k].x + step * dx[k] - original[k].x,
                    before[k].y + step * dy[k] - original[k].y,
                );
                if shift.norm() > MAX_SHIFT_M {
                    shift *= MAX_SHIFT_M / shift.norm();
                }
                p.x = original[k].x + shift.x;
                p.y = original[k].y + shift.y;
            }
            match realize(robot, sk, plan, task, sequence) {
                Ok(s) => {
                    next = Some(s);
                    break;
                }
                Err(SynthError::IkFailed { .. }) => step *= 0.5,
                Err(e) => return Err(e),
            }
        }
        match next {
            Some(s) => solved = s,
            None => {
                for (f, p) in plan.frames.iter_mut().zip(&before) {
                    f.pelvis.translation.vector = *p;
                }
                break;
            }
        }
        stats.shift_max_m = plan
            .frames
            .iter()
            .zip(&original)
            .map(|(f, o)| (f.pelvis.translation.vector - o).xy().norm())
            .fold(stats.shift_max_m, f64::max);
    }
    Ok((solved, stats))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_constant_error_becomes_a_constant_offset_away_from_the_ends() {
        let x = cart_table_offsets(&vec![0.05; 500], 0.06, 0.02);
        assert!((x[250] - 0.05).abs() < 1e-6, "{}", x[250]);
        assert!(x[0].abs() < 0.01 && x[499].abs() < 0.01);
    }

    #[test]
    fn the_offsets_solve_the_cart_table_equation() {
        let r: Vec<f64> = (0..200).map(|k| (k as f64 * 0.1).sin() * 0.03).collect();
        let (c, dt) = (0.065, 0.02);
        let x = cart_table_offsets(&r, c, dt);
        for k in 1..199 {
            let lhs = x[k] - c * (x[k + 1] - 2.0 * x[k] + x[k - 1]) / (dt * dt);
            assert!((lhs - r[k]).abs() < 1e-9);
        }
    }

    #[test]
    fn the_signed_distance_is_negative_inside() {
        let sq = [
            Point2::new(0.0, 0.0),
            Point2::new(1.0, 0.0),
            Point2::new(1.0, 1.0),
            Point2::new(0.0, 1.0),
        ];
        assert!((signed_distance(&sq, &Point2::new(0.5, 0.2)) + 0.2).abs() < 1e-12);
        assert!((signed_distance(&sq, &Point2::new(1.5, 0.5)) - 0.5).abs() < 1e-12);
    }
}
