//! Payloads: point masses rigidly held by a body, so a simulated hand carries an object's
//! weight and inertia and nothing else (no shape, no contact, no drag).
//!
//! An engine folds a body's point masses into that body's own inertial (mass, centre of
//! mass, inertia about it, by the parallel-axis theorem) before the episode starts; the
//! multibody dynamics then carry the weight and the inertia exactly, where an external
//! force `−m·(a − g)` computed from the last step's acceleration would lag a step and, for a
//! mass heavier than the hand's effective mass, diverge.

use crate::sim::robot::Body;
use nalgebra::{Matrix3, Point3, Vector3};

/// A point mass held rigidly at a point of a body.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointMass {
    /// Body index in the robot model (never the root: its frame is the floating base's).
    pub body: usize,
    /// Mass, kg (> 0).
    pub mass_kg: f64,
    /// Where it is held, in the body frame, m.
    pub point_b: Point3<f64>,
}

impl PointMass {
    /// Panics unless every payload is held by a body of a model of `n_bodies`, not its
    /// root (the rule of [`super::Physics::set_payloads`], shared by the backends).
    pub(crate) fn check_bodies(payloads: &[Self], n_bodies: usize) {
        for p in payloads {
            assert!(p.body != 0 && p.body < n_bodies, "payload body index");
        }
    }
}

/// A body's mass properties: mass, centre of mass and inertia about it, body axes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Inertial {
    /// Mass, kg.
    pub mass_kg: f64,
    /// Centre of mass in the body frame, m.
    pub com_b: Vector3<f64>,
    /// Inertia about the centre of mass, body axes, kg·m².
    pub inertia_kgm2: Matrix3<f64>,
}

impl Inertial {
    /// The model's own inertial of `body`.
    pub fn of(body: &Body) -> Self {
        Self {
            mass_kg: body.mass_kg,
            com_b: body.com_b,
            inertia_kgm2: body.inertia_kgm2,
        }
    }

    /// This inertial with point masses added: the masses add, the centre of mass is their
    /// weighted mean, and each part's inertia moves to the new centre by the parallel-axis
    /// theorem (`I + m (|d|² 1 − d dᵀ)`, a point mass having none of its own).
    pub fn with_point_masses<'p>(self, masses: impl IntoIterator<Item = &'p PointMass>) -> Self {
        let parts: Vec<(f64, Vector3<f64>, Matrix3<f64>)> =
            std::iter::once((self.mass_kg, self.com_b, self.inertia_kgm2))
                .chain(
                    masses
                        .into_iter()
                        .map(|p| (p.mass_kg, p.point_b.coords, Matrix3::zeros())),
                )
                .collect();
        let mass_kg: f64 = parts.iter().map(|p| p.0).sum();
        if parts.len() == 1 || mass_kg <= 0.0 {
            return self;
        }
        let com_b = parts.iter().map(|p| p.1 * p.0).sum::<Vector3<f64>>() / mass_kg;
        let inertia_kgm2 = parts
            .iter()
            .map(|(m, c, i)| {
                let d = c - com_b;
                i + (Matrix3::identity() * d.norm_squared() - d * d.transpose()) * *m
            })
            .sum();
        Self {
            mass_kg,
            com_b,
            inertia_kgm2,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_point_mass_shifts_the_centre_and_adds_its_parallel_axis_inertia() {
        // A 1 kg body with its centre at the origin and a 1 kg point at (0.2, 0, 0): the
        // centre moves to (0.1, 0, 0); about it each part sits 0.1 m away on x, adding
        // 2 · 1 kg · 0.01 m² about y and z, nothing about x.
        let own = Inertial {
            mass_kg: 1.0,
            com_b: Vector3::zeros(),
            inertia_kgm2: Matrix3::from_diagonal(&Vector3::new(0.01, 0.02, 0.03)),
        };
        let p = PointMass {
            body: 1,
            mass_kg: 1.0,
            point_b: Point3::new(0.2, 0.0, 0.0),
        };
        let loaded = own.with_point_masses([&p]);
        assert_eq!(loaded.mass_kg, 2.0);
        assert!((loaded.com_b - Vector3::new(0.1, 0.0, 0.0)).norm() < 1e-12);
        let expected = Matrix3::from_diagonal(&Vector3::new(0.01, 0.04, 0.05));
        assert!(
            (loaded.inertia_kgm2 - expected).norm() < 1e-12,
            "{}",
            loaded.inertia_kgm2
        );
        assert_eq!(own.with_point_masses([]), own);
    }
}
