//! The force menu's disturbances as an episode applies them, step by step, through the
//! same path a run takes (`Setting::parse` → `EpisodeSetup::for_setting` → `Episode`): an
//! event's force at each physics step is its ramp–hold–release at that step's time, in the
//! direction it names; impulses come at seeded times with their magnitude, duration and
//! gaps inside their ranges; a payload reaches the engine as point masses at the hands.
//! (A payload's weight on a standing robot is in the physics conformance suite.)

use nalgebra::Vector3;
use std::sync::Arc;
use thorarena::eval::episode::{Episode, EpisodeSetup};
use thorarena::eval::{Setting, TerminationRule};
use thorarena::policy::{HoldPolicy, Policy};
use thorarena::sim::motion::{Sequence, LEFT, RIGHT};
use thorarena::sim::physics::{
    standing_default_pose, ExternalForce, PdGains, Physics, PhysicsSettings, PhysicsState,
    PointMass, RapierPhysics, ResetState,
};
use thorarena::sim::profile::{bundled_profile_path, load_profile};
use thorarena::sim::robot::RobotModel;

mod common;
use common::{g1, sample_sequence};

/// Rapier, recording the external forces held at each physics step (with the step's
/// start time) and every payload set.
struct RecordingPhysics {
    inner: RapierPhysics,
    held: Vec<ExternalForce>,
    steps: Vec<(f64, Vec<ExternalForce>)>,
    payloads: Vec<Vec<PointMass>>,
}

impl Physics for RecordingPhysics {
    fn model(&self) -> &RobotModel {
        self.inner.model()
    }
    fn settings(&self) -> &PhysicsSettings {
        self.inner.settings()
    }
    fn reset(&mut self, state: &ResetState) {
        self.held.clear();
        self.inner.reset(state)
    }
    fn set_gains(&mut self, gains: &PdGains) {
        self.inner.set_gains(gains)
    }
    fn set_targets(&mut self, q_target: &[f64]) {
        self.inner.set_targets(q_target)
    }
    fn set_feedforward(&mut self, torque_nm: &[f64]) {
        self.inner.set_feedforward(torque_nm)
    }
    fn set_external_force(&mut self, force: ExternalForce) {
        match self
            .held
            .iter_mut()
            .find(|f| f.body == force.body && f.point_b == force.point_b)
        {
            Some(f) => *f = force,
            None => self.held.push(force),
        }
        self.inner.set_external_force(force)
    }
    fn clear_external_forces(&mut self) {
        self.held.clear();
        self.inner.clear_external_forces()
    }
    fn set_payloads(&mut self, payloads: &[PointMass]) {
        self.payloads.push(payloads.to_vec());
        self.inner.set_payloads(payloads)
    }
    fn step(&mut self) {
        self.steps.push((self.inner.time_s(), self.held.clone()));
        self.inner.step()
    }
    fn read_state(&self, out: &mut PhysicsState) {
        self.inner.read_state(out)
    }
    fn time_s(&self) -> f64 {
        self.inner.time_s()
    }
    fn contact_count(&self) -> usize {
        self.inner.contact_count()
    }
    fn ground_contacts(&self, out: &mut Vec<thorarena::sim::physics::GroundContact>) {
        self.inner.ground_contacts(out)
    }
}

/// A 3 s reference standing still in the default pose, facing world +y (yaw 90°).
fn standing_facing_y(robot: &RobotModel, id: &str) -> Sequence {
    let mut seq = sample_sequence(robot, id);
    let stand = standing_default_pose(robot);
    let t = &stand.root.world_from_root.translation;
    let n = 91;
    let half = std::f64::consts::FRAC_PI_4;
    seq.root_pos = vec![[t.x, t.y, t.z]; n];
    seq.root_quat_wxyz = vec![[half.cos(), 0.0, 0.0, half.sin()]; n];
    seq.joint_pos = vec![stand.q.clone(); n];
    seq.force_sensor = [vec![[5.0, 0.0, 0.0]; n], vec![[5.0, 0.0, 0.0]; n]];
    seq
}

