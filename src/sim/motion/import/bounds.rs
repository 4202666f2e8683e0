//! The bounds every imported motion is held to, whatever its format (motion files, force
//! logs, rollout traces), and every dataset file on load: joint angles within their
//! joint's limits widened by [`JOINT_LIMIT_MARGIN_RAD`], root orientations that are
//! rotations, and hand forces within [`MAX_HAND_FORCE_N`]. Each check returns why a value
//! is refused (or `None`); the caller names the file, frame and field.

use crate::files::names::short_number;
use crate::sim::robot::Joint;

/// How far beyond a joint's limits an imported angle may lie, rad: retargeted human motion
/// overshoots a limit by a little (the controller's PD law clamps it), while a value far
/// beyond one is a broken file (a unit mix-up, a corrupt cell) that would be stored and
/// scored as if it were motion.
pub const JOINT_LIMIT_MARGIN_RAD: f64 = 1.0;

/// The largest force on one hand a sequence may hold, N. The bundled tasks peak near
/// 100 N for both hands together, and the task levels SOURCES.md ("Task forces") cites
/// reach 100 N to break a chair loose and 145–168 N for Thor's pulls (arXiv 2510.26280);
/// five hundred newtons on one hand is far above any of them, and a force far beyond it
/// is a broken file (a unit mix-up, a corrupt sample) that would fell the robot and be
/// scored as the policy's fall.
pub const MAX_HAND_FORCE_N: f64 = 500.0;

/// Why `angle` (rad) is no angle `joint` can take within [`JOINT_LIMIT_MARGIN_RAD`] of its
/// limits, or `None`.
pub fn joint_angle_problem(joint: &Joint, angle: f64) -> Option<String> {
    let (lo, hi) = (
        joint.lower_rad - JOINT_LIMIT_MARGIN_RAD,
        joint.upper_rad + JOINT_LIMIT_MARGIN_RAD,
    );
    (!(lo..=hi).contains(&angle)).then(|| {
        format!(
            "`{}` is {} rad, outside the joint's limits {:.3} to {:.3} rad widened by {JOINT_LIMIT_MARGIN_RAD} rad",
            joint.name,
            short_number(angle),
            joint.lower_rad,
            joint.upper_rad
        )
    })
}

/// Why `q` (w, x, y, z) is no rotation (a zero, infinite or NaN quaternion), or `None`.
/// Its norm's distance from 1 is the caller's to judge (repaired on request at import).
pub fn rotation_problem(q: &[f64; 4]) -> Option<String> {
    let n = q.iter().map(|x| x * x).sum::<f64>().sqrt();
    (!n.is_finite() || n < 1e-9).then(|| {
        format!(
            "root quaternion {} is not a rotation (norm {})",
            short_quat(q),
            short_number(n)
        )
    })
}

/// Why `force_n` (N, any frame) is no plausible force on one hand (beyond
/// [`MAX_HAND_FORCE_N`], or not a number), or `None`.
pub fn hand_force_problem(force_n: &[f64; 3]) -> Option<String> {
    let n = force_n.iter().map(|x| x * x).sum::<f64>().sqrt();
    (n.is_nan() || n > MAX_HAND_FORCE_N).then(|| {
        format!(
            "a hand force of {} N, beyond the plausibility bound of {MAX_HAND_FORCE_N} N a hand (no task comes near it)",
            short_number(n)
        )
    })
}

fn short_quat(q: &[f64; 4]) -> String {
    let parts: Vec<String> = q.iter().map(|x| short_number(*x)).collect();
    format!("({})", parts.join(", "))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn knee() -> Joint {
        crate::sim::robot::load_bundled("g1_29dof").unwrap().joints[3].clone()
    }

    #[test]
    fn an_angle_a_little_past_a_limit_passes_and_one_far_past_it_is_refused() {
        let j = knee();
        assert!(joint_angle_problem(&j, j.upper_rad + 0.5).is_none());
        let why = joint_angle_problem(&j, 10.0).unwrap();
        assert!(
            why.contains("left_knee_joint") && why.contains("10 rad"),
            "{why}"
        );
        assert!(joint_angle_problem(&j, f64::NAN).is_some());
        let why = joint_angle_problem(&j, 1e30).unwrap();
        assert!(why.contains("1e30 rad"), "{why}");
    }

    #[test]
    fn a_zero_quaternion_is_no_rotation_and_a_unit_one_is() {
        assert!(rotation_problem(&[1.0, 0.0, 0.0, 0.0]).is_none());
        let why = rotation_problem(&[0.0; 4]).unwrap();
        assert!(
            why.contains("root quaternion") && why.contains("norm 0"),
            "{why}"
        );
        assert!(rotation_problem(&[f64::NAN, 0.0, 0.0, 0.0]).is_some());
    }

    #[test]
    fn a_hand_force_beyond_the_bound_is_refused_short() {
        assert!(hand_force_problem(&[300.0, 300.0, 0.0]).is_none());
        assert!(hand_force_problem(&[400.0, 400.0, 0.0]).is_some());
        assert!(hand_force_problem(&[f64::NAN, 0.0, 0.0]).is_some());
        let why = hand_force_problem(&[0.0, 0.0, 1e30]).unwrap();
        assert!(why.contains("1e30 N") && why.len() < 200, "{why}");
    }
}
