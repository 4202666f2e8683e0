//! Forward kinematics on the robot model, independent of any physics engine.
//!
//! Used to place bodies at reset, to compute reference keypoints from a motion, and to
//! check that the physics backend agrees with the model.

use super::model::RobotModel;
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};

/// World poses of every body for a root pose and joint angles (canonical order).
///
/// `world_from_body` is resized to the number of bodies; reuse it to avoid allocation.
pub fn forward_kinematics(
    model: &RobotModel,
    world_from_root: &Isometry3<f64>,
    q: &[f64],
    world_from_body: &mut Vec<Isometry3<f64>>,
) {
    assert_eq!(q.len(), model.n_joints(), "joint vector length");
    world_from_body.clear();
    for body in &model.bodies {
        let pose = match (body.parent, body.joint) {
            (Some(p), Some(j)) => {
                let rot = UnitQuaternion::from_axis_angle(&body.axis, q[j]);
                world_from_body[p]
                    * body.parent_from_joint
                    * Isometry3::from_parts(Translation3::identity(), rot)
            }
            _ => *world_from_root,
        };
        world_from_body.push(pose);
    }
}

/// World pose of a named frame given the body poses.
pub fn frame_pose(
    model: &RobotModel,
    world_from_body: &[Isometry3<f64>],
    frame: usize,
) -> Isometry3<f64> {
    let f = &model.frames[frame];
    world_from_body[f.body] * f.body_from_frame
}

/// World-frame velocity of a named frame: linear (of the frame's origin, m/s) and angular
/// (rad/s), from the root's velocity (`root_lin_vel_w` of the root frame's origin) and the
/// joint velocities `qd` (canonical order), given the body poses of the same state.
///
/// The velocity of the chain from the root to the frame's body, joint by joint: each
/// revolute joint on it adds `axis_w · q̇` to the angular velocity and
/// `axis_w × (p − p_joint) · q̇` to the frame origin's linear velocity. Used for the
/// reference anchor's velocities, which a motion file carries per body but the canonical
/// format derives.
pub fn frame_velocity_w(
    model: &RobotModel,
    world_from_body: &[Isometry3<f64>],
    root_lin_vel_w: &Vector3<f64>,
    root_ang_vel_w: &Vector3<f64>,
    qd: &[f64],
    frame: usize,
) -> (Vector3<f64>, Vector3<f64>) {
    let f = &model.frames[frame];
    let p = (world_from_body[f.body] * f.body_from_frame)
        .translation
        .vector;
    let root_p = world_from_body[0].translation.vector;
    let mut lin = root_lin_vel_w + root_ang_vel_w.cross(&(p - root_p));
    let mut ang = *root_ang_vel_w;
    let mut body = f.body;
    while let (Some(parent), Some(j)) = (model.bodies[body].parent, model.bodies[body].joint) {
        let pose = &world_from_body[body];
        let axis_w = pose.rotation * model.bodies[body].axis.into_inner();
        ang += axis_w * qd[j];
        lin += axis_w.cross(&(p - pose.translation.vector)) * qd[j];
        body = parent;
    }
    (lin, ang)
}

/// World positions of a keypoint set's frames, upper-body ones first.
pub fn keypoint_positions(
    model: &RobotModel,
    world_from_body: &[Isometry3<f64>],
    set: &super::model::KeypointSet,
    out: &mut Vec<Point3<f64>>,
) {
    out.clear();
    out.extend(
        set.frames
            .iter()
            .map(|&f| frame_pose(model, world_from_body, f) * Point3::origin()),
    );
}

/// Whole-body centre of mass in the world frame.
pub fn center_of_mass(model: &RobotModel, world_from_body: &[Isometry3<f64>]) -> Point3<f64> {
    let mut sum = Vector3::zeros();
    for (b, pose) in model.bodies.iter().zip(world_from_body) {
        sum += (pose * Point3::from(b.com_b)).coords * b.mass_kg;
    }
    Point3::from(sum / model.total_mass_kg())
}

/// Height of the lowest point of the sole shapes, world frame; `None` if the model has no
/// sole shapes.
pub fn lowest_sole_point_z(model: &RobotModel, world_from_body: &[Isometry3<f64>]) -> Option<f64> {
    lowest_sole_point_z_of(model, world_from_body, |_| true)
}

/// [`lowest_sole_point_z`] over the bodies `which` accepts (by body index): one foot's.
pub fn lowest_sole_point_z_of(
    model: &RobotModel,
    world_from_body: &[Isometry3<f64>],
    which: impl Fn(usize) -> bool,
) -> Option<f64> {
    let mut lowest: Option<f64> = None;
    for (_, (body, pose)) in model
        .bodies
        .iter()
        .zip(world_from_body)
        .enumerate()
        .filter(|(i, _)| which(*i))
    {
        for shape in body.shapes.iter().filter(|s| s.is_sole) {
            let p = pose * shape.body_from_shape;
            let z = p.translation.vector.z - support_depth(&shape.geometry, &p.rotation);
            lowest = Some(lowest.map_or(z, |l: f64| l.min(z)));
        }
    }
    lowest
}

/// How far a shape reaches below its centre along −z, given its world orientation.
fn support_depth(g: &super::model::Geometry, rot: &UnitQuaternion<f64>) -> f64 {
    use super::model::Geometry;
    let m = rot.to_rotation_matrix();
    let row_z = m.matrix().row(2);
    match *g {
        Geometry::Sphere { radius } => radius,
        Geometry::Box { half_extents: h } => (0..3).map(|k| row_z[k].abs() * h[k]).sum(),
        Geometry::Capsule {
            radius,
            half_length,
        } => row_z[2].abs() * half_length + radius,
        Geometry::Cylinder {
            radius,
            half_length,
        } => row_z[2].abs() * half_length + radius * (1.0 - row_z[2] * row_z[2]).max(0.0).sqrt(),
    }
}
