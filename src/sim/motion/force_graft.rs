//! A force profile of one sequence replayed on another motion: the clips published with a
//! single-clip policy carry no hand forces, so a policy's response to a realistic force
//! history is measured by grafting one — the recorded (or synthetic) hand forces of
//! another sequence, looped to the clip's length — onto the clip. The result says so in
//! its id and provenance: it is not a recording of that motion under that force. A grafted
//! history is stored and replayed in the world frame (see [`with_forces_of`]).

use super::{heading_rad, ForceFrame, Sequence, LEFT, RIGHT};
use crate::sim::robot::{forward_kinematics, RobotModel};
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3};

/// The first `seconds` of `seq` (all of it when shorter; at least two frames).
pub fn first_seconds(seq: &Sequence, seconds: f64) -> Sequence {
    // Capped before the cast: 1e300 s would saturate to usize::MAX and wrap to 0 frames.
    let steps = (seconds * seq.fps).round().min(seq.n_frames() as f64);
    let frames = (steps as usize + 1).clamp(2, seq.n_frames().max(2));
    let frames = frames.min(seq.n_frames());
    let mut s = seq.clone();
    s.root_pos.truncate(frames);
    s.root_quat_wxyz.truncate(frames);
    s.joint_pos.truncate(frames);
    if let Some(v) = s.joint_vel.as_mut() {
        v.truncate(frames);
    }
    for side in &mut s.force_sensor {
        side.truncate(frames);
    }
    s
}

