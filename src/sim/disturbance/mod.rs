//! Disturbances a setting puts on the robot instead of a recorded force history: force
//! events on the hands (SoftMimic's training shape), seeded random impulses on the torso or
//! a hand (the random pushes trackers are evaluated with), and payloads held at the wrists.
//!
//! A disturbance is a value a run records (`run.json`, each setting) and a table names by
//! its canonical spelling ([`Disturbance::name`]): two spellings of one disturbance are one
//! setting. What it applies at each physics step is a pure function of the specification,
//! the reference's initial heading and, for impulses, the seed and the sequence id
//! ([`ActiveDisturbance`]), so the same episode applies the same forces on any engine.

mod event;
mod impulse;
mod spelling;

pub use spelling::{fits_name, MAX_NUMBER_CHARS};

pub use event::ForceEvent;
pub use impulse::{ImpulseTarget, Impulses, Pulse};

use crate::sim::motion::{LEFT, RIGHT};
use crate::sim::physics::PointMass;
use crate::sim::robot::RobotModel;
use nalgebra::{Point3, Vector3};
use serde::{Deserialize, Serialize};

/// Which hands a disturbance acts on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Hands {
    /// The left hand only.
    Left,
    /// The right hand only.
    Right,
    /// Each hand, the same.
    Both,
}

impl Hands {
    /// Whether side `s` ([`LEFT`] or [`RIGHT`]) is one of these hands.
    pub fn includes(self, s: usize) -> bool {
        match self {
            Self::Left => s == LEFT,
            Self::Right => s == RIGHT,
            Self::Both => true,
        }
    }

    /// The spelling in a setting (`left`, `right`, `both`).
    pub fn word(self) -> &'static str {
        match self {
            Self::Left => "left",
            Self::Right => "right",
            Self::Both => "both",
        }
    }
}

/// Masses held at the wrists: their weight and inertia, nothing else.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Payload {
    /// Mass at each hand it is held by, kg.
    pub mass_kg: f64,
    /// The hands holding one.
    pub hands: Hands,
}

impl Payload {
    /// Largest mass per hand accepted, kg (a G1 arm is rated for a few kilograms; FALCON's
    /// payloads reach 20 N, about 2 kg).
    pub const MAX_KG: f64 = 20.0;

    /// The point masses on `robot`: at each holding hand's force application point.
    pub fn point_masses(&self, robot: &RobotModel) -> Vec<PointMass> {
        [LEFT, RIGHT]
            .into_iter()
            .filter(|&s| self.hands.includes(s) && self.mass_kg > 0.0)
            .map(|s| {
                let hand = &robot.hands[s];
                let frame = &robot.frames[hand.frame];
                PointMass {
                    body: frame.body,
                    mass_kg: self.mass_kg,
                    point_b: frame.body_from_frame * hand.point_hand,
                }
            })
            .collect()
    }
}

/// One disturbance of a setting.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Disturbance {
    /// A force event on one hand or both: ramp, hold, release.
    Event(ForceEvent),
    /// Random pushes at seeded times.
    Impulses(Impulses),
    /// Masses held at the wrists.
    Payload(Payload),
}

impl Disturbance {
    /// Parses `event:…`, `impulse:…` or `payload:…` (see [`Self::SYNTAX`]): `None` when `s`
    /// starts with none of them, `Some(Err(why))` when it does but is malformed.
    pub fn parse(s: &str) -> Option<Result<Self, String>> {
        spelling::parse(s)
    }

    /// The spellings, for messages and `--help`.
    pub const SYNTAX: &'static str = spelling::SYNTAX;

    /// The canonical spelling, every field given: the setting's name, so two spellings of
    /// one disturbance name one setting.
    pub fn name(&self) -> String {
        spelling::name(self)
    }
}

/// A disturbance made ready for one episode: the direction of an event fixed by the
/// reference's initial heading, the impulses drawn for this sequence, the torso's
/// application point found.
#[derive(Debug, Clone)]
pub struct ActiveDisturbance {
    /// The world-frame unit direction of an event.
    event_direction_w: Vector3<f64>,
    disturbance: Disturbance,
    /// Impulses of this episode, in time order.
    pulses: Vec<Pulse>,
    /// The torso's body and the point its impulses act at, body frame.
    torso: (usize, Point3<f64>),
}

impl ActiveDisturbance {
    /// `disturbance` for an episode of `sequence_id` lasting `duration_s`, whose reference
    /// starts heading `initial_heading_rad` (yaw of the root's x axis) on `robot`.
    pub fn new(
        disturbance: &Disturbance,
        robot: &RobotModel,
        initial_heading_rad: f64,
        sequence_id: &str,
        duration_s: f64,
    ) -> Self {
        let event_direction_w = match disturbance {
            Disturbance::Event(e) => e.direction_w(initial_heading_rad),
            _ => Vector3::zeros(),
        };
        let pulses = match disturbance {
            Disturbance::Impulses(i) => i.draw(sequence_id, duration_s),
            _ => Vec::new(),
        };
        let torso = robot
            .frame_index("torso_link")
            .map(|f| {
                let frame = &robot.frames[f];
                (frame.body, frame.body_from_frame * Point3::origin())
            })
            .unwrap_or((0, Point3::origin()));
        Self {
            event_direction_w,
            disturbance: disturbance.clone(),
            pulses,
            torso,
        }
    }

    /// The world-frame force on each hand at `t_s`, N.
    pub fn hand_forces_w(&self, t_s: f64) -> [Vector3<f64>; 2] {
        match &self.disturbance {
            Disturbance::Event(e) => {
                let f = self.event_direction_w * e.magnitude_at(t_s);
                [LEFT, RIGHT].map(|s| {
                    if e.hands.includes(s) {
                        f
                    } else {
                        Vector3::zeros()
                    }
                })
            }
            Disturbance::Impulses(_) => [LEFT, RIGHT].map(|s| {
                self.pulse_at(t_s)
                    .filter(|p| p.target == ImpulseTarget::Hand(s))
                    .map_or_else(Vector3::zeros, |p| p.force_w)
            }),
            Disturbance::Payload(_) => [Vector3::zeros(); 2],
        }
    }

    /// The world-frame force on the torso at `t_s`, N, with its body and application point
    /// (body frame); `None` when this disturbance never pushes the torso.
    pub fn torso_force_w(&self, t_s: f64) -> Option<(usize, Point3<f64>, Vector3<f64>)> {
        match &self.disturbance {
            Disturbance::Impulses(i) if i.target == ImpulseTarget::Torso => {
                let f = self
                    .pulse_at(t_s)
                    .map_or_else(Vector3::zeros, |p| p.force_w);
                Some((self.torso.0, self.torso.1, f))
            }
            _ => None,
        }
    }

    /// This episode's impulses, in time order.
    pub fn pulses(&self) -> &[Pulse] {
        &self.pulses
    }

    /// The pulse acting at `t_s` (pulses never overlap).
    fn pulse_at(&self, t_s: f64) -> Option<&Pulse> {
        self.pulses.iter().find(|p| p.acts_at(t_s))
    }
}
