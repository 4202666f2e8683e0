//! What the feet do on the ground: per foot and per control step, the ground's normal and
//! friction force, their ratio, the centre of pressure, and how far each sole point slid
//! while it touched the ground.
//!
//! Everything here is computed the same way whatever the engine, from the contacts a
//! backend reports ([`GroundContact`]: a point on a body, a normal and a friction force) and
//! the bodies' poses before and after each physics step. Slip is the horizontal
//! displacement, over a physics step in which it carried load, of the body point where the
//! contact was: the material point, so a foot pivoting on a sole sphere does not count as
//! sliding.

use crate::sim::physics::{GroundContact, Physics};
use crate::sim::robot::{Geometry, RobotModel};
use nalgebra::{Isometry3, Point3, Vector3};
use serde::{Deserialize, Serialize};

/// One sole point of a foot over a control step.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SolePoint {
    /// Mean normal force over the control step, N.
    pub normal_n: f64,
    /// Mean friction force magnitude over the control step, N.
    pub friction_n: f64,
    /// Mean sliding speed over the control step (distance slid while loaded / step), m/s.
    pub slip_speed_mps: f64,
    /// Distance slid while loaded since the episode started, m.
    pub slip_m: f64,
}

/// One foot over a control step.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FootContact {
    /// The foot's body name in the robot model.
    pub body: String,
    /// Mean normal force over the control step, N.
    pub normal_n: f64,
    /// Mean friction force over the control step, world frame, N.
    pub friction_w: [f64; 3],
    /// |friction| / normal (absent when the foot carried no load).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction_ratio: Option<f64>,
    /// Centre of pressure over the control step, world frame, m (absent without load).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cop_w: Option<[f64; 3]>,
    /// Load-weighted mean sliding speed of the sole points, m/s.
    pub slip_speed_mps: f64,
    /// Load-weighted slip accumulated since the episode started, m.
    pub slip_m: f64,
    /// The foot's sole points, in the robot model's order.
    pub soles: Vec<SolePoint>,
}

/// A foot of the robot model: a body carrying sole shapes.
#[derive(Debug, Clone)]
struct Foot {
    body: usize,
    name: String,
    /// Lowest points of the sole shapes, body frame (where a contact is attributed).
    soles_b: Vec<Point3<f64>>,
}

/// Running sums of one sole point.
#[derive(Debug, Clone, Default)]
struct SoleSums {
    normal_ns: f64,
    friction_ns: f64,
    slid_m: f64,
    total_slid_m: f64,
}

/// Running sums of one foot.
#[derive(Debug, Clone, Default)]
struct FootSums {
    normal_ns: f64,
    friction_ns: Vector3<f64>,
    cop_moment_ns: Vector3<f64>,
    /// Load-weighted slip of the control step so far, m.
    slid_m: f64,
    /// Within one physics step: Σ normal·slid (N·m) and Σ normal (N) of its contacts.
    step_moment_nm: f64,
    step_load_n: f64,
    slip_total_m: f64,
    soles: Vec<SoleSums>,
}

/// Accumulates foot contacts over the physics steps of a control step.
#[derive(Debug, Clone)]
pub struct FeetMeter {
    feet: Vec<Foot>,
    sums: Vec<FootSums>,
    contacts: Vec<GroundContact>,
}

impl FeetMeter {
    /// A meter for the feet of `model`: the bodies carrying sole shapes, in model order.
    pub fn new(model: &RobotModel) -> Self {
        let feet: Vec<Foot> = model
            .bodies
            .iter()
            .enumerate()
            .filter_map(|(i, b)| {
                let soles_b: Vec<Point3<f64>> = b
                    .shapes
                    .iter()
                    .filter(|s| s.is_sole)
                    .map(|s| {
                        let drop = match s.geometry {
                            Geometry::Sphere { radius } => radius,
                            _ => 0.0,
                        };
                        s.body_from_shape * Point3::origin() - Vector3::z() * drop
                    })
                    .collect();
                (!soles_b.is_empty()).then(|| Foot {
                    body: i,
                    name: b.name.clone(),
                    soles_b,
                })
            })
            .collect();
        let sums = feet
            .iter()
            .map(|f| FootSums {
                soles: vec![SoleSums::default(); f.soles_b.len()],
                ..Default::default()
            })
            .collect();
        Self {
            feet,
            sums,
            contacts: Vec::new(),
        }
    }

