//! The TWIST2 observation, block by block, from hand-made states: the mimic frame in the
//! root frame (a 90° yaw turns a world-x velocity into −y), the proprioception scales and
//! the hidden ankle velocities, the reference frames' roles (t + 0.02 s for the mimic
//! part, t for the future part), the history refill on steps 0 and 1 and its shift after.

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use thorarena::policy::twist2::{
    observation, single_frame, History, MIMIC_LEN, OBS_LEN, SINGLE_LEN,
};
use thorarena::policy::Observation;
use thorarena::sim::motion::ReferenceFrame;
use thorarena::sim::physics::RootState;

fn frame(yaw: f64, z: f64, vx_w: f64, joint: f64) -> ReferenceFrame {
    ReferenceFrame {
        world_from_root: Isometry3::from_parts(
            Translation3::new(1.0, 2.0, z),
            UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
        ),
        root_lin_vel_w: Vector3::new(vx_w, 0.0, 0.0),
        root_ang_vel_w: Vector3::new(0.0, 0.0, 0.7),
        joint_pos: vec![joint; 29],
        joint_vel: vec![0.0; 29],
        force_sensor: [Vector3::zeros(); 2],
    }
}

fn obs(step: usize) -> Observation {
    Observation {
        env: 0,
        episode_id: 0,
        step,
        time_s: step as f64 * 0.02,
        root: RootState {
            world_from_root: Isometry3::from_parts(
                Translation3::new(0.0, 0.0, 0.79),
                UnitQuaternion::from_euler_angles(0.1, -0.2, 0.0),
            ),
            lin_vel_w: Vector3::zeros(),
            ang_vel_w: Vector3::new(0.0, 0.0, 2.0),
        },
        q: (0..29).map(|j| j as f64 * 0.01).collect(),
        qd: vec![4.0; 29],
        last_action: vec![0.5 + step as f64; 29],
        // [0] at t (the future block), [1] at t + 0.02 s (the mimic block).
        reference: vec![
            frame(0.0, 0.75, 1.0, 0.3),
            frame(std::f64::consts::FRAC_PI_2, 0.8, 1.0, 0.2),
        ],
    }
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-9
}

#[test]
fn the_current_frame_has_the_documented_blocks() {
    let default = vec![0.1; 29];
    let s = single_frame(&obs(5), &default);
    assert_eq!(s.len(), SINGLE_LEN);
    // mimic of the t + 0.02 s frame, yawed 90°: world +x velocity is root −y.
    assert!(close(s[0], 0.0) && close(s[1], -1.0), "{:?}", &s[..2]);
    assert!(close(s[2], 0.8), "root height");
    assert!(
        close(s[3], 0.0) && close(s[4], 0.0),
        "roll, pitch of a pure yaw"
    );
    assert!(close(s[5], 0.7), "yaw rate in the root frame");
    assert!(
        s[6..MIMIC_LEN].iter().all(|&v| close(v, 0.2)),
        "reference joints"
    );
    // proprio
    let p = &s[MIMIC_LEN..];
    let w_b = obs(5).root.ang_vel_b();
    assert!(close(p[0], 0.25 * w_b.x) && close(p[2], 0.25 * w_b.z));
    assert!(
        close(p[3], 0.1) && close(p[4], -0.2),
        "roll, pitch: {:?}",
        &p[3..5]
    );
    assert!(close(p[5 + 3], 0.03 - 0.1), "q − default");
    let qd = &p[34..63];
    for (j, v) in qd.iter().enumerate() {
        let want = if [4, 5, 10, 11].contains(&j) {
            0.0
        } else {
            0.2
        };
        assert!(close(*v, want), "qd[{j}] = {v}");
    }
    assert!(p[63..].iter().all(|&v| close(v, 5.5)), "last action");
}

#[test]
fn history_is_refilled_on_the_first_two_steps_then_shifted() {
    let default = vec![0.0; 29];
    let mut h = History::default();
    let o0 = observation(&obs(0), &default, &mut h);
    assert_eq!(o0.len(), OBS_LEN);
    assert!(
        o0[SINGLE_LEN..SINGLE_LEN * 11].iter().all(|&v| v == 0.0),
        "zero before step 0"
    );
    // The future block is mimic(reference at t).
    assert!((o0[OBS_LEN - MIMIC_LEN + 2] - 0.75).abs() < 1e-6);
    let o1 = observation(&obs(1), &default, &mut h);
    let last_action_of = |o: &[f32], frame: usize| o[frame * SINGLE_LEN + SINGLE_LEN - 1];
    for k in 1..=10 {
        assert_eq!(last_action_of(&o1, k), 0.5, "step 1 sees step 0 everywhere");
    }
    let _ = observation(&obs(2), &default, &mut h);
    let o3 = observation(&obs(3), &default, &mut h);
    // Step 1 refilled all ten with itself; step 2 shifted once: nine of step 1, then step 2.
    assert_eq!(last_action_of(&o3, 1), 1.5);
    assert_eq!(last_action_of(&o3, 9), 1.5);
    assert_eq!(last_action_of(&o3, 10), 2.5);
    assert_eq!(last_action_of(&o3, 0), 3.5, "the current frame");
    // A new episode (step 0 again) starts from zeros.
    let again = observation(&obs(0), &default, &mut h);
    assert_eq!(again, o0);
}

#[test]
fn the_observation_is_clipped_to_100() {
    let mut o = obs(4);
    o.last_action = vec![1e6; 29];
    let v = observation(&o, &[0.0; 29], &mut History::default());
    assert_eq!(v[SINGLE_LEN - 1], 100.0);
}
