//! The BeyondMimic family's observation, block by block, from hand-made states: the 160-
//! and the 154-term layouts (holosoma's terms sorted by name), the joint order mapped by name (a reversed order moves every
//! per-joint block), the anchor pose of the reference in the robot's anchor frame (a shift
//! becomes `motion_anchor_pos_b`, a 90° yaw the two columns of `motion_anchor_ori_b`), base
//! velocities in the root frame; and a network whose metadata contradicts the profile is
//! reported.

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use thorarena::policy::beyondmimic::{
    build_observation, layout_width, ObservationSpec, Scratch, Term, KNOWN_LAYOUTS, LAYOUT_154,
    LAYOUT_154_MJLAB, LAYOUT_160,
};
use thorarena::policy::Observation;
use thorarena::sim::motion::ReferenceFrame;
use thorarena::sim::physics::RootState;
use thorarena::sim::robot::RobotModel;

#[path = "common/onnx_model.rs"]
mod onnx_model;
mod prereq;

fn g1() -> RobotModel {
    thorarena::sim::robot::load_bundled("g1_29dof").unwrap()
}

/// Joint j's angle in the hand-made states: 0.01·j rad, the waist (12–14) at zero so that
/// the torso anchor is the pelvis shifted, not turned.
fn q(j: f64) -> f64 {
    if (12.0..=14.0).contains(&j) {
        0.0
    } else {
        0.01 * j
    }
}

/// The robot at the origin, yawed by `yaw`, moving +x in the world at 1 m/s and turning
/// about z at 2 rad/s; joint j at `q(j)`, velocity 0.1·j.
fn observation(yaw: f64, reference: ReferenceFrame) -> Observation {
    Observation {
        env: 0,
        episode_id: 0,
        step: 3,
        time_s: 0.06,
        root: RootState {
            world_from_root: Isometry3::from_parts(
                Translation3::new(0.0, 0.0, 0.79),
                UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
            ),
            lin_vel_w: Vector3::new(1.0, 0.0, 0.0),
            ang_vel_w: Vector3::new(0.0, 0.0, 2.0),
        },
        q: (0..29).map(|j| q(j as f64)).collect(),
        qd: (0..29).map(|j| j as f64 * 0.1).collect(),
        last_action: vec![0.0; 29],
        reference: vec![reference],
    }
}

/// The reference: root at `(x, y)`, yawed by `yaw`, the same joints as the robot, joint
/// velocities −j.
fn reference(x: f64, y: f64, yaw: f64) -> ReferenceFrame {
    ReferenceFrame {
        world_from_root: Isometry3::from_parts(
            Translation3::new(x, y, 0.79),
            UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
        ),
        root_lin_vel_w: Vector3::zeros(),
        root_ang_vel_w: Vector3::zeros(),
        joint_pos: (0..29).map(|j| q(j as f64)).collect(),
        joint_vel: (0..29).map(|j| -(j as f64)).collect(),
        force_sensor: [Vector3::zeros(); 2],
    }
}

fn spec(robot: &RobotModel, terms: &[Term], reversed: bool) -> ObservationSpec {
    let to_canonical: Vec<usize> = if reversed {
        (0..29).rev().collect()
    } else {
        (0..29).collect()
    };
    ObservationSpec {
        terms: terms.to_vec(),
        default_pos: to_canonical.iter().map(|&c| c as f64 * 0.001).collect(),
        to_canonical,
        anchor_frame: robot.frame_index("torso_link").unwrap(),
    }
}

fn build(robot: &RobotModel, spec: &ObservationSpec, obs: &Observation) -> Vec<f32> {
    let last: Vec<f64> = (0..29).map(|i| 100.0 + i as f64).collect();
    let mut out = Vec::new();
    build_observation(
        spec,
        robot,
        obs,
        &obs.reference[0],
        &last,
        &mut Scratch::default(),
        &mut out,
    );
    out
}

fn close(a: &[f32], b: &[f64], tol: f64) {
    assert_eq!(a.len(), b.len());
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        assert!(
            (f64::from(*x) - y).abs() < tol,
            "index {i}: {x} vs {y}\n{a:?}\nvs {b:?}"
        );
    }
}