    /// Takes in the physics step just done: `before` and `after` are the bodies' poses at
    /// its start and end.
    pub fn after_step(
        &mut self,
        physics: &dyn Physics,
        before: &[Isometry3<f64>],
        after: &[Isometry3<f64>],
        dt_s: f64,
    ) {
        physics.ground_contacts(&mut self.contacts);
        for c in &self.contacts {
            let Some(k) = self.feet.iter().position(|f| f.body == c.body) else {
                continue;
            };
            let foot = &self.feet[k];
            let sums = &mut self.sums[k];
            let p_before = before[c.body] * c.point_b;
            let p_after = after[c.body] * c.point_b;
            let slid = (p_after - p_before).xy().norm();
            sums.normal_ns += c.normal_n * dt_s;
            sums.friction_ns += c.friction_w * dt_s;
            sums.cop_moment_ns += p_after.coords * (c.normal_n * dt_s);
            let nearest = foot
                .soles_b
                .iter()
                .enumerate()
                .min_by(|a, b| {
                    (a.1 - c.point_b)
                        .norm()
                        .total_cmp(&(b.1 - c.point_b).norm())
                })
                .map(|(i, _)| i)
                .expect("a foot has soles");
            let sole = &mut sums.soles[nearest];
            sole.normal_ns += c.normal_n * dt_s;
            sole.friction_ns += c.friction_w.norm() * dt_s;
            sole.slid_m += slid;
            sole.total_slid_m += slid;
            sums.step_moment_nm += c.normal_n * slid;
            sums.step_load_n += c.normal_n;
        }
        // Each foot's slip over this step: its contacts' slides weighted by their load.
        for sums in &mut self.sums {
            if sums.step_load_n > 0.0 {
                sums.slid_m += sums.step_moment_nm / sums.step_load_n;
            }
            sums.step_moment_nm = 0.0;
            sums.step_load_n = 0.0;
        }
    }

    /// Closes a control step of `control_dt_s`: the feet's means over it, and the running
    /// totals carried on.
    pub fn finish_step(&mut self, control_dt_s: f64) -> Vec<FootContact> {
        let mut out = Vec::with_capacity(self.feet.len());
        for (foot, sums) in self.feet.iter().zip(self.sums.iter_mut()) {
            let normal_n = sums.normal_ns / control_dt_s;
            let friction = sums.friction_ns / control_dt_s;
            let loaded = sums.normal_ns > 0.0;
            let slid_m = sums.slid_m;
            sums.slip_total_m += slid_m;
            out.push(FootContact {
                body: foot.name.clone(),
                normal_n,
                friction_w: friction.into(),
                friction_ratio: loaded.then(|| friction.norm() / normal_n),
                cop_w: loaded.then(|| (sums.cop_moment_ns / sums.normal_ns).into()),
                slip_speed_mps: slid_m / control_dt_s,
                slip_m: sums.slip_total_m,
                soles: sums
                    .soles
                    .iter()
                    .map(|s| SolePoint {
                        normal_n: s.normal_ns / control_dt_s,
                        friction_n: s.friction_ns / control_dt_s,
                        slip_speed_mps: s.slid_m / control_dt_s,
                        slip_m: s.total_slid_m,
                    })
                    .collect(),
            });
            sums.normal_ns = 0.0;
            sums.friction_ns = Vector3::zeros();
            sums.cop_moment_ns = Vector3::zeros();
            sums.slid_m = 0.0;
            for s in &mut sums.soles {
                s.normal_ns = 0.0;
                s.friction_ns = 0.0;
                s.slid_m = 0.0;
            }
        }
        out
    }
}