/// Runs `setting` on `seq` holding the pose; returns the recording.
fn run(robot: &Arc<RobotModel>, seq: &Sequence, setting: &str) -> RecordingPhysics {
    let profile = load_profile(&bundled_profile_path("default"), robot).unwrap();
    let setting = Setting::parse(setting).unwrap_or_else(|e| panic!("{e}"));
    let setup = EpisodeSetup::for_setting(
        robot,
        &profile,
        robot.keypoint_set("default").unwrap(),
        TerminationRule::default(),
        &setting,
        vec![0.0],
    );
    let settings = PhysicsSettings {
        dt_s: profile.physics_dt_s,
        ..Default::default()
    };
    let mut physics = RecordingPhysics {
        inner: RapierPhysics::new(robot.clone(), settings, profile.gains.clone()),
        held: Vec::new(),
        steps: Vec::new(),
        payloads: Vec::new(),
    };
    let mut ep = Episode::start(&setup, seq, &mut physics);
    let mut actions = vec![vec![0.0; robot.n_joints()]];
    while !ep.is_done() {
        HoldPolicy.act(&[ep.observation()], &mut actions);
        ep.advance(&mut physics, &actions[0]);
    }
    physics
}

/// The force held on `body` at step `k` (zero when none is).
fn force_on(rec: &RecordingPhysics, k: usize, body: usize) -> Vector3<f64> {
    rec.steps[k]
        .1
        .iter()
        .filter(|f| f.body == body)
        .map(|f| f.force_w)
        .sum()
}

fn hand_body(robot: &RobotModel, side: usize) -> usize {
    robot.frames[robot.hands[side].frame].body
}

#[test]
fn an_event_applies_its_ramp_hold_and_release_at_every_physics_step() {
    let robot = Arc::new(g1());
    let seq = standing_facing_y(&robot, "still");
    let rec = run(
        &robot,
        &seq,
        "event:20@90:hand=left:start=0.5:ramp=0.4:hold=0.6:release=0.2",
    );
    // Facing +y, 90° counter-clockwise from the heading is world −x.
    let direction = Vector3::new(-1.0, 0.0, 0.0);
    let expected = |t: f64| -> f64 {
        match t {
            t if t < 0.5 => 0.0,
            t if t < 0.9 => 20.0 * (t - 0.5) / 0.4,
            t if t < 1.5 => 20.0,
            t if t < 1.7 => 20.0 * (1.7 - t) / 0.2,
            _ => 0.0,
        }
    };
    let last_t = rec.steps.last().expect("steps").0;
    assert!(
        last_t > 2.0,
        "the episode ended at {last_t} s, before the event did"
    );
    let (mut ramping, mut held) = (0, 0);
    for (k, (t, _)) in rec.steps.iter().enumerate() {
        let left = force_on(&rec, k, hand_body(&robot, LEFT));
        let right = force_on(&rec, k, hand_body(&robot, RIGHT));
        let want = direction * expected(*t);
        assert!(
            (left - want).norm() < 1e-9,
            "t = {t}: left hand {left:?}, the event says {want:?}"
        );
        assert!(right.norm() < 1e-12, "t = {t}: right hand {right:?}");
        ramping += usize::from(expected(*t) > 0.0 && expected(*t) < 20.0);
        held += usize::from(expected(*t) == 20.0);
    }
    assert!(
        ramping > 80 && held > 80,
        "ramp {ramping}, hold {held} steps"
    );
    assert_eq!(rec.payloads, vec![Vec::new()], "an event holds no payload");
}

