//! Conversions between our f64 nalgebra types and rapier's f32 glam types.

use nalgebra::{Isometry3, Point3, Quaternion, Translation3, UnitQuaternion, Vector3};
use rapier3d::prelude::{Pose, Rotation, Vector};

pub(super) fn vec_to_rapier(v: &Vector3<f64>) -> Vector {
    Vector::new(v.x as f32, v.y as f32, v.z as f32)
}

pub(super) fn point_to_rapier(p: &Point3<f64>) -> Vector {
    Vector::new(p.x as f32, p.y as f32, p.z as f32)
}

pub(super) fn vec_from_rapier(v: Vector) -> Vector3<f64> {
    Vector3::new(v.x as f64, v.y as f64, v.z as f64)
}

pub(super) fn rot_to_rapier(q: &UnitQuaternion<f64>) -> Rotation {
    Rotation::from_xyzw(q.i as f32, q.j as f32, q.k as f32, q.w as f32).normalize()
}

pub(super) fn pose_to_rapier(p: &Isometry3<f64>) -> Pose {
    Pose::from_parts(
        vec_to_rapier(&p.translation.vector),
        rot_to_rapier(&p.rotation),
    )
}

pub(super) fn pose_from_rapier(p: &Pose) -> Isometry3<f64> {
    let r = p.rotation;
    let q = Quaternion::new(r.w as f64, r.x as f64, r.y as f64, r.z as f64);
    Isometry3::from_parts(
        Translation3::from(vec_from_rapier(p.translation)),
        UnitQuaternion::from_quaternion(q),
    )
}