/// `motion` with the hand forces of `forces`, replayed in the world frame
/// ([`ForceFrame::World`]) and turned to keep the direction they had relative to their own
/// motion's heading: each force of `forces` goes to the world through its reference's hand
/// pose (forward kinematics on `robot`), is expressed relative to that motion's heading at
/// that time, sampled at `motion`'s frame times (linear interpolation, looped when `forces`
/// is the shorter) and turned to `motion`'s heading at each. A push on the chair in front
/// stays a push in front of the clip, however the clip's hands turn, and a member that
/// yields receives the same load as one that does not. Its id is
/// `<motion>+forces-<forces>`.
pub fn with_forces_of(robot: &RobotModel, motion: &Sequence, forces: &Sequence) -> Sequence {
    let source_duration = forces.duration_s();
    let heading_from_world = |q: [f64; 4]| {
        let r = UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3]));
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), -heading_rad(&r))
    };
    // Per source frame: each hand's force in its motion's heading frame.
    let mut poses = Vec::new();
    let in_heading: Vec<[Vector3<f64>; 2]> = (0..forces.n_frames())
        .map(|k| {
            let p = forces.root_pos[k];
            let q = forces.root_quat_wxyz[k];
            let world_from_root = Isometry3::from_parts(
                Translation3::new(p[0], p[1], p[2]),
                UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3])),
            );
            forward_kinematics(robot, &world_from_root, &forces.joint_pos[k], &mut poses);
            [LEFT, RIGHT].map(|s| {
                let f = Vector3::from(forces.force_sensor[s][k]);
                let f_w = match forces.force_frame {
                    ForceFrame::World => f,
                    ForceFrame::Sensor => {
                        let frame = &robot.frames[robot.hands[s].frame];
                        let c = forces.hand_from_sensor_wxyz[s];
                        let hand_from_sensor = UnitQuaternion::from_quaternion(Quaternion::new(
                            c[0], c[1], c[2], c[3],
                        ));
                        (poses[frame.body] * frame.body_from_frame).rotation
                            * (hand_from_sensor * f)
                    }
                };
                heading_from_world(q) * f_w
            })
        })
        .collect();
    let sample = |side: usize, t: f64| -> Vector3<f64> {
        if in_heading.len() < 2 || source_duration <= 0.0 {
            return in_heading.first().map_or_else(Vector3::zeros, |f| f[side]);
        }
        let x = t.rem_euclid(source_duration) * forces.fps;
        let i = (x.floor() as usize).min(in_heading.len() - 2);
        let a = x - i as f64;
        in_heading[i][side] * (1.0 - a) + in_heading[i + 1][side] * a
    };
    let mut s = motion.clone();
    s.sequence_id = format!("{}+forces-{}", motion.sequence_id, forces.sequence_id);
    s.force_sensor = [LEFT, RIGHT].map(|side| {
        (0..motion.n_frames())
            .map(|k| {
                let world_from_heading = heading_from_world(motion.root_quat_wxyz[k]).inverse();
                let f = world_from_heading * sample(side, k as f64 / motion.fps);
                [f.x, f.y, f.z]
            })
            .collect()
    });
    s.force_frame = ForceFrame::World;
    s.hand_from_sensor_wxyz = forces.hand_from_sensor_wxyz;
    s.force_point_hand = forces.force_point_hand;
    s.forces_recorded = true;
    s.provenance = serde_json::json!({
        "format": "force-graft",
        "motion": motion.provenance,
        "forces_grafted_from": {
            "task": forces.task,
            "sequence_id": forces.sequence_id,
            "duration_s": source_duration,
            "looped": source_duration < motion.duration_s(),
            "frame": "world, turned from the source's heading to this motion's at each frame",
            "provenance": forces.provenance,
        },
        "note": "the hand forces of another sequence replayed on this motion, not a recording of this motion under force",
    });
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn g1() -> RobotModel {
        crate::sim::robot::load_bundled("g1_29dof").unwrap()
    }

    /// A G1 standing in its default pose, yawed `yaw` rad, with `force(k)` on the left
    /// sensor's x axis and 1 N on the right sensor's z axis.
    fn seq(
        robot: &RobotModel,
        id: &str,
        frames: usize,
        fps: f64,
        yaw: f64,
        force: impl Fn(usize) -> f64,
    ) -> Sequence {
        let (c, s) = ((yaw / 2.0).cos(), (yaw / 2.0).sin());
        Sequence {
            task: "t".into(),
            sequence_id: id.into(),
            fps,
            joint_names: robot.joints.iter().map(|j| j.name.clone()).collect(),
            root_pos: vec![[0.0, 0.0, 0.78]; frames],
            root_quat_wxyz: vec![[c, 0.0, 0.0, s]; frames],
            joint_pos: vec![robot.default_pose(); frames],
            joint_vel: None,
            force_sensor: [
                (0..frames).map(|k| [force(k), 0.0, 0.0]).collect(),
                vec![[0.0, 0.0, 1.0]; frames],
            ],
            force_frame: ForceFrame::Sensor,
            hand_from_sensor_wxyz: [[1.0, 0.0, 0.0, 0.0]; 2],
            force_point_hand: [[0.01, 0.0, 0.0]; 2],
            forces_recorded: false,
            provenance: serde_json::json!({"format": "test"}),
        }
    }

    /// Each hand's force in the world at frame `k` of a sensor-frame sequence.
    fn world_forces(robot: &RobotModel, seq: &Sequence, k: usize) -> [Vector3<f64>; 2] {
        let q = seq.root_quat_wxyz[k];
        let p = seq.root_pos[k];
        let mut poses = Vec::new();
        let root = Isometry3::from_parts(
            Translation3::new(p[0], p[1], p[2]),
            UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3])),
        );
        forward_kinematics(robot, &root, &seq.joint_pos[k], &mut poses);
        [LEFT, RIGHT].map(|s| {
            let frame = &robot.frames[robot.hands[s].frame];
            (poses[frame.body] * frame.body_from_frame).rotation
                * Vector3::from(seq.force_sensor[s][k])
        })
    }

    #[test]
    fn forces_are_resampled_onto_the_motion_and_looped_in_the_world_frame() {
        let robot = g1();
        let motion = seq(&robot, "clip", 61, 30.0, 0.0, |_| 0.0); // 2 s
        let forces = seq(&robot, "push_chair_000", 51, 50.0, 0.0, |k| k as f64); // fx = 50 t
        let g = with_forces_of(&robot, &motion, &forces);
        assert_eq!(g.sequence_id, "clip+forces-push_chair_000");
        assert_eq!(g.n_frames(), 61);
        assert!(g.forces_recorded);
        assert_eq!(g.force_frame, ForceFrame::World);
        // Same heading: the world forces of the source at t = 0.5 s (25 N on the left
        // sensor's x), and again at t = 1.5 s, looped.
        let at_half = world_forces(&robot, &forces, 25);
        for k in [15, 45] {
            let f = Vector3::from(g.force_sensor[LEFT][k]);
            assert!(
                (f - at_half[LEFT]).norm() < 1e-9,
                "{k}: {f:?} vs {:?}",
                at_half[LEFT]
            );
        }
        let right = Vector3::from(g.force_sensor[RIGHT][30]);
        assert!((right - at_half[RIGHT]).norm() < 1e-9);
        assert_eq!(g.provenance["forces_grafted_from"]["looped"], true);
        assert_eq!(g.root_pos, motion.root_pos);
    }

    #[test]
    fn grafted_forces_keep_their_direction_relative_to_the_heading_not_to_the_hands() {
        let robot = g1();
        let forces = seq(&robot, "push", 51, 50.0, 0.0, |_| 20.0);
        let source = world_forces(&robot, &forces, 0);
        // A clip facing +y (yaw 90°): the source's forces turn with the heading by 90°.
        let turned = seq(
            &robot,
            "turned",
            31,
            30.0,
            std::f64::consts::FRAC_PI_2,
            |_| 0.0,
        );
        let g = with_forces_of(&robot, &turned, &forces);
        let quarter =
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), std::f64::consts::FRAC_PI_2);
        for s in [LEFT, RIGHT] {
            let f = Vector3::from(g.force_sensor[s][10]);
            assert!((f - quarter * source[s]).norm() < 1e-9, "{f:?}");
        }
        // The clip's hands rotated (wrists rolled) change nothing: the force is the world's.
        let mut rolled = seq(&robot, "rolled", 31, 30.0, 0.0, |_| 0.0);
        let roll = robot.joint_index("left_wrist_roll_joint").unwrap();
        for q in &mut rolled.joint_pos {
            q[roll] += 1.0;
        }
        let plain = with_forces_of(
            &robot,
            &seq(&robot, "clip", 31, 30.0, 0.0, |_| 0.0),
            &forces,
        );
        let g = with_forces_of(&robot, &rolled, &forces);
        assert_eq!(g.force_sensor, plain.force_sensor);
    }

    #[test]
    fn first_seconds_cuts_every_series() {
        let robot = g1();
        let s = seq(&robot, "clip", 300, 30.0, 0.0, |k| k as f64);
        let cut = first_seconds(&s, 2.0);
        assert_eq!(cut.n_frames(), 61);
        assert_eq!(cut.force_sensor[0].len(), 61);
        assert_eq!(first_seconds(&s, 100.0).n_frames(), 300);
    }
}