/// The pulses seen in a recording on `body`: (start, end, force), merging runs of steps
/// holding the same nonzero force.
fn pulses_seen(rec: &RecordingPhysics, body: usize) -> Vec<(f64, f64, Vector3<f64>)> {
    let dt = rec.steps[1].0 - rec.steps[0].0;
    let mut out: Vec<(f64, f64, Vector3<f64>)> = Vec::new();
    for (k, (t, _)) in rec.steps.iter().enumerate() {
        let f = force_on(rec, k, body);
        if f.norm() == 0.0 {
            continue;
        }
        match out.last_mut() {
            Some(last) if last.2 == f && (t - last.1).abs() < 0.5 * dt => last.1 = t + dt,
            _ => out.push((*t, t + dt, f)),
        }
    }
    out
}

#[test]
fn impulses_come_at_seeded_times_within_their_ranges_and_differ_per_sequence() {
    let robot = Arc::new(g1());
    let spec = "impulse:60-120:on=torso:dur=0.1:every=0.3-0.6:seed=3";
    let torso = robot.frames[robot.frame_index("torso_link").unwrap()].body;
    let a = run(&robot, &standing_facing_y(&robot, "a"), spec);
    let seen = pulses_seen(&a, torso);
    assert!(seen.len() >= 3, "{} pulses in 3 s: {seen:?}", seen.len());
    let mut previous_end = 0.0;
    for (start, end, f) in &seen {
        assert!(
            (end - start - 0.1).abs() < 1e-6,
            "a pulse lasts {} s",
            end - start
        );
        let gap = start - previous_end;
        assert!(
            (0.3 - 1e-6..=0.6 + 0.005).contains(&gap),
            "gap {gap} s before the pulse at {start}"
        );
        assert!((60.0..=120.0).contains(&f.norm()), "magnitude {}", f.norm());
        assert_eq!(f.z, 0.0, "horizontal");
        previous_end = *end;
    }
    for side in [LEFT, RIGHT] {
        assert!(pulses_seen(&a, hand_body(&robot, side)).is_empty());
    }
    // The same sequence draws the same pulses; another sequence other ones.
    let again = run(&robot, &standing_facing_y(&robot, "a"), spec);
    assert_eq!(pulses_seen(&again, torso), seen);
    let b = run(&robot, &standing_facing_y(&robot, "b"), spec);
    assert_ne!(pulses_seen(&b, torso), seen);
    // On the hands: one hand per pulse, never both at once.
    let h = run(
        &robot,
        &standing_facing_y(&robot, "a"),
        "impulse:50:on=hands:dur=0.2:every=0.3:seed=1",
    );
    let (l, r) = (
        pulses_seen(&h, hand_body(&robot, LEFT)),
        pulses_seen(&h, hand_body(&robot, RIGHT)),
    );
    assert!(!l.is_empty() || !r.is_empty());
    for (s, e, f) in l.iter().chain(&r) {
        assert!((f.norm() - 50.0).abs() < 1e-9 && (e - s - 0.2).abs() < 1e-6);
    }
    assert!(pulses_seen(&h, torso).is_empty());
}

#[test]
fn a_payload_reaches_the_engine_as_point_masses_at_the_hands_and_applies_no_force() {
    let robot = Arc::new(g1());
    let rec = run(&robot, &standing_facing_y(&robot, "still"), "payload:2.5");
    let set = &rec.payloads;
    assert_eq!(set.len(), 1);
    let bodies: Vec<usize> = set[0].iter().map(|p| p.body).collect();
    assert_eq!(
        bodies,
        vec![hand_body(&robot, LEFT), hand_body(&robot, RIGHT)]
    );
    assert!(set[0].iter().all(|p| p.mass_kg == 2.5));
    assert!(
        rec.steps
            .iter()
            .all(|(_, held)| held.iter().all(|f| f.force_w == Vector3::zeros())),
        "a payload acts through its mass only (and the recorded forces are not replayed)"
    );
    let left = run(
        &robot,
        &standing_facing_y(&robot, "still"),
        "payload:1:hand=left",
    );
    assert_eq!(left.payloads[0].len(), 1);
    assert_eq!(left.payloads[0][0].body, hand_body(&robot, LEFT));
}
