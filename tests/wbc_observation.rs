//! wbc-mjlab's general tracker, its observation and its action, from hand-made states
//! (yawed, tilted, moving), against values computed here independently, with the formulas
//! of its deploy code (wbc-mjlab/wbc-g1-deploy at 066ab157, `src/WbcMotionLoader.cpp`):
//! every `ref_*` term is the inverse rotation of the reference `torso_link` applied to a
//! world vector (its linear and angular velocity; gravity (0, 0, −1)), written out below
//! as the quaternion product `q* v q`; the height is the anchor's world z. The anchor's
//! velocities are taken here by central differences of its pose along the reference's
//! motion, not by the library's joint-by-joint chain. And the residual action: a zero
//! action means the reference's joints, and the `actions` term recovers the last action
//! from the previous step's reference.

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use std::sync::Arc;
use thorarena::policy::beyondmimic::{
    build_observation, layout_width, ObservationSpec, Scratch, LAYOUT_132_WBC,
};
use thorarena::policy::{BeyondMimicPolicy, Observation, Policy};
use thorarena::sim::motion::ReferenceFrame;
use thorarena::sim::physics::RootState;
use thorarena::sim::profile::ActionMode;
use thorarena::sim::robot::{forward_kinematics, frame_pose, RobotModel};

#[path = "common/onnx_model.rs"]
mod onnx_model;

fn g1() -> RobotModel {
    thorarena::sim::robot::load_bundled("g1_29dof").unwrap()
}

const WAIST: [usize; 3] = [12, 13, 14];

/// A reference moving every way at once: root at (0.3, −0.2, 0.78), rolled 0.15, pitched
/// −0.1 and yawed 0.9 rad, moving (0.6, −0.25, 0.05) m/s and turning (0.3, −0.2, 0.8)
/// rad/s in the world; every joint bent, the waist (which carries the torso anchor) too,
/// and every joint moving.
fn moving_reference() -> ReferenceFrame {
    let mut joint_pos: Vec<f64> = (0..29).map(|j| 0.02 * j as f64 - 0.1).collect();
    let mut joint_vel: Vec<f64> = (0..29).map(|j| 0.05 * j as f64 - 0.4).collect();
    for (k, &j) in WAIST.iter().enumerate() {
        joint_pos[j] = [0.3, 0.1, -0.2][k];
        joint_vel[j] = [1.0, -0.5, 0.7][k];
    }
    ReferenceFrame {
        world_from_root: Isometry3::from_parts(
            Translation3::new(0.3, -0.2, 0.78),
            UnitQuaternion::from_euler_angles(0.15, -0.1, 0.9),
        ),
        root_lin_vel_w: Vector3::new(0.6, -0.25, 0.05),
        root_ang_vel_w: Vector3::new(0.3, -0.2, 0.8),
        joint_pos,
        joint_vel,
        force_sensor: [Vector3::zeros(); 2],
    }
}

/// The reference `dt` seconds along its velocities.
fn advanced(r: &ReferenceFrame, dt: f64) -> ReferenceFrame {
    let turn = UnitQuaternion::from_scaled_axis(r.root_ang_vel_w * dt);
    ReferenceFrame {
        world_from_root: Isometry3::from_parts(
            Translation3::from(r.world_from_root.translation.vector + r.root_lin_vel_w * dt),
            turn * r.world_from_root.rotation,
        ),
        joint_pos: r
            .joint_pos
            .iter()
            .zip(&r.joint_vel)
            .map(|(p, v)| p + v * dt)
            .collect(),
        ..r.clone()
    }
}

fn torso(robot: &RobotModel, r: &ReferenceFrame) -> Isometry3<f64> {
    let mut poses = Vec::new();
    forward_kinematics(robot, &r.world_from_root, &r.joint_pos, &mut poses);
    frame_pose(robot, &poses, robot.frame_index("torso_link").unwrap())
}

/// The deploy code's `quatApplyInverse(q, v)`: `q* v q` with q = (w, x, y, z), written as
/// the Hamilton product, no library rotation.
fn quat_apply_inverse(q: [f64; 4], v: [f64; 3]) -> [f64; 3] {
    let mul = |a: [f64; 4], b: [f64; 4]| {
        [
            a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
            a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
            a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
            a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
        ]
    };
    let conj = [q[0], -q[1], -q[2], -q[3]];
    let r = mul(mul(conj, [0.0, v[0], v[1], v[2]]), q);
    [r[1], r[2], r[3]]
}

