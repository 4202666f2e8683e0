//! The forces a family's networks were trained with on the robot: a policy scored under a
//! force its training never showed it is measured off its distribution, and every table
//! says so where it happens ([`TrainedForces::holds_push`],
//! [`TrainedForces::holds_hand_forces`], [`TrainedForces::outside_disturbance`]), shown,
//! never hidden.

use crate::sim::disturbance::{Disturbance, Hands, ImpulseTarget};
use crate::sim::motion::check::HandForceSpan;

/// What a family saw on its hands in training.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TrainedForces {
    /// Not a trained network (the built-ins).
    Untrained,
    /// Trained without forces on the robot (the general trackers): every force setting is
    /// outside its training by design — the benchmark measures what that costs — so its
    /// cells are not marked one by one.
    Blind,
    /// Not known: a network of the user's or a policy process.
    Unknown,
    /// A curriculum of forces on both hands (FALCON): per hand, a horizontal force up to
    /// `horizontal_max_n` while walking and none standing, a vertical one inside
    /// `vertical_n` (negative: down).
    HandCurriculum {
        /// Largest horizontal force on a hand, N (while walking).
        horizontal_max_n: f64,
        /// Vertical force on a hand, lowest and highest, N (z up).
        vertical_n: (f64, f64),
        /// Where the numbers are.
        source: &'static str,
    },
    /// Force events on one wrist at a time (SoftMimic): a ramp, a hold, a release; the
    /// force bounded by the commanded stiffness times a largest yield and by a cap.
    WristEvents {
        /// Shortest and longest ramp of an event, s.
        ramp_s: (f64, f64),
        /// Longest hold of an event, s.
        hold_max_s: f64,
        /// Largest displacement the force may ask of the wrist, m (F ≤ k · this).
        yield_max_m: f64,
        /// Largest force, N.
        force_max_n: f64,
        /// Where the numbers are.
        source: &'static str,
    },
}

/// FALCON's force curriculum.
pub const FALCON_FORCES: TrainedForces = TrainedForces::HandCurriculum {
    horizontal_max_n: 40.0,
    vertical_n: (-50.0, 5.0),
    source: "LeCAR-Lab/FALCON, humanoidverse/config/env/decoupled_locomotion_stand_height_waist_wbc_ma_diff_force.yaml",
};

/// SoftMimic's force events.
pub const SOFTMIMIC_FORCES: TrainedForces = TrainedForces::WristEvents {
    ramp_s: (0.1, 2.0),
    hold_max_s: 1.0,
    yield_max_m: 0.7,
    force_max_n: 140.0,
    source:
        "robodreamer/softmimic, compliant_motion_augmentation/constants.py and force_profile.py",
};

/// What the sensor's noise may add to a measured force before it counts as outside, N.
pub const MEASURED_TOLERANCE_N: f64 = 2.0;

impl TrainedForces {
    /// Whether there is an envelope to judge a load against (a family trained with
    /// forces of a known shape).
    pub fn has_envelope(&self) -> bool {
        !matches!(self, Self::Untrained | Self::Blind | Self::Unknown)
    }

    /// One line for `thorarena policies` and the tables' notes.
    pub fn describe(&self) -> String {
        match self {
            Self::Untrained => "not trained (a built-in)".into(),
            Self::Blind => "trained without forces on the robot".into(),
            Self::Unknown => "unknown".into(),
            Self::HandCurriculum {
                horizontal_max_n,
                vertical_n,
                source,
            } => format!(
                "a curriculum on both hands: horizontal up to {horizontal_max_n} N while walking, none standing; vertical {} to {} N ({source})",
                vertical_n.0, vertical_n.1
            ),
            Self::WristEvents {
                ramp_s,
                hold_max_s,
                yield_max_m,
                force_max_n,
                source,
            } => format!(
                "events on one wrist at a time, ramped over {} to {} s, held at most {hold_max_s} s, F ≤ stiffness × {yield_max_m} m and ≤ {force_max_n} N ({source})",
                ramp_s.0, ramp_s.1
            ),
        }
    }

    /// Whether a constant push of `per_hand_n` on every hand, held `held_s`, lies inside
    /// the training (`None`: nothing to judge, [`TrainedForces::Blind`] or `Unknown`).
    /// `stiffness_n_per_m` is the commanded stiffness of a [`TrainedForces::WristEvents`]
    /// family; `walking` whether the motion walks.
    pub fn holds_push(
        &self,
        per_hand_n: f64,
        held_s: f64,
        both_hands: bool,
        stiffness_n_per_m: Option<f64>,
        walking: bool,
    ) -> Option<bool> {
        match *self {
            Self::Untrained | Self::Blind | Self::Unknown => None,
            Self::HandCurriculum {
                horizontal_max_n, ..
            } => Some(per_hand_n <= horizontal_max_n && (walking || per_hand_n == 0.0)),
            Self::WristEvents {
                hold_max_s,
                yield_max_m,
                force_max_n,
                ..
            } => {
                let bound =
                    stiffness_n_per_m.map_or(force_max_n, |k| (k * yield_max_m).min(force_max_n));
                Some(
                    per_hand_n == 0.0
                        || (!both_hands && held_s <= hold_max_s && per_hand_n <= bound),
                )
            }
        }
    }

