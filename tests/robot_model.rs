//! The robot model: the bundled G1 loads with the numbers of its description, forward
//! kinematics places it sensibly, and every kind of bad description is a typed error that
//! names the file and the field.

use nalgebra::Isometry3;
use std::path::Path;
use thorarena::sim::robot::{self, RobotError};

fn g1() -> robot::RobotModel {
    robot::load_bundled("g1_29dof").expect("bundled G1 loads")
}

#[test]
fn bundled_g1_has_29_joints_in_canonical_order_and_its_published_mass() {
    let m = g1();
    assert_eq!(m.n_joints(), 29);
    assert_eq!(m.joints[0].name, "left_hip_pitch_joint");
    assert_eq!(m.joints[12].name, "waist_yaw_joint");
    assert_eq!(m.joints[28].name, "right_wrist_yaw_joint");
    // 39 URDF links, 9 of them fixed: 30 bodies remain.
    assert_eq!(m.bodies.len(), 30);
    assert!(
        (m.total_mass_kg() - 33.34).abs() < 0.05,
        "mass {}",
        m.total_mass_kg()
    );
    let knee = &m.joints[m.joint_index("left_knee_joint").unwrap()];
    assert_eq!(
        (knee.effort_nm, knee.lower_rad, knee.upper_rad),
        (139.0, -0.087267, 2.8798)
    );
    assert!((knee.armature_kgm2 - 0.025101925).abs() < 1e-12);
}

#[test]
fn fixed_links_are_merged_and_remain_addressable_as_frames() {
    let m = g1();
    let hand = m.frame_index("left_rubber_hand").unwrap();
    let wrist = m.body_index("left_wrist_yaw_link").unwrap();
    assert_eq!(m.frames[hand].body, wrist);
    assert!((m.frames[hand].body_from_frame.translation.vector.x - 0.0415).abs() < 1e-12);
    assert!(
        (m.bodies[wrist].mass_kg - (0.08457647 + 0.170)).abs() < 1e-12,
        "wrist yaw link + rubber hand"
    );
    assert!(
        m.body_index("head_link").is_none(),
        "the head is merged into the torso"
    );
}

#[test]
fn keypoint_sets_have_the_documented_sizes_and_upper_lower_split() {
    let m = g1();
    let d = m.keypoint_set("default").unwrap();
    assert_eq!((d.frames.len(), d.n_upper), (13, 7));
    let t = m.keypoint_set("twist9").unwrap();
    assert_eq!((t.frames.len(), t.n_upper), (9, 5));
    assert!(m
        .keypoint_set("default")
        .unwrap()
        .frames
        .iter()
        .all(|&f| m.frames[f].name != "pelvis"));
}

#[test]
fn default_pose_kinematics_puts_feet_below_pelvis_and_is_left_right_symmetric() {
    let m = g1();
    let mut poses = Vec::new();
    robot::forward_kinematics(&m, &Isometry3::identity(), &m.default_pose(), &mut poses);
    let l = poses[m.body_index("left_ankle_roll_link").unwrap()]
        .translation
        .vector;
    let r = poses[m.body_index("right_ankle_roll_link").unwrap()]
        .translation
        .vector;
    assert!(l.z < -0.6 && r.z < -0.6, "ankles at {l:?} {r:?}");
    assert!((l.x - r.x).abs() < 1e-6 && (l.y + r.y).abs() < 1e-6 && (l.z - r.z).abs() < 1e-6);
    let lowest = robot::lowest_sole_point_z(&m, &poses).unwrap();
    assert!(lowest < l.z, "sole below the ankle frame");
    let com = robot::center_of_mass(&m, &poses);
    assert!(com.y.abs() < 0.01, "com {com:?}");
}

/// A writable copy of the bundled G1 whose robot.toml we can break.
fn broken_copy(edit: impl Fn(&str) -> String) -> tempfile::TempDir {
    let src = robot::bundled_robot_dir("g1_29dof");
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(src.join("g1_29dof.urdf"), dir.path().join("g1_29dof.urdf")).unwrap();
    let toml = std::fs::read_to_string(src.join("robot.toml")).unwrap();
    std::fs::write(dir.path().join("robot.toml"), edit(&toml)).unwrap();
    dir
}

fn load_err(dir: &Path) -> String {
    let err = robot::load_robot_dir(dir).expect_err("must be rejected");
    let text = err.to_string();
    match err {
        RobotError::BadField { ref path, .. } | RobotError::Toml { ref path, .. } => {
            assert!(text.contains(&path.display().to_string()));
            assert_eq!(path.file_name().unwrap(), "robot.toml", "{text}");
        }
        other => panic!("unexpected error kind: {other}"),
    }
    text
}

#[test]
fn unknown_joint_is_rejected_naming_file_and_field() {
    let dir = broken_copy(|t| t.replacen("\"left_knee_joint\"", "\"left_knee_jont\"", 1));
    let msg = load_err(dir.path());
    assert!(
        msg.contains("joints[3].name") && msg.contains("unknown joint `left_knee_jont`"),
        "{msg}"
    );
}

#[test]
fn missing_joint_is_a_count_mismatch_naming_the_missing_joint() {
    let dir = broken_copy(|t| {
        t.lines()
            .filter(|l| !l.contains("\"right_wrist_yaw_joint\""))
            .collect::<Vec<_>>()
            .join("\n")
    });
    let msg = load_err(dir.path());
    assert!(
        msg.contains("field `joints`")
            && msg.contains("lists 28 joints")
            && msg.contains("right_wrist_yaw_joint"),
        "{msg}"
    );
}

#[test]
fn missing_keypoint_body_is_rejected_naming_the_set_and_index() {
    let dir = broken_copy(|t| t.replacen("\"left_elbow_link\",", "\"left_elbo_link\",", 1));
    let msg = load_err(dir.path());
    assert!(
        msg.contains("keypoints.default.upper[3]") && msg.contains("left_elbo_link"),
        "{msg}"
    );
}

#[test]
fn duplicate_joint_and_default_outside_limits_are_rejected() {
    let dir = broken_copy(|t| t.replacen("\"left_hip_roll_joint\"", "\"left_hip_pitch_joint\"", 1));
    assert!(load_err(dir.path()).contains("listed twice"));
    let dir = broken_copy(|t| t.replacen("default_rad = 0.4 }", "default_rad = 3.5 }", 1));
    let msg = load_err(dir.path());
    assert!(
        msg.contains("joints[3].default_rad") && msg.contains("outside the URDF limits"),
        "{msg}"
    );
}

#[test]
fn unknown_field_and_bad_hand_frame_are_rejected() {
    let dir = broken_copy(|t| {
        t.replacen(
            "root_body = \"pelvis\"",
            "root_body = \"pelvis\"\nroot_bdy = 1",
            1,
        )
    });
    assert!(load_err(dir.path()).contains("root_bdy"));
    let dir =
        broken_copy(|t| t.replacen("frame = \"left_rubber_hand\"", "frame = \"left_glove\"", 1));
    let msg = load_err(dir.path());
    assert!(
        msg.contains("hands.left.frame") && msg.contains("left_glove"),
        "{msg}"
    );
}

#[test]
fn missing_directory_is_an_io_error_naming_the_file() {
    let err = robot::load_robot_dir(Path::new("/nonexistent/robot")).unwrap_err();
    assert!(matches!(err, RobotError::Io { .. }));
    assert!(err.to_string().contains("/nonexistent/robot/robot.toml"));
}