fn wxyz(q: &UnitQuaternion<f64>) -> [f64; 4] {
    [q.w, q.i, q.j, q.k]
}

/// The robot: tilted (roll −0.2, pitch 0.25, yaw −1.1), turning (0.5, −0.3, 1.2) rad/s.
fn robot_state(reference: Vec<ReferenceFrame>) -> Observation {
    Observation {
        env: 0,
        episode_id: 0,
        step: 5,
        time_s: 0.1,
        root: RootState {
            world_from_root: Isometry3::from_parts(
                Translation3::new(0.1, 0.0, 0.75),
                UnitQuaternion::from_euler_angles(-0.2, 0.25, -1.1),
            ),
            lin_vel_w: Vector3::new(0.2, 0.1, 0.0),
            ang_vel_w: Vector3::new(0.5, -0.3, 1.2),
        },
        q: (0..29).map(|j| 0.03 * j as f64 - 0.3).collect(),
        qd: (0..29).map(|j| 0.7 - 0.04 * j as f64).collect(),
        last_action: vec![0.0; 29],
        reference,
    }
}

fn close(what: &str, got: &[f32], want: &[f64], tol: f64) {
    assert_eq!(got.len(), want.len(), "{what}: length");
    for (k, (g, w)) in got.iter().zip(want).enumerate() {
        assert!(
            (f64::from(*g) - w).abs() <= tol,
            "{what}[{k}]: built {g}, expected {w}"
        );
    }
}

#[test]
fn the_132_term_observation_matches_the_deploy_codes_formulas() {
    let robot = g1();
    let reference = moving_reference();
    let obs = robot_state(vec![reference.clone()]);
    let default_pos: Vec<f64> = (0..29).map(|j| 0.01 * j as f64).collect();
    let last_action: Vec<f64> = (0..29).map(|j| 0.1 - 0.01 * j as f64).collect();
    let spec = ObservationSpec {
        terms: LAYOUT_132_WBC.to_vec(),
        to_canonical: (0..29).collect(),
        default_pos: default_pos.clone(),
        anchor_frame: robot.frame_index("torso_link").unwrap(),
    };
    let mut out = Vec::new();
    build_observation(
        &spec,
        &robot,
        &obs,
        &reference,
        &last_action,
        &mut Scratch::default(),
        &mut out,
    );
    assert_eq!(out.len(), 132);
    assert_eq!(layout_width(&LAYOUT_132_WBC, 29), 132);

    // The anchor and its velocities by central differences of its pose.
    let h = 1e-6;
    let anchor = torso(&robot, &reference);
    let (ahead, behind) = (
        torso(&robot, &advanced(&reference, h)),
        torso(&robot, &advanced(&reference, -h)),
    );
    let lin_w = (ahead.translation.vector - behind.translation.vector) / (2.0 * h);
    let ang_w = (ahead.rotation * behind.rotation.inverse()).scaled_axis() / (2.0 * h);
    let q = wxyz(&anchor.rotation);
    // The waist moves the anchor: its velocity is not the root's.
    // (The torso's origin sits at the waist joints, a few cm from the pelvis's: its linear
    // velocity differs by ≈ 0.014 m/s here, its angular velocity by the waist's 1.37 rad/s.)
    assert!((lin_w - reference.root_lin_vel_w).norm() > 0.01);
    assert!((ang_w - reference.root_ang_vel_w).norm() > 0.5);

    close("ref_base_height", &out[0..1], &[anchor.translation.z], 1e-6);
    close(
        "ref_base_lin_vel_b",
        &out[1..4],
        &quat_apply_inverse(q, lin_w.into()),
        1e-5,
    );
    close(
        "ref_base_ang_vel_b",
        &out[4..7],
        &quat_apply_inverse(q, ang_w.into()),
        1e-5,
    );
    close(
        "ref_gravity_b",
        &out[7..10],
        &quat_apply_inverse(q, [0.0, 0.0, -1.0]),
        1e-6,
    );
    close("ref_joint_pos", &out[10..39], &reference.joint_pos, 1e-6);
    // The robot's own terms: its pelvis IMU.
    let root = wxyz(&obs.root.world_from_root.rotation);
    close(
        "base_ang_vel",
        &out[39..42],
        &quat_apply_inverse(root, obs.root.ang_vel_w.into()),
        1e-6,
    );
    close(
        "projected_gravity",
        &out[42..45],
        &quat_apply_inverse(root, [0.0, 0.0, -1.0]),
        1e-6,
    );
    let rel: Vec<f64> = obs.q.iter().zip(&default_pos).map(|(q, d)| q - d).collect();
    close("joint_pos", &out[45..74], &rel, 1e-6);
    close("joint_vel", &out[74..103], &obs.qd, 1e-6);
    close("actions", &out[103..132], &last_action, 1e-6);
}

