//! The feet on the ground, kinematically: which sole points touch, the support polygon
//! they span, and how far a point on the ground lies outside it.
//!
//! The sole points are the robot's sole collision shapes (`robot.toml`'s
//! `sole_collision`: four small spheres under each G1 foot), the same points that carry
//! the robot in the simulator. A point touches when the bottom of its sphere is within
//! [`CONTACT_HEIGHT_M`] of the ground plane z = 0, the simulator's ground.

use crate::sim::robot::{Geometry, RobotModel};
use nalgebra::{Isometry3, Point2, Point3, Vector2};

/// A sole point whose lowest point is at most this high above the ground touches it, m.
/// Generous enough for a retargeted foot that floats a little, tight enough that a swing
/// foot's toe-off and heel-strike are not counted long before or after they happen.
pub const CONTACT_HEIGHT_M: f64 = 0.02;

/// Where each sole point is on the robot: its body, centre in the body frame, radius.
#[derive(Debug, Clone)]
pub struct SolePoints {
    points: Vec<(usize, Point3<f64>, f64)>,
}

/// One sole point at one frame.
#[derive(Debug, Clone, Copy)]
pub struct SoleSample {
    /// The body (foot) it belongs to.
    pub body: usize,
    /// Its lowest point, world frame, m.
    pub bottom_w: Point3<f64>,
}

impl SolePoints {
    /// The sole shapes of `robot`, each as a point (spheres) or its shape's centre.
    pub fn of(robot: &RobotModel) -> Self {
        let mut points = Vec::new();
        for (b, body) in robot.bodies.iter().enumerate() {
            for shape in body.shapes.iter().filter(|s| s.is_sole) {
                let radius = match shape.geometry {
                    Geometry::Sphere { radius } => radius,
                    _ => 0.0,
                };
                let centre = shape.body_from_shape * Point3::origin();
                points.push((b, centre, radius));
            }
        }
        Self { points }
    }

    /// Whether the robot has sole points at all.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Every sole point's lowest point for the body poses of one frame.
    pub fn sample(&self, world_from_body: &[Isometry3<f64>]) -> Vec<SoleSample> {
        self.points
            .iter()
            .map(|&(body, centre, radius)| {
                let mut bottom_w = world_from_body[body] * centre;
                bottom_w.z -= radius;
                SoleSample { body, bottom_w }
            })
            .collect()
    }
}

/// Convex hull of points in the plane, counter-clockwise, without collinear points
/// (Andrew's monotone chain). One or two points come back as they are (deduplicated).
pub fn convex_hull(points: &[Point2<f64>]) -> Vec<Point2<f64>> {
    let mut p: Vec<Point2<f64>> = points.to_vec();
    p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    p.dedup_by(|a, b| (*a - *b).norm() < 1e-12);
    if p.len() < 3 {
        return p;
    }
    let cross = |o: &Point2<f64>, a: &Point2<f64>, b: &Point2<f64>| (a - o).perp(&(b - o));
    let mut hull: Vec<Point2<f64>> = Vec::with_capacity(2 * p.len());
    for pass in [p.clone(), p.iter().rev().copied().collect()] {
        let start = hull.len();
        for q in pass {
            while hull.len() >= start + 2
                && cross(&hull[hull.len() - 2], &hull[hull.len() - 1], &q) <= 0.0
            {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop();
    }
    hull
}

/// Distance from `x` to the segment `a`–`b`.
fn segment_distance(x: &Point2<f64>, a: &Point2<f64>, b: &Point2<f64>) -> f64 {
    let ab: Vector2<f64> = b - a;
    let len2 = ab.norm_squared();
    let t = if len2 > 0.0 {
        ((x - a).dot(&ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (x - (a + ab * t)).norm()
}

/// How far `x` lies outside the convex polygon `hull` (counter-clockwise, as
/// [`convex_hull`] returns it), m; 0 inside or on it. A hull of one or two points is a
/// point or a segment.
pub fn distance_outside(hull: &[Point2<f64>], x: &Point2<f64>) -> f64 {
    match hull.len() {
        0 => f64::INFINITY,
        1 => (x - hull[0]).norm(),
        2 => segment_distance(x, &hull[0], &hull[1]),
        n => {
            let edges = (0..n).map(|i| (hull[i], hull[(i + 1) % n]));
            let inside = edges.clone().all(|(a, b)| (b - a).perp(&(x - a)) >= 0.0);
            if inside {
                0.0
            } else {
                edges
                    .map(|(a, b)| segment_distance(x, &a, &b))
                    .fold(f64::INFINITY, f64::min)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(x: f64, y: f64) -> Point2<f64> {
        Point2::new(x, y)
    }

    #[test]
    fn the_hull_of_a_square_with_an_inner_point_is_its_corners() {
        let h = convex_hull(&[p(0., 0.), p(1., 0.), p(0.5, 0.5), p(1., 1.), p(0., 1.)]);
        assert_eq!(h.len(), 4);
        assert_eq!(distance_outside(&h, &p(0.5, 0.5)), 0.0);
        assert!((distance_outside(&h, &p(1.5, 0.5)) - 0.5).abs() < 1e-12);
        assert!((distance_outside(&h, &p(2.0, 2.0)) - 2f64.sqrt()).abs() < 1e-12);
    }

    #[test]
    fn one_or_two_points_are_a_point_or_a_segment() {
        assert!((distance_outside(&convex_hull(&[p(1., 1.)]), &p(1., 2.)) - 1.0).abs() < 1e-12);
        let seg = convex_hull(&[p(0., 0.), p(2., 0.), p(2., 0.)]);
        assert_eq!(seg.len(), 2);
        assert!((distance_outside(&seg, &p(1., 0.3)) - 0.3).abs() < 1e-12);
        assert_eq!(distance_outside(&[], &p(0., 0.)), f64::INFINITY);
    }

    #[test]
    fn the_g1_has_four_sole_points_under_each_foot() {
        let g1 = crate::sim::robot::load_bundled("g1_29dof").unwrap();
        let soles = SolePoints::of(&g1);
        let mut poses = Vec::new();
        crate::sim::robot::forward_kinematics(
            &g1,
            &Isometry3::translation(0.0, 0.0, 0.793),
            &g1.default_pose(),
            &mut poses,
        );
        let samples = soles.sample(&poses);
        assert_eq!(samples.len(), 8);
        let feet: std::collections::BTreeSet<usize> = samples.iter().map(|s| s.body).collect();
        assert_eq!(feet.len(), 2);
    }
}