#[test]
fn the_160_term_layout_has_the_documented_blocks() {
    let robot = g1();
    let s = spec(&robot, &LAYOUT_160, false);
    assert_eq!(layout_width(&LAYOUT_160, 29), 160);
    // Robot and reference differ by a shift (1, 2) m only: the anchors differ by the same.
    let x = build(&robot, &s, &observation(0.0, reference(1.0, 2.0, 0.0)));
    assert_eq!(x.len(), 160);
    let qs: Vec<f64> = (0..29).map(|j| q(j as f64)).collect();
    close(&x[..29], &qs, 1e-6); // command: reference joint positions
    close(
        &x[29..58],
        &(0..29).map(|j| -(j as f64)).collect::<Vec<_>>(),
        1e-6,
    );
    close(&x[58..61], &[1.0, 2.0, 0.0], 1e-6); // anchor position
    close(&x[61..67], &[1.0, 0.0, 0.0, 1.0, 0.0, 0.0], 1e-6); // identity, two columns
    close(&x[67..70], &[1.0, 0.0, 0.0], 1e-6); // base linear velocity
    close(&x[70..73], &[0.0, 0.0, 2.0], 1e-6); // base angular velocity
    let rel: Vec<f64> = (0..29).map(|j| q(j as f64) - j as f64 * 0.001).collect();
    close(&x[73..102], &rel, 1e-6); // q − default
    close(
        &x[102..131],
        &(0..29).map(|j| j as f64 * 0.1).collect::<Vec<_>>(),
        1e-6,
    );
    close(
        &x[131..160],
        &(0..29).map(|i| 100.0 + i as f64).collect::<Vec<_>>(),
        1e-6,
    );
}

#[test]
fn a_yawed_robot_sees_the_reference_anchor_and_its_velocity_in_its_own_frame() {
    let robot = g1();
    let s = spec(&robot, &LAYOUT_160, false);
    // Robot yawed +90°, reference unyawed and 1 m ahead in world x: in the robot's frame
    // the reference is 1 m to its right (−y) and turned −90°; its world +x velocity is −y.
    let x = build(
        &robot,
        &s,
        &observation(std::f64::consts::FRAC_PI_2, reference(1.0, 0.0, 0.0)),
    );
    // Exactly: the anchors through the kinematics' own torso offset.
    let torso = robot.frame_index("torso_link").unwrap();
    let mut poses = Vec::new();
    thorarena::sim::robot::forward_kinematics(
        &robot,
        &Isometry3::identity(),
        &(0..29).map(|j| q(j as f64)).collect::<Vec<_>>(),
        &mut poses,
    );
    let t = thorarena::sim::robot::frame_pose(&robot, &poses, torso);
    let robot_anchor = Isometry3::from_parts(
        Translation3::new(0.0, 0.0, 0.79),
        UnitQuaternion::from_euler_angles(0.0, 0.0, std::f64::consts::FRAC_PI_2),
    ) * t;
    let ref_anchor = Isometry3::translation(1.0, 0.0, 0.79) * t;
    let rel = robot_anchor.inverse() * ref_anchor;
    let p = rel.translation.vector;
    close(&x[58..61], &[p.x, p.y, p.z], 1e-6);
    let m = rel.rotation.to_rotation_matrix();
    close(
        &x[61..67],
        &[
            m[(0, 0)],
            m[(0, 1)],
            m[(1, 0)],
            m[(1, 1)],
            m[(2, 0)],
            m[(2, 1)],
        ],
        1e-6,
    );
    // Roughly: the reference 1 m to the right, turned −90° (the torso is 4 mm behind the
    // pelvis axis).
    assert!((p.y + 1.0).abs() < 0.05 && p.x.abs() < 0.05, "{p:?}");
    assert!(m[(1, 0)] < -0.99, "{m:?}");
    close(&x[67..70], &[0.0, -1.0, 0.0], 1e-6);
}

#[test]
fn the_154_term_layout_drops_anchor_position_and_linear_velocity() {
    let robot = g1();
    assert_eq!(layout_width(&LAYOUT_154, 29), 154);
    let full = build(
        &robot,
        &spec(&robot, &LAYOUT_160, false),
        &observation(0.3, reference(0.5, -0.2, 0.1)),
    );
    let short = build(
        &robot,
        &spec(&robot, &LAYOUT_154, false),
        &observation(0.3, reference(0.5, -0.2, 0.1)),
    );
    assert_eq!(short.len(), 154);
    // holosoma's order: actions, angular velocity, joint positions, joint velocities,
    // command, orientation (its names sorted).
    assert_eq!(short[..29], full[131..160]);
    assert_eq!(short[29..32], full[70..73]);
    assert_eq!(short[32..61], full[73..102]);
    assert_eq!(short[61..90], full[102..131]);
    assert_eq!(short[90..148], full[..58]);
    assert_eq!(short[148..154], full[61..67]);
}

