//! The per-timestep keypoint error with root re-anchoring.

use nalgebra::{Isometry3, Point3};

/// Reference keypoints mapped to the world as if the reference root stood where the robot's
/// root is: `world_from_robot_root · ref_root⁻¹ · x_ref`. Global drift so drops out of the
/// error (it is reported apart, as root drift).
pub fn reanchor(
    ref_keypoints_w: &[Point3<f64>],
    world_from_ref_root: &Isometry3<f64>,
    world_from_robot_root: &Isometry3<f64>,
    out: &mut Vec<Point3<f64>>,
) {
    let robot_from_ref = world_from_robot_root * world_from_ref_root.inverse();
    out.clear();
    out.extend(ref_keypoints_w.iter().map(|p| robot_from_ref * p));
}

/// Mean Euclidean distance between matching keypoints, m (`e_kp(t)` of the paper).
pub fn keypoint_error_m(reference: &[Point3<f64>], robot: &[Point3<f64>]) -> f64 {
    assert_eq!(reference.len(), robot.len(), "keypoint count");
    if reference.is_empty() {
        return 0.0;
    }
    reference
        .iter()
        .zip(robot)
        .map(|(a, b)| (a - b).norm())
        .sum::<f64>()
        / reference.len() as f64
}
