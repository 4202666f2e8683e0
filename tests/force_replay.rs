//! Force replay: a known sensor force at a known hand pose lands in the world frame
//! exactly, coefficient 0 applies nothing, and the replayed force follows the reference
//! clock at every control/physics step combination of the shipped profiles.

use nalgebra::{Isometry3, UnitQuaternion, Vector3};
use std::f64::consts::FRAC_PI_2;
use std::sync::Arc;
use thorarena::sim::motion::{ForceFrame, Reference};
use thorarena::sim::physics::{
    standing_default_pose, standing_gains, ContactMode, Physics, PhysicsSettings, PhysicsState,
    RapierPhysics,
};
use thorarena::sim::profile::{bundled_profile_path, load_profile};
use thorarena::sim::replay::{world_force, ForceReplay};
use thorarena::sim::robot::{self, forward_kinematics};

mod common;
use common::{g1, sample_sequence};

#[test]
fn a_sensor_force_is_rotated_by_calibration_then_hand_pose_and_scaled() {
    let hand = Isometry3::new(Vector3::new(0.3, 0.2, 1.0), Vector3::z() * FRAC_PI_2);
    let calib = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), FRAC_PI_2);
    // sensor y → hand z (calibration) → world z (yaw leaves z); sensor x → hand x → world y.
    let f = world_force(&hand, &calib, &Vector3::new(2.0, 3.0, 0.0), 1.0);
    assert!((f - Vector3::new(0.0, 2.0, 3.0)).norm() < 1e-12, "{f:?}");
    assert_eq!(
        world_force(&hand, &calib, &Vector3::new(2.0, 3.0, 0.0), 0.0),
        Vector3::zeros()
    );
    assert!(
        (world_force(&hand, &calib, &Vector3::new(2.0, 3.0, 0.0), 0.5) - f * 0.5).norm() < 1e-12
    );
}

#[test]
fn replayed_forces_use_the_simulated_hand_pose_and_the_sequence_calibration() {
    let robot = g1();
    let seq = sample_sequence(&robot, "s"); // right calibration: 180° about x
    let reference = Reference::new(&seq);
    let replay = ForceReplay::new(&robot, &seq, 1.0);
    let stand = standing_default_pose(&robot);
    let mut poses = Vec::new();
    forward_kinematics(&robot, &stand.root.world_from_root, &stand.q, &mut poses);
    let [l, r] = replay.forces_at(&reference, 0.5, &poses);
    let hand = |s: usize| robot::frame_pose(&robot, &poses, robot.hands[s].frame);
    // Left: identity calibration, sensor force (15, 0, −5) at t = 0.5 s (30 fps ramp).
    let expected_l = hand(0).rotation * Vector3::new(15.0, 0.0, -5.0);
    assert!((l - expected_l).norm() < 1e-9, "{l:?} vs {expected_l:?}");
    // Right: (0, 1, 2) turned 180° about x → (0, −1, −2) in the hand frame.
    let expected_r = hand(1).rotation * Vector3::new(0.0, -1.0, -2.0);
    assert!((r - expected_r).norm() < 1e-9, "{r:?} vs {expected_r:?}");
}

#[test]
fn a_grafted_world_frame_history_keeps_its_direction_when_the_hand_rotates() {
    let robot = g1();
    let mut seq = sample_sequence(&robot, "s");
    let stand = standing_default_pose(&robot);
    let mut poses = Vec::new();
    forward_kinematics(&robot, &stand.root.world_from_root, &stand.q, &mut poses);
    // The same robot with both wrists rolled by 1 rad: the hands point elsewhere.
    let mut rolled_q = stand.q.clone();
    for j in ["left_wrist_roll_joint", "right_wrist_roll_joint"] {
        rolled_q[robot.joint_index(j).unwrap()] += 1.0;
    }
    let mut rolled = Vec::new();
    forward_kinematics(&robot, &stand.root.world_from_root, &rolled_q, &mut rolled);
    let forces = |seq: &thorarena::sim::motion::Sequence, poses: &[Isometry3<f64>]| {
        let replay = ForceReplay::new(&robot, seq, 0.5);
        replay.forces_at(&Reference::new(seq), 0.5, poses)
    };
    // In the sensor frame the force turns with the hand …
    let (a, b) = (forces(&seq, &poses), forces(&seq, &rolled));
    assert!((a[0] - b[0]).norm() > 1.0, "{a:?} vs {b:?}");
    // … in the world frame it does not: the stored vector × the coefficient, as it is.
    seq.force_frame = ForceFrame::World;
    let (a, b) = (forces(&seq, &poses), forces(&seq, &rolled));
    assert_eq!(a, b);
    assert!(
        (a[0] - Vector3::new(15.0, 0.0, -5.0) * 0.5).norm() < 1e-9,
        "{a:?}"
    );
}

