//! Reference processing: resampling is linear for positions and joints and slerp for
//! rotations, finite-difference velocities are exact on uniform motion, keypoints come from
//! forward kinematics, and the ground check finds a known height offset.

use nalgebra::Vector3;
use thorarena::sim::motion::{ground_check, reference_keypoints, shift_root_height, Reference};
use thorarena::sim::physics::standing_default_pose;

mod common;
use common::{g1, sample_sequence};

#[test]
fn resampling_interpolates_between_frames() {
    let robot = g1();
    let seq = sample_sequence(&robot, "s");
    let r = Reference::new(&seq);
    assert!((r.duration_s() - 39.0 / 30.0).abs() < 1e-12);
    let f = r.sample(2.5 / 30.0); // halfway between frames 2 and 3
    assert!((f.world_from_root.translation.x - 0.025).abs() < 1e-12);
    let yaw = f.world_from_root.rotation.euler_angles().2;
    assert!((yaw - 0.025).abs() < 1e-9, "slerp halfway: yaw {yaw}");
    assert!((f.joint_pos[0] - (seq.joint_pos[2][0] + seq.joint_pos[3][0]) / 2.0).abs() < 1e-12);
    assert!((f.force_sensor[0].x - 2.5).abs() < 1e-12);
    // The control clock: every 20 ms up to the last frame, clamped beyond it.
    let frames = r.resample(0.02);
    assert_eq!(frames.len(), 66); // t = 0, 0.02, …, 1.30 s
    assert_eq!(r.sample(100.0).joint_pos, seq.joint_pos[39]);
}

#[test]
fn finite_difference_velocities_are_exact_on_uniform_motion() {
    let robot = g1();
    let r = Reference::new(&sample_sequence(&robot, "s"));
    for t in [0.0, 0.5, 39.0 / 30.0] {
        let f = r.sample(t);
        assert!(
            (f.root_lin_vel_w - Vector3::new(0.3, 0.0, 0.0)).norm() < 1e-9,
            "{:?}",
            f.root_lin_vel_w
        );
        assert!(
            (f.root_ang_vel_w - Vector3::new(0.0, 0.0, 0.3)).norm() < 1e-9,
            "{:?}",
            f.root_ang_vel_w
        );
        assert!(f.joint_vel.iter().all(|v| (v - 0.03).abs() < 1e-9));
    }
}

#[test]
fn keypoints_follow_the_root_by_forward_kinematics() {
    let robot = g1();
    let r = Reference::new(&sample_sequence(&robot, "s"));
    let set = robot.keypoint_set("default").unwrap();
    let frames = r.resample(0.1);
    let kp = reference_keypoints(&robot, &frames, set);
    assert_eq!((kp.len(), kp[0].len()), (frames.len(), 13));
    // Torso keypoint sits above the pelvis, whatever the frame.
    for (f, k) in frames.iter().zip(&kp) {
        assert!(k[0].z > f.world_from_root.translation.z);
    }
}

#[test]
fn ground_check_finds_the_height_offset_and_the_shift_removes_it() {
    let robot = g1();
    let mut seq = sample_sequence(&robot, "s");
    let stand = standing_default_pose(&robot);
    let z = stand.root.world_from_root.translation.z;
    for (k, p) in seq.root_pos.iter_mut().enumerate() {
        *p = [0.0, 0.0, z + 0.05];
        seq.root_quat_wxyz[k] = [1.0, 0.0, 0.0, 0.0];
        seq.joint_pos[k] = stand.q.clone();
    }
    let g = ground_check(&robot, &seq).unwrap();
    assert!(
        (g.offset_m - 0.05).abs() < 1e-9 && (g.min_m - 0.05).abs() < 1e-9,
        "{g:?}"
    );
    shift_root_height(&mut seq, -g.offset_m);
    assert!(ground_check(&robot, &seq).unwrap().offset_m.abs() < 1e-9);
}