    /// Whether a replayed force history spanning `span` (both hands, continuous) lies
    /// inside the training, allowing [`MEASURED_TOLERANCE_N`] for the sensor's noise.
    pub fn holds_hand_forces(&self, span: &HandForceSpan) -> Option<bool> {
        self.outside_hand_forces(span).map(|why| why.is_empty())
    }

    /// What in `span` lies outside the training, one phrase each (`61 N horizontal
    /// walking, above 40`); empty when all of it lies inside, `None` with nothing to judge.
    pub fn outside_hand_forces(&self, span: &HandForceSpan) -> Option<Vec<String>> {
        let tol = MEASURED_TOLERANCE_N;
        match *self {
            Self::Untrained | Self::Blind | Self::Unknown => None,
            Self::HandCurriculum {
                horizontal_max_n,
                vertical_n,
                ..
            } => {
                let mut why = Vec::new();
                if span.horizontal_walking_max_n > horizontal_max_n + tol {
                    why.push(format!(
                        "{:.0} N horizontal walking, above {horizontal_max_n}",
                        span.horizontal_walking_max_n
                    ));
                }
                if span.horizontal_standing_max_n > tol {
                    why.push(format!(
                        "{:.1} N horizontal standing, where training has none",
                        span.horizontal_standing_max_n
                    ));
                }
                vertical_outside(span.vertical_n, vertical_n, tol, &mut why);
                Some(why)
            }
            // A history on both hands for seconds on end is no event on one wrist.
            Self::WristEvents { .. } => Some(vec!["both hands, continuously".into()]),
        }
    }

    /// What in disturbance `d` lies outside the training, one phrase each; empty when all
    /// of it lies inside, `None` with nothing to judge. `stiffness_n_per_m` is a
    /// [`TrainedForces::WristEvents`] family's commanded stiffness. A curriculum family is
    /// judged as if the whole episode walked, except that a horizontal force is named as
    /// trained only while walking (every motion stands at its start); a payload by its
    /// weight (the curriculum's forces have no inertia, and a payload's is not judged).
    pub fn outside_disturbance(
        &self,
        d: &Disturbance,
        stiffness_n_per_m: Option<f64>,
    ) -> Option<Vec<String>> {
        match *self {
            Self::Untrained | Self::Blind | Self::Unknown => None,
            Self::HandCurriculum {
                horizontal_max_n,
                vertical_n,
                ..
            } => {
                let mut why = Vec::new();
                let mut judge = |horizontal_n: f64, vertical: (f64, f64)| {
                    if horizontal_n > 1e-6 {
                        why.push(if horizontal_n > horizontal_max_n {
                            format!("{horizontal_n:.0} N horizontal, above {horizontal_max_n}")
                        } else {
                            format!("{horizontal_n:.0} N horizontal, trained only while walking")
                        });
                    }
                    vertical_outside(vertical, vertical_n, 0.0, &mut why);
                };
                match d {
                    Disturbance::Event(e) => {
                        let up = e.up_deg.to_radians();
                        let v = e.force_n * up.sin();
                        judge(e.force_n * up.cos(), (v.min(0.0), v.max(0.0)));
                    }
                    Disturbance::Impulses(i) => {
                        if i.target == ImpulseTarget::Torso {
                            why.push("pushes on the torso, never in training".into());
                        } else {
                            judge(i.force_n[1], (0.0, 0.0));
                        }
                    }
                    Disturbance::Payload(p) => judge(0.0, (-p.mass_kg * 9.81, 0.0)),
                }
                Some(why)
            }
            Self::WristEvents {
                ramp_s,
                hold_max_s,
                yield_max_m,
                force_max_n,
                ..
            } => {
                let bound =
                    stiffness_n_per_m.map_or(force_max_n, |k| (k * yield_max_m).min(force_max_n));
                let mut why = Vec::new();
                let mut judge_force = |f: f64| {
                    if f > bound {
                        why.push(format!("{f:.0} N, above {bound:.0}"));
                    }
                };
                match d {
                    Disturbance::Event(e) => {
                        judge_force(e.force_n);
                        if e.hands == Hands::Both {
                            why.push("both hands at once".into());
                        }
                        if e.hold_s > hold_max_s {
                            why.push(format!("held {} s, above {hold_max_s}", e.hold_s));
                        }
                        for (what, t) in [("ramped", e.ramp_s), ("released", e.release_s)] {
                            if t < ramp_s.0 || t > ramp_s.1 {
                                why.push(format!(
                                    "{what} over {t} s, outside {} to {}",
                                    ramp_s.0, ramp_s.1
                                ));
                            }
                        }
                    }
                    Disturbance::Impulses(i) => {
                        if i.target == ImpulseTarget::Torso {
                            why.push("pushes on the torso, never in training".into());
                        } else {
                            judge_force(i.force_n[1]);
                            why.push(format!(
                                "steps, where training ramps over {} to {} s",
                                ramp_s.0, ramp_s.1
                            ));
                        }
                    }
                    Disturbance::Payload(_) => {
                        why.push(format!("a load held the whole episode, where training holds at most {hold_max_s} s"));
                    }
                }
                Some(why)
            }
        }
    }
}