#[test]
fn the_policy_joint_order_is_mapped_by_name() {
    let robot = g1();
    let x = build(
        &robot,
        &spec(&robot, &LAYOUT_154, true),
        &observation(0.0, reference(0.0, 0.0, 0.0)),
    );
    // Policy joint i is canonical joint 28 − i in every per-joint block.
    let rev = |f: &dyn Fn(f64) -> f64| (0..29).rev().map(|j| f(j as f64)).collect::<Vec<f64>>();
    close(&x[90..119], &rev(&q), 1e-6);
    close(&x[119..148], &rev(&|j| -j), 1e-6);
    close(&x[32..61], &rev(&|j| q(j) - j * 0.001), 1e-6);
    close(&x[61..90], &rev(&|j| j * 0.1), 1e-6);
}

#[test]
fn a_network_whose_metadata_contradicts_the_profile_is_reported() {
    const TEST: &str = "beyondmimic_observation::metadata_contradicts_profile";
    let onnx = thorarena::reference_dir().join("holosoma/fastsac_g1_29dof_dancing.onnx");
    if !onnx.is_file() {
        return prereq::skip(TEST, &format!("{} is absent", onnx.display()));
    }
    let robot = std::sync::Arc::new(g1());
    let path = thorarena::sim::profile::bundled_profile_path("holosoma-wbt");
    let profile = thorarena::sim::profile::load_profile(&path, &robot).unwrap();
    let agrees =
        thorarena::policy::BeyondMimicPolicy::load(&onnx, robot.clone(), &profile).unwrap();
    assert_eq!(agrees.disagreements(), [] as [String; 0]);
    assert_eq!(agrees.terms(), LAYOUT_154);
    // The same network under a profile whose knee gains are doubled.
    let mut text = std::fs::read_to_string(&path).unwrap();
    text = text.replace("knee = 99.098428", "knee = 198.196856");
    let dir = tempfile::tempdir().unwrap();
    let edited = dir.path().join("edited.toml");
    std::fs::write(&edited, text).unwrap();
    let profile = thorarena::sim::profile::load_profile(&edited, &robot).unwrap();
    let differs = thorarena::policy::BeyondMimicPolicy::load(&onnx, robot, &profile).unwrap();
    let d = differs.disagreements();
    assert_eq!(d.len(), 1, "{d:?}");
    assert!(d[0].starts_with("kp:") && d[0].contains("knee"), "{d:?}");
}

/// A network `width` inputs wide with no metadata, loaded under bundled profile `profile`.
fn load_bare(width: i64, profile: &str) -> Result<thorarena::policy::BeyondMimicPolicy, String> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bare.onnx");
    let net = onnx_model::Network {
        inputs: vec![("obs", vec![1, width])],
        outputs: vec![("actions", "obs", 29, 0.0)],
        metadata: Vec::new(),
    };
    std::fs::write(&path, net.bytes()).unwrap();
    let robot = std::sync::Arc::new(g1());
    let profile = thorarena::sim::profile::load_profile(
        &thorarena::sim::profile::bundled_profile_path(profile),
        &robot,
    )
    .unwrap();
    thorarena::policy::BeyondMimicPolicy::load(&path, robot, &profile).map_err(|e| e.to_string())
}

#[test]
fn a_width_two_known_layouts_fit_is_refused_unless_the_profile_names_the_terms() {
    // 154 inputs and nothing saying which 154: both candidates named, nothing guessed.
    let e = load_bare(154, "beyondmimic").err().expect("refused");
    assert!(e.contains("fits 2 known layouts"), "{e}");
    for (name, terms) in KNOWN_LAYOUTS
        .iter()
        .filter(|(_, l)| layout_width(l, 29) == 154)
    {
        let listed: Vec<&str> = terms.iter().map(|t| t.name()).collect();
        assert!(
            e.contains(name) && e.contains(&listed.join(", ")),
            "{name}: {e}"
        );
    }
    assert!(e.contains("observation_names"), "{e}");
    // The holosoma profile names its terms: the same file loads, in holosoma's order.
    let named = load_bare(154, "holosoma-wbt").unwrap();
    assert_eq!(named.terms(), LAYOUT_154);
    // 160 wide: one known layout fits, and it is taken.
    assert_eq!(load_bare(160, "beyondmimic").unwrap().terms(), LAYOUT_160);
    // A width no layout has names every known width.
    let e = load_bare(150, "beyondmimic").err().expect("refused");
    assert!(e.contains("160") && e.contains("154"), "{e}");
}

