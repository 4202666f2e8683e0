//! Force replay: a recorded sensor-frame hand force becomes a world-frame force on the
//! simulated hand — sensor → hand (the sequence's calibration) → world (the hand's pose in
//! the simulation at that physics step) × a coefficient (1 = force setting, 0 = no force).
//! A history stored in the world frame ([`ForceFrame::World`], a grafted one) is replayed
//! as it is. A constant push or a [`crate::sim::disturbance`] adds its own world-frame
//! forces.

use crate::sim::disturbance::ActiveDisturbance;
use crate::sim::motion::{ForceFrame, Reference, Sequence, LEFT, RIGHT};
use crate::sim::physics::{ExternalForce, Physics};
use crate::sim::robot::RobotModel;
use nalgebra::{Isometry3, Point3, Quaternion, UnitQuaternion, Vector3};

/// `coefficient · R_world←hand · R_hand←sensor · f_sensor`.
pub fn world_force(
    world_from_hand: &Isometry3<f64>,
    hand_from_sensor: &UnitQuaternion<f64>,
    force_sensor: &Vector3<f64>,
    coefficient: f64,
) -> Vector3<f64> {
    world_from_hand.rotation * (hand_from_sensor * force_sensor) * coefficient
}

/// A constant push ramps in linearly over this long from the episode's start, s.
pub const PUSH_RAMP_S: f64 = 1.0;

/// Replays one sequence's hand forces onto a physics backend.
#[derive(Debug, Clone)]
pub struct ForceReplay {
    /// Scale of the replayed force (1 = as recorded, 0 = none).
    pub coefficient: f64,
    /// A constant world-frame force added on each hand, N, ramped over [`PUSH_RAMP_S`].
    pub push_w: Vector3<f64>,
    hand_from_sensor: [UnitQuaternion<f64>; 2],
    /// Per side: body index and application point in the body frame.
    application: [(usize, Point3<f64>); 2],
    /// Per side: the hand frame in its body frame.
    body_from_hand: [Isometry3<f64>; 2],
    /// Events or impulses added to the hands (and the torso).
    disturbance: Option<ActiveDisturbance>,
    /// The frame the sequence's forces are in: a world-frame history skips the hand pose.
    frame: ForceFrame,
}

impl ForceReplay {
    /// Prepares the replay of `seq` on `robot` (calibration and application point come from
    /// the sequence; the hand frames from the robot).
    pub fn new(robot: &RobotModel, seq: &Sequence, coefficient: f64) -> Self {
        let side = |s: usize| {
            let frame = &robot.frames[robot.hands[s].frame];
            let p = seq.force_point_hand[s];
            let q = seq.hand_from_sensor_wxyz[s];
            (
                UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3])),
                (
                    frame.body,
                    frame.body_from_frame * Point3::new(p[0], p[1], p[2]),
                ),
                frame.body_from_frame,
            )
        };
        let (l, r) = (side(LEFT), side(RIGHT));
        Self {
            coefficient,
            push_w: Vector3::zeros(),
            hand_from_sensor: [l.0, r.0],
            application: [l.1, r.1],
            body_from_hand: [l.2, r.2],
            disturbance: None,
            frame: seq.force_frame,
        }
    }

    /// Adds a disturbance's forces (events on the hands, impulses on the hands or the
    /// torso; a payload acts through the bodies' mass, not here).
    pub fn with_disturbance(mut self, disturbance: ActiveDisturbance) -> Self {
        self.disturbance = Some(disturbance);
        self
    }

    /// Adds a constant world-frame push on each hand (ramped in over [`PUSH_RAMP_S`]).
    pub fn with_push(mut self, push_w: Vector3<f64>) -> Self {
        self.push_w = push_w;
        self
    }

    /// The world-frame forces for the reference at `t_s` and the hands' current world poses
    /// (`world_from_body` from the physics state).
    pub fn forces_at(
        &self,
        reference: &Reference,
        t_s: f64,
        world_from_body: &[Isometry3<f64>],
    ) -> [Vector3<f64>; 2] {
        let f = reference.sample(t_s).force_sensor;
        let push = self.push_w * (t_s / PUSH_RAMP_S).clamp(0.0, 1.0);
        let disturbance = self
            .disturbance
            .as_ref()
            .map_or([Vector3::zeros(); 2], |d| d.hand_forces_w(t_s));
        [LEFT, RIGHT].map(|s| {
            let recorded = match self.frame {
                ForceFrame::Sensor => {
                    let world_from_hand =
                        world_from_body[self.application[s].0] * self.body_from_hand[s];
                    world_force(
                        &world_from_hand,
                        &self.hand_from_sensor[s],
                        &f[s],
                        self.coefficient,
                    )
                }
                ForceFrame::World => f[s] * self.coefficient,
            };
            recorded + push + disturbance[s]
        })
    }

    /// Sets the hand forces for the coming physics step: the reference at the physics
    /// clock's current time, rotated by the current hand poses, and a disturbance's torso
    /// force. Call before every step. Returns the hand forces.
    pub fn apply(
        &self,
        physics: &mut dyn Physics,
        reference: &Reference,
        world_from_body: &[Isometry3<f64>],
    ) -> [Vector3<f64>; 2] {
        let forces = self.forces_at(reference, physics.time_s(), world_from_body);
        for s in [LEFT, RIGHT] {
            let (body, point_b) = self.application[s];
            physics.set_external_force(ExternalForce {
                body,
                force_w: forces[s],
                point_b,
            });
        }
        if let Some((body, point_b, force_w)) = self
            .disturbance
            .as_ref()
            .and_then(|d| d.torso_force_w(physics.time_s()))
        {
            physics.set_external_force(ExternalForce {
                body,
                force_w,
                point_b,
            });
        }
        forces
    }
}
