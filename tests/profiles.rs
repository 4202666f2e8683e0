//! Dynamics profiles: the shipped ones load with the numbers of SOURCES.md, Gains and Policies, actions map
//! to targets as clip → scale → offset, and bad profiles are clear errors naming the field.

use thorarena::sim::profile::{bundled_profile_path, joint_group, load_profile};

mod common;
use common::g1;

#[test]
fn shipped_profiles_load_with_their_published_numbers() {
    let robot = g1();
    for name in ["twist2", "gmt", "beyondmimic", "default"] {
        let p = load_profile(&bundled_profile_path(name), &robot)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!((p.name.as_str(), p.substeps), (name, 4));
        assert_eq!(p.gains.kp.len(), 29);
    }
    let t = load_profile(&bundled_profile_path("twist2"), &robot).unwrap();
    let j = |n: &str| robot.joint_index(n).unwrap();
    assert_eq!(t.gains.kp[j("left_knee_joint")], 150.0);
    assert_eq!(
        (
            t.gains.kp[j("right_wrist_yaw_joint")],
            t.gains.kd[j("right_wrist_yaw_joint")]
        ),
        (4.0, 0.2)
    );
    assert_eq!(t.gains.kp[j("left_elbow_joint")], 40.0);
    assert_eq!(t.gains.effort_limit_nm[j("left_knee_joint")], 139.0);
    let b = load_profile(&bundled_profile_path("beyondmimic"), &robot).unwrap();
    assert!((b.gains.kp[j("left_hip_pitch_joint")] - 40.18).abs() < 0.01);
    assert!((b.gains.kd[j("left_hip_pitch_joint")] - 2.558).abs() < 0.001);
    assert!((b.action_scale[j("left_hip_pitch_joint")] - 0.25 * 88.0 / 40.18).abs() < 1e-3);
    assert_eq!(
        (
            b.action_offset_rad[j("left_shoulder_roll_joint")],
            b.action_offset_rad[j("right_shoulder_roll_joint")]
        ),
        (0.2, -0.2)
    );
}

#[test]
fn actions_are_clipped_scaled_and_offset_by_the_default_pose() {
    let robot = g1();
    let t = load_profile(&bundled_profile_path("twist2"), &robot).unwrap();
    let mut action = vec![0.0; 29];
    action[3] = 1.0;
    action[18] = 50.0; // clipped to 10
    let mut targets = vec![0.0; 29];
    t.targets_from_action(&action, &mut targets);
    assert!((targets[3] - (0.4 + 0.5)).abs() < 1e-12);
    assert!((targets[18] - (1.2 + 5.0)).abs() < 1e-12);
    assert_eq!(targets[0], -0.2);
}

fn error_for(edit: impl Fn(&str) -> String) -> String {
    let robot = g1();
    let text = std::fs::read_to_string(bundled_profile_path("twist2")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("p.toml");
    std::fs::write(&path, edit(&text)).unwrap();
    let msg = load_profile(&path, &robot).unwrap_err().to_string();
    assert!(msg.contains("p.toml"), "{msg}");
    msg
}

#[test]
fn bad_profiles_are_rejected_naming_the_field() {
    let msg = error_for(|t| t.replace("knee = 150.0", "kneee = 150.0"));
    assert!(
        msg.contains("kp.kneee") && msg.contains("no joint"),
        "{msg}"
    );
    let msg = error_for(|t| t.replace("physics_dt_s = 0.005", "physics_dt_s = 0.0"));
    assert!(
        msg.contains("physics_dt_s") && msg.contains("must be > 0"),
        "{msg}"
    );
    let msg = error_for(|t| t.replace("physics_dt_s = 0.005", "physics_dt_s = 0.003"));
    assert!(
        msg.contains("control_dt_s") && msg.contains("not a whole multiple"),
        "{msg}"
    );
    let msg = error_for(|t| t.replace("default = 5.0\n", ""));
    assert!(
        msg.contains("kd") && msg.contains("no value for joint"),
        "{msg}"
    );
    let msg = error_for(|t| t.replace("robot = \"g1_29dof\"", "robot = \"h1\""));
    assert!(msg.contains("field `robot`"), "{msg}");
    let msg = error_for(|t| t.replace("action_delay_steps = 0", "action_delay = 0"));
    assert!(msg.contains("action_delay"), "{msg}");
}

#[test]
fn joint_groups_drop_side_and_suffix() {
    assert_eq!(joint_group("left_hip_pitch_joint"), "hip_pitch");
    assert_eq!(joint_group("waist_yaw_joint"), "waist_yaw");
    assert_eq!(joint_group("right_wrist_roll_joint"), "wrist_roll");
}