/// A 154-wide network with `metadata`, under the holosoma-wbt profile with
/// `[beyondmimic] joint_names` set to `profile_order` (none when empty).
fn load_ordered(
    metadata: Vec<(&str, String)>,
    profile_order: &[String],
) -> Result<thorarena::policy::BeyondMimicPolicy, String> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bare.onnx");
    let net = onnx_model::Network {
        inputs: vec![("obs", vec![1, 154])],
        outputs: vec![("actions", "obs", 29, 0.0)],
        metadata,
    };
    std::fs::write(&path, net.bytes()).unwrap();
    let robot = std::sync::Arc::new(g1());
    let mut text = std::fs::read_to_string(thorarena::sim::profile::bundled_profile_path(
        "holosoma-wbt",
    ))
    .unwrap();
    if !profile_order.is_empty() {
        let quoted: Vec<String> = profile_order.iter().map(|n| format!("\"{n}\"")).collect();
        text = text.replace(
            "[beyondmimic]\n",
            &format!("[beyondmimic]\njoint_names = [{}]\n", quoted.join(", ")),
        );
    }
    let profile_path = dir.path().join("profile.toml");
    std::fs::write(&profile_path, text).unwrap();
    let profile = thorarena::sim::profile::load_profile(&profile_path, &robot).unwrap();
    thorarena::policy::BeyondMimicPolicy::load(&path, robot, &profile).map_err(|e| e.to_string())
}

#[test]
fn a_bare_export_takes_its_joint_order_from_the_profile_and_a_contradiction_is_refused() {
    use thorarena::policy::beyondmimic::JointOrderFrom;
    use thorarena::policy::Policy as _;
    let robot = g1();
    let canonical: Vec<String> = robot.joints.iter().map(|j| j.name.clone()).collect();
    // Isaac Lab's breadth-first order interleaves left, right and waist joints: here any
    // order not the robot's will do, so the robot's reversed.
    let reversed: Vec<String> = canonical.iter().rev().cloned().collect();

    // Nothing names an order: the robot's is assumed, and policy check says so.
    let bare = load_ordered(Vec::new(), &[]).unwrap();
    assert_eq!(bare.joint_order_from(), JointOrderFrom::Robot);
    assert_eq!(bare.joint_order(), (0..29).collect::<Vec<_>>());
    assert!(
        bare.wiring()
            .facts
            .iter()
            .any(|f| f.contains("joint order: the robot's")),
        "{:?}",
        bare.wiring().facts
    );

    // The profile names it: policy joint i is the robot's joint 28 - i.
    let ordered = load_ordered(Vec::new(), &reversed).unwrap();
    assert_eq!(ordered.joint_order_from(), JointOrderFrom::Profile);
    assert_eq!(ordered.joint_order(), (0..29).rev().collect::<Vec<_>>());

    // The file names the same order: it agrees, and the file is credited.
    let file_meta = vec![("joint_names", reversed.join(","))];
    let both = load_ordered(file_meta, &reversed).unwrap();
    assert_eq!(both.joint_order_from(), JointOrderFrom::File);

    // The file names another order than the profile: refused, naming the first joint
    // where they part.
    let e = load_ordered(vec![("joint_names", canonical.join(","))], &reversed)
        .err()
        .expect("refused");
    assert!(
        e.contains("different orders") && e.contains(&canonical[0]) && e.contains(&reversed[0]),
        "{e}"
    );

    // A profile order that names a joint twice is refused.
    let mut twice = reversed.clone();
    twice[1] = twice[0].clone();
    let e = load_ordered(Vec::new(), &twice).err().expect("refused");
    assert!(e.contains("named twice in the profile"), "{e}");
}

#[test]
fn every_term_name_parses_back_to_its_term() {
    for (_, terms) in KNOWN_LAYOUTS {
        for &t in terms {
            assert_eq!(Term::parse(t.name()), Some(t));
        }
    }
    assert_eq!(layout_width(&LAYOUT_154_MJLAB, 29), 154);
}