/// Adds to `why` what of the vertical force span `vertical` (N, z up: lowest, highest)
/// lies outside the trained `range` by more than `tol`.
fn vertical_outside(vertical: (f64, f64), range: (f64, f64), tol: f64, why: &mut Vec<String>) {
    if vertical.0 < range.0 - tol {
        why.push(format!("{:.0} N down, beyond {}", -vertical.0, -range.0));
    }
    if vertical.1 > range.1 + tol {
        why.push(format!("{:.0} N up, above {}", vertical.1, range.1));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn falcon_holds_walking_pushes_to_40_n_and_no_standing_push() {
        assert_eq!(
            FALCON_FORCES.holds_push(30.0, 20.0, true, None, true),
            Some(true)
        );
        assert_eq!(
            FALCON_FORCES.holds_push(50.0, 20.0, true, None, true),
            Some(false)
        );
        assert_eq!(
            FALCON_FORCES.holds_push(10.0, 20.0, true, None, false),
            Some(false)
        );
        let carry = HandForceSpan {
            horizontal_walking_max_n: 25.0,
            horizontal_standing_max_n: 1.5,
            vertical_n: (-16.0, 3.0),
        };
        assert_eq!(FALCON_FORCES.holds_hand_forces(&carry), Some(true));
        let chair = HandForceSpan {
            horizontal_walking_max_n: 64.0,
            ..carry
        };
        assert_eq!(FALCON_FORCES.holds_hand_forces(&chair), Some(false));
        let wipe = HandForceSpan {
            vertical_n: (-1.0, 22.0),
            ..carry
        };
        assert_eq!(FALCON_FORCES.holds_hand_forces(&wipe), Some(false));
    }

    #[test]
    fn disturbances_are_judged_against_each_envelope() {
        let d = |s: &str| Disturbance::parse(s).unwrap().unwrap();
        // SoftMimic: one wrist, ramped 0.5 s, held 1 s, 30 N at 60 N/m (bound 42 N): inside.
        let inside = d("event:30:hand=right:ramp=0.5:hold=1");
        assert_eq!(
            SOFTMIMIC_FORCES.outside_disturbance(&inside, Some(60.0)),
            Some(vec![])
        );
        let why = SOFTMIMIC_FORCES
            .outside_disturbance(&d("event:50:hand=both:ramp=0:hold=3"), Some(60.0))
            .unwrap();
        assert_eq!(why.len(), 5, "{why:?}"); // force, both hands, hold, ramp, release
        assert!(!SOFTMIMIC_FORCES
            .outside_disturbance(&d("payload:1"), None)
            .unwrap()
            .is_empty());
        assert!(!SOFTMIMIC_FORCES
            .outside_disturbance(&d("impulse:20:on=hands"), None)
            .unwrap()
            .is_empty());
        // FALCON: a 2 kg payload weighs 19.6 N, inside −50…5 N; 6 kg does not.
        assert_eq!(
            FALCON_FORCES.outside_disturbance(&d("payload:2"), None),
            Some(vec![])
        );
        assert_eq!(
            FALCON_FORCES
                .outside_disturbance(&d("payload:6"), None)
                .unwrap()
                .len(),
            1
        );
        // A straight-down event inside the vertical range; any horizontal one is named.
        assert_eq!(
            FALCON_FORCES.outside_disturbance(&d("event:30:up=-90"), None),
            Some(vec![])
        );
        let why = FALCON_FORCES
            .outside_disturbance(&d("event:30"), None)
            .unwrap();
        assert!(why[0].contains("only while walking"), "{why:?}");
        assert!(TrainedForces::Blind
            .outside_disturbance(&inside, None)
            .is_none());
    }

    #[test]
    fn softmimic_holds_only_short_one_wrist_events_within_its_stiffness() {
        let k = Some(60.0); // F ≤ 42 N
        assert_eq!(
            SOFTMIMIC_FORCES.holds_push(30.0, 0.8, false, k, false),
            Some(true)
        );
        assert_eq!(
            SOFTMIMIC_FORCES.holds_push(50.0, 0.8, false, k, false),
            Some(false)
        );
        assert_eq!(
            SOFTMIMIC_FORCES.holds_push(10.0, 20.0, true, k, false),
            Some(false)
        );
        assert_eq!(
            SOFTMIMIC_FORCES.holds_push(0.0, 20.0, true, k, false),
            Some(true)
        );
        assert_eq!(
            TrainedForces::Blind.holds_push(10.0, 1.0, false, None, false),
            None
        );
    }
}