/// A 132-wide network answering zero, its metadata wbc-mjlab's (terms, residual mode),
/// loaded under the `wbc-mjlab` profile.
fn zero_residual_network(dir: &std::path::Path) -> BeyondMimicPolicy {
    let path = dir.join("wbc.onnx");
    let names = LAYOUT_132_WBC.map(|t| t.name()).join(",");
    let net = onnx_model::Network {
        inputs: vec![("obs", vec![1, 132])],
        outputs: vec![("actions", "obs", 29, 0.0)],
        metadata: vec![
            ("observation_names", names),
            ("action_mode", "reference_residual".into()),
            ("anchor_body_name", "torso_link".into()),
        ],
    };
    std::fs::write(&path, net.bytes()).unwrap();
    let robot = Arc::new(g1());
    let profile = thorarena::policy::registry::profile("wbc-mjlab", &robot).unwrap();
    BeyondMimicPolicy::load(&path, robot, &profile).unwrap()
}

#[test]
fn a_residual_action_is_added_to_the_reference_and_recovered_from_the_last_step() {
    let dir = tempfile::tempdir().unwrap();
    let mut policy = zero_residual_network(dir.path());
    assert_eq!(policy.action_mode(), ActionMode::ReferenceResidual);
    assert_eq!(policy.terms(), LAYOUT_132_WBC);
    assert_eq!(policy.disagreements(), [] as [String; 0]);
    // It asks for the previous control step's reference frame too.
    assert_eq!(policy.reference_offsets_s(), vec![0.0, -0.02]);

    let robot = g1();
    let profile = thorarena::policy::registry::profile("wbc-mjlab", &robot).unwrap();
    let now = moving_reference();
    let before = advanced(&now, -0.02);
    // The last action the policy meant (a_prev), as the raw action the profile received.
    let a_prev: Vec<f64> = (0..29).map(|j| 0.3 - 0.02 * j as f64).collect();
    let mut obs = robot_state(vec![now.clone(), before.clone()]);
    obs.last_action = (0..29)
        .map(|j| {
            let target = before.joint_pos[j] + profile.action_scale[j] * a_prev[j];
            (target - profile.action_offset_rad[j]) / profile.action_scale[j]
        })
        .collect();
    let mut actions = vec![vec![0.0; 29]];
    policy.act(std::slice::from_ref(&obs), &mut actions);
    // Zero from the network: the targets are the reference's joints, exactly.
    let mut targets = vec![0.0; 29];
    profile.targets_from_action(&actions[0], &mut targets);
    for (j, (t, r)) in targets.iter().zip(&now.joint_pos).enumerate() {
        assert!((t - r).abs() < 1e-9, "joint {j}: target {t}, reference {r}");
    }
    close(
        "actions (recovered)",
        &policy.last_inputs()[0][103..132],
        &a_prev,
        1e-5,
    );
}

#[test]
fn wbc_mjlab_is_one_entry_of_the_registry_with_its_own_profile() {
    let arg = thorarena::policy::registry::PolicySource::parse("wbc-mjlab:w.onnx").unwrap();
    assert_eq!(arg.family().profile, "wbc-mjlab");
    assert_eq!(arg.default_profile(), "wbc-mjlab");
    let robot = g1();
    let profile = thorarena::policy::registry::profile("wbc-mjlab", &robot).unwrap();
    let bm = profile.beyondmimic.as_ref().unwrap();
    assert_eq!(bm.action_mode, Some(ActionMode::ReferenceResidual));
    assert_eq!(bm.observation_names, LAYOUT_132_WBC.map(|t| t.name()));
    // The torque cap is 0.98 × the motor catalog's peak: 131 N·m at the knees.
    let knee = robot.joint_index("left_knee_joint").unwrap();
    assert!((profile.gains.effort_limit_nm[knee] - 0.98 * 131.0).abs() < 1e-9);
    // And the default profile is refused for it, saying why.
    let default = thorarena::policy::registry::profile("default", &robot).unwrap();
    let e = arg.check_profile(&default).unwrap_err();
    assert!(e.contains("wbc-mjlab"), "{e}");
}
