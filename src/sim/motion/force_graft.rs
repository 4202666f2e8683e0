//! A force profile of one sequence replayed on another motion: the clips published with a
//! single-clip policy carry no hand forces, so a policy's response to a realistic force
//! history is measured by grafting one — the recorded (or synthetic) hand forces of
//! another sequence, looped to the clip's length — onto the clip. The result says so in
//! its id and provenance: it is not a recording of that motion under that force.

use super::Sequence;

/// The first `seconds` of `seq` (all of it when shorter; at least two frames).
pub fn first_seconds(seq: &Sequence, seconds: f64) -> Sequence {
    let frames = ((seconds * seq.fps).round() as usize + 1).clamp(2, seq.n_frames().max(2));
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

/// `motion` with the hand forces of `forces` (sensor frames, sensor mounts and force
/// points included), sampled at `motion`'s frame times by linear interpolation and
/// looped when `forces` is the shorter. Its id is `<motion>+forces-<forces>`.
pub fn with_forces_of(motion: &Sequence, forces: &Sequence) -> Sequence {
    let source_duration = forces.duration_s();
    let sample = |side: usize, t: f64| -> [f64; 3] {
        let log = &forces.force_sensor[side];
        if log.len() < 2 || source_duration <= 0.0 {
            return log.first().copied().unwrap_or([0.0; 3]);
        }
        let t = t.rem_euclid(source_duration);
        let x = t * forces.fps;
        let i = (x.floor() as usize).min(log.len() - 2);
        let a = x - i as f64;
        std::array::from_fn(|k| log[i][k] * (1.0 - a) + log[i + 1][k] * a)
    };
    let times: Vec<f64> = (0..motion.n_frames())
        .map(|k| k as f64 / motion.fps)
        .collect();
    let mut s = motion.clone();
    s.sequence_id = format!("{}+forces-{}", motion.sequence_id, forces.sequence_id);
    s.force_sensor = [0, 1].map(|side| times.iter().map(|&t| sample(side, t)).collect());
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
            "provenance": forces.provenance,
        },
        "note": "the hand forces of another sequence replayed on this motion, not a recording of this motion under force",
    });
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seq(id: &str, frames: usize, fps: f64, force: impl Fn(usize) -> f64) -> Sequence {
        Sequence {
            task: "t".into(),
            sequence_id: id.into(),
            fps,
            joint_names: vec!["j".into()],
            root_pos: vec![[0.0, 0.0, 0.78]; frames],
            root_quat_wxyz: vec![[1.0, 0.0, 0.0, 0.0]; frames],
            joint_pos: vec![vec![0.0]; frames],
            joint_vel: None,
            force_sensor: [
                (0..frames).map(|k| [force(k), 0.0, 0.0]).collect(),
                vec![[0.0, 0.0, 1.0]; frames],
            ],
            hand_from_sensor_wxyz: [[0.0, 1.0, 0.0, 0.0]; 2],
            force_point_hand: [[0.01, 0.0, 0.0]; 2],
            forces_recorded: false,
            provenance: serde_json::json!({"format": "test"}),
        }
    }

    #[test]
    fn forces_are_resampled_onto_the_motion_and_looped() {
        let motion = seq("clip", 61, 30.0, |_| 0.0); // 2 s
        let forces = seq("push_chair_000", 51, 50.0, |k| k as f64); // 1 s, fx = 50 t
        let g = with_forces_of(&motion, &forces);
        assert_eq!(g.sequence_id, "clip+forces-push_chair_000");
        assert_eq!(g.n_frames(), 61);
        assert!(g.forces_recorded);
        assert_eq!(g.hand_from_sensor_wxyz, forces.hand_from_sensor_wxyz);
        // t = 0.5 s → 25 N; t = 1.5 s loops to 0.5 s.
        assert!((g.force_sensor[0][15][0] - 25.0).abs() < 1e-9);
        assert!((g.force_sensor[0][45][0] - 25.0).abs() < 1e-9);
        assert_eq!(g.force_sensor[1][30], [0.0, 0.0, 1.0]);
        assert_eq!(g.provenance["forces_grafted_from"]["looped"], true);
        assert_eq!(g.root_pos, motion.root_pos);
    }

    #[test]
    fn first_seconds_cuts_every_series() {
        let s = seq("clip", 300, 30.0, |k| k as f64);
        let cut = first_seconds(&s, 2.0);
        assert_eq!(cut.n_frames(), 61);
        assert_eq!(cut.force_sensor[0].len(), 61);
        assert_eq!(first_seconds(&s, 100.0).n_frames(), 300);
    }
}