#[test]
fn coefficient_zero_applies_nothing_and_one_applies_the_recorded_impulse() {
    let robot = Arc::new(g1());
    let seq = sample_sequence(&robot, "s");
    let reference = Reference::new(&seq);
    let momentum_after = |coefficient: f64| {
        let settings = PhysicsSettings {
            gravity: [0.0; 3],
            contacts: ContactMode::None,
            ..Default::default()
        };
        let mut p = RapierPhysics::new(robot.clone(), settings, standing_gains(&robot));
        let mut start = standing_default_pose(&robot);
        start.root.world_from_root = Isometry3::translation(0.0, 0.0, 2.0);
        p.reset(&start);
        p.set_targets(&start.q);
        let replay = ForceReplay::new(&robot, &seq, coefficient);
        let mut state = PhysicsState::default();
        let mut impulse = Vector3::zeros();
        let com = |p: &RapierPhysics, st: &mut PhysicsState| {
            p.read_state(st);
            robot::center_of_mass(&robot, &st.world_from_body)
        };
        let mut prev = com(&p, &mut state);
        for _ in 0..100 {
            p.read_state(&mut state);
            let [l, r] = replay.apply(&mut p, &reference, &state.world_from_body);
            impulse += (l + r) * p.settings().dt_s;
            prev = com(&p, &mut state);
            p.step();
        }
        let v = (com(&p, &mut state) - prev) / p.settings().dt_s;
        (v * robot.total_mass_kg(), impulse)
    };
    let (m0, i0) = momentum_after(0.0);
    assert_eq!(i0, Vector3::zeros());
    assert!(m0.norm() < 1e-6, "no force, no momentum: {m0:?}");
    let (m1, i1) = momentum_after(1.0);
    assert!(
        (m1 - i1).norm() < 0.01 * i1.norm(),
        "momentum {m1:?} vs applied impulse {i1:?}"
    );
}

#[test]
fn replayed_force_follows_the_reference_clock_for_every_shipped_profile() {
    let robot = Arc::new(g1());
    let seq = sample_sequence(&robot, "s");
    let reference = Reference::new(&seq);
    let replay = ForceReplay::new(&robot, &seq, 1.0);
    for name in ["twist2", "gmt", "beyondmimic", "default"] {
        let profile = load_profile(&bundled_profile_path(name), &robot).unwrap();
        let settings = PhysicsSettings {
            dt_s: profile.physics_dt_s,
            contacts: ContactMode::None,
            fixed_base: true,
            ..Default::default()
        };
        let mut p = RapierPhysics::new(robot.clone(), settings, standing_gains(&robot));
        let mut start = standing_default_pose(&robot);
        start.root.world_from_root = Isometry3::translation(0.0, 0.0, 1.0);
        p.reset(&start);
        let mut poses = Vec::new();
        forward_kinematics(&robot, &start.root.world_from_root, &start.q, &mut poses);
        let control_steps = (reference.duration_s() / profile.control_dt_s).floor() as usize;
        let mut k = 0usize;
        for _ in 0..control_steps {
            for _ in 0..profile.substeps {
                // Sensor-frame left force is (30·t, 0, −5) N: read back the time it was sampled at.
                let sampled = replay.forces_at(&reference, p.time_s(), &poses)[0];
                let hand = robot::frame_pose(&robot, &poses, robot.hands[0].frame);
                let f_sensor = hand.rotation.inverse() * sampled;
                let t_expected = k as f64 * profile.physics_dt_s;
                assert!(
                    (f_sensor.x / 30.0 - t_expected).abs() < 1e-9,
                    "{name}: physics step {k} sampled t = {}",
                    f_sensor.x / 30.0
                );
                p.step();
                k += 1;
            }
        }
        assert!((p.time_s() - control_steps as f64 * profile.control_dt_s).abs() < 1e-9);
    }
}
