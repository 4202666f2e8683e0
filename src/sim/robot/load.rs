//! Reading `robot.toml` and the URDF, merging fixed links, and validating the result.

use super::config::{FrameConfig, HandConfig, RobotConfig};
use super::error::RobotError;
use super::model::{Body, Frame, Geometry, Hand, Joint, KeypointSet, RobotModel, Shape};
use nalgebra::{Isometry3, Matrix3, Point3, Translation3, Unit, UnitQuaternion, Vector3};
use std::path::{Path, PathBuf};

/// Loads `<dir>/robot.toml` and the URDF it names.
pub fn load_robot_dir(dir: &Path) -> Result<RobotModel, RobotError> {
    let toml_path = dir.join("robot.toml");
    let text = read(&toml_path)?;
    let config: RobotConfig = toml::from_str(&text).map_err(|e| RobotError::Toml {
        path: toml_path.clone(),
        message: e.to_string(),
    })?;
    let urdf_path = dir.join(&config.urdf);
    let urdf_text = read(&urdf_path)?;
    let urdf = urdf_rs::read_from_string(&urdf_text).map_err(|e| RobotError::Urdf {
        path: urdf_path.clone(),
        message: e.to_string(),
    })?;
    build_model(&config, &urdf, &toml_path, &urdf_path)
}

/// The largest robot file (`robot.toml`, its URDF) read, bytes (the G1's URDF is about
/// 100 KiB).
pub const MAX_ROBOT_FILE_BYTES: u64 = 16 * crate::files::bounded_read::MIB;

/// `path` whole, a regular file of at most [`MAX_ROBOT_FILE_BYTES`].
fn read(path: &Path) -> Result<String, RobotError> {
    crate::files::bounded_read::read_to_string(path, "robot file", MAX_ROBOT_FILE_BYTES).map_err(
        |source| RobotError::Io {
            path: path.to_path_buf(),
            source,
        },
    )
}

/// Assembles and validates a model from an already parsed config and URDF.
///
/// The phases run in this order, so the first error a broken robot reports stays the same
/// however it is broken: root link, joint list, tree walk, joints, mass and shapes, extra
/// frames, keypoints, hands.
pub fn build_model(
    config: &RobotConfig,
    urdf: &urdf_rs::Robot,
    toml_path: &Path,
    urdf_path: &Path,
) -> Result<RobotModel, RobotError> {
    let inputs = Inputs {
        config,
        urdf,
        toml_path,
        urdf_path,
    };
    let root_link = inputs.link_index(&config.root_body).ok_or_else(|| {
        inputs.bad_toml(
            "root_body",
            format!("no URDF link named `{}`", config.root_body),
        )
    })?;
    check_joint_list(&inputs)?;
    let Tree {
        mut bodies,
        mut frames,
        joints,
        links,
    } = walk_tree(&inputs, root_link)?;
    let joints = actuated_joints(&inputs, joints)?;
    add_mass_and_shapes(&inputs, &mut bodies, &links)?;
    add_extra_frames(&inputs, &mut frames)?;
    let keypoint_sets = keypoint_sets(&inputs, &frames)?;
    let hands = [
        hand(&inputs, &frames, "left", &config.hands.left)?,
        hand(&inputs, &frames, "right", &config.hands.right)?,
    ];
    Ok(RobotModel {
        name: config.name.clone(),
        joints,
        bodies,
        frames,
        keypoint_sets,
        hands,
    })
}

/// The parsed `robot.toml` and URDF a model is built from, with their paths so that an
/// error names the file (and field) at fault.
struct Inputs<'a> {
    config: &'a RobotConfig,
    urdf: &'a urdf_rs::Robot,
    toml_path: &'a Path,
    urdf_path: &'a Path,
}

impl Inputs<'_> {
    /// A bad field of `robot.toml`.
    fn bad_toml(&self, field: impl Into<String>, reason: impl Into<String>) -> RobotError {
        bad_field(self.toml_path, field.into(), reason.into())
    }

    /// A bad element of the URDF.
    fn bad_urdf(&self, field: impl Into<String>, reason: impl Into<String>) -> RobotError {
        bad_field(self.urdf_path, field.into(), reason.into())
    }

    /// The index of the URDF link `name`.
    fn link_index(&self, name: &str) -> Option<usize> {
        self.urdf.links.iter().position(|l| l.name == name)
    }
}

fn bad_field(path: &Path, field: String, reason: String) -> RobotError {
    RobotError::BadField {
        path: path.to_path_buf(),
        field,
        reason,
    }
}

/// Every URDF joint must be either fixed or listed in robot.toml, and vice versa; a listed
/// joint must be revolute with a positive effort and velocity limit and a non-negative
/// armature. Checked before the tree walk, which relies on it.
fn check_joint_list(inputs: &Inputs) -> Result<(), RobotError> {
    let Inputs {
        config,
        urdf,
        urdf_path,
        ..
    } = inputs;
    let mut seen = std::collections::HashSet::new();
    for (i, jc) in config.joints.iter().enumerate() {
        if !seen.insert(jc.name.as_str()) {
            return Err(inputs.bad_toml(
                format!("joints[{i}].name"),
                format!("`{}` is listed twice", jc.name),
            ));
        }
        let Some(uj) = urdf.joints.iter().find(|j| j.name == jc.name) else {
            return Err(inputs.bad_toml(
                format!("joints[{i}].name"),
                format!(
                    "unknown joint `{}`: not in {}",
                    jc.name,
                    urdf_path.display()
                ),
            ));
        };
        if uj.joint_type != urdf_rs::JointType::Revolute {
            return Err(inputs.bad_toml(
                format!("joints[{i}].name"),
                format!(
                    "`{}` is a {:?} joint; only revolute joints can be actuated",
                    jc.name, uj.joint_type
                ),
            ));
        }
        for (field, v) in [
            ("effort_nm", jc.effort_nm),
            ("velocity_rad_s", jc.velocity_rad_s),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(inputs.bad_toml(
                    format!("joints[{i}].{field}"),
                    format!("must be > 0, got {v}"),
                ));
            }
        }
        if !(jc.armature_kgm2.is_finite() && jc.armature_kgm2 >= 0.0) {
            return Err(inputs.bad_toml(
                format!("joints[{i}].armature_kgm2"),
                format!("must be >= 0, got {}", jc.armature_kgm2),
            ));
        }
    }
    let n_moving = urdf
        .joints
        .iter()
        .filter(|j| j.joint_type != urdf_rs::JointType::Fixed)
        .count();
    if n_moving != config.joints.len() {
        let missing: Vec<&str> = urdf
            .joints
            .iter()
            .filter(|j| {
                j.joint_type != urdf_rs::JointType::Fixed && !seen.contains(j.name.as_str())
            })
            .map(|j| j.name.as_str())
            .collect();
        return Err(inputs.bad_toml(
            "joints",
            format!(
                "lists {} joints but the URDF has {} non-fixed joints (missing: {})",
                config.joints.len(),
                n_moving,
                missing.join(", ")
            ),
        ));
    }
    Ok(())
}

/// Where a URDF link sits: (link index, body index, body_from_link).
type LinkPlacement = (usize, usize, Isometry3<f64>);

/// The URDF tree walked from the root: moving joints start a new body, fixed ones merge
/// their child link into the parent's body.
struct Tree {
    /// Root first, then in URDF declaration order.
    bodies: Vec<Body>,
    /// One per link, in visiting order.
    frames: Vec<Frame>,
    /// By robot.toml joint index; `None` for a joint the walk never reached.
    joints: Vec<Option<Joint>>,
    /// Every link, in visiting order.
    links: Vec<LinkPlacement>,
}

/// Walks the tree depth-first from `root_link`; a link reached twice is an error (the
/// URDF is not a tree).
fn walk_tree(inputs: &Inputs, root_link: usize) -> Result<Tree, RobotError> {
    let urdf = inputs.urdf;
    let mut tree = Tree {
        bodies: vec![new_body(
            &urdf.links[root_link],
            None,
            None,
            Isometry3::identity(),
            Vector3::x_axis(),
        )],
        frames: Vec::new(),
        joints: vec![None; inputs.config.joints.len()],
        links: Vec::new(),
    };
    let mut stack: Vec<LinkPlacement> = vec![(root_link, 0, Isometry3::identity())];
    let mut visited = vec![false; urdf.links.len()];
    while let Some((link, body, body_from_link)) = stack.pop() {
        if std::mem::replace(&mut visited[link], true) {
            return Err(inputs.bad_urdf(
                format!("link `{}`", urdf.links[link].name),
                "appears twice in the tree",
            ));
        }
        tree.links.push((link, body, body_from_link));
        tree.frames.push(Frame {
            name: urdf.links[link].name.clone(),
            body,
            body_from_frame: body_from_link,
        });
        let children = tree.attach_children(inputs, link, body, body_from_link)?;
        // Bodies are numbered in URDF declaration order; the stack is filled in reverse so
        // that it pops them in that order too.
        stack.extend(children.into_iter().rev());
    }
    Ok(tree)
}

impl Tree {
    /// The child links of `link` (which sits in `body`), in URDF declaration order: a
    /// fixed joint's child joins `body`; a moving joint's child starts a new body, and the
    /// joint is recorded.
    fn attach_children(
        &mut self,
        inputs: &Inputs,
        link: usize,
        body: usize,
        body_from_link: Isometry3<f64>,
    ) -> Result<Vec<LinkPlacement>, RobotError> {
        let Inputs { config, urdf, .. } = inputs;
        let mut children = Vec::new();
        for uj in urdf
            .joints
            .iter()
            .filter(|j| j.parent.link == urdf.links[link].name)
        {
            let child = inputs.link_index(&uj.child.link).ok_or_else(|| {
                inputs.bad_urdf(
                    format!("joint `{}`.child", uj.name),
                    format!("no link `{}`", uj.child.link),
                )
            })?;
            let link_from_joint = pose_of(&uj.origin);
            if uj.joint_type == urdf_rs::JointType::Fixed {
                children.push((child, body, body_from_link * link_from_joint));
                continue;
            }
            let ji = config
                .joints
                .iter()
                .position(|j| j.name == uj.name)
                .expect("checked above");
            let axis = Vector3::from(uj.axis.xyz.0);
            let axis = Unit::try_new(axis, 1e-9).ok_or_else(|| {
                inputs.bad_urdf(format!("joint `{}`.axis", uj.name), "zero-length axis")
            })?;
            let new = self.bodies.len();
            self.bodies.push(new_body(
                &urdf.links[child],
                Some(body),
                Some(ji),
                body_from_link * link_from_joint,
                axis,
            ));
            let jc = &config.joints[ji];
            self.joints[ji] = Some(Joint {
                name: jc.name.clone(),
                body: new,
                lower_rad: uj.limit.lower,
                upper_rad: uj.limit.upper,
                effort_nm: jc.effort_nm,
                velocity_rad_s: jc.velocity_rad_s,
                armature_kgm2: jc.armature_kgm2,
                default_rad: jc.default_rad,
            });
            children.push((child, new, Isometry3::identity()));
        }
        Ok(children)
    }
}

/// The joints in canonical order: each must have been reached from the root and its
/// default angle must lie within its URDF limits.
fn actuated_joints(inputs: &Inputs, reached: Vec<Option<Joint>>) -> Result<Vec<Joint>, RobotError> {
    let config = inputs.config;
    let joints: Vec<Joint> = reached
        .into_iter()
        .enumerate()
        .map(|(i, j)| {
            j.ok_or_else(|| {
                inputs.bad_toml(
                    format!("joints[{i}].name"),
                    format!(
                        "`{}` is not reachable from root `{}`",
                        config.joints[i].name, config.root_body
                    ),
                )
            })
        })
        .collect::<Result<_, _>>()?;
    for (i, j) in joints.iter().enumerate() {
        if !(j.lower_rad <= j.default_rad && j.default_rad <= j.upper_rad) {
            return Err(inputs.bad_toml(
                format!("joints[{i}].default_rad"),
                format!(
                    "{} is outside the URDF limits [{}, {}]",
                    j.default_rad, j.lower_rad, j.upper_rad
                ),
            ));
        }
    }
    Ok(joints)
}

/// Mass properties and shapes: every link adds its inertial and collisions to the body it
/// belongs to; a body that ends up without mass cannot move and is an error.
fn add_mass_and_shapes(
    inputs: &Inputs,
    bodies: &mut [Body],
    links: &[LinkPlacement],
) -> Result<(), RobotError> {
    let mut acc: Vec<MassAccumulator> = vec![MassAccumulator::default(); bodies.len()];
    for &(link, body, body_from_link) in links {
        let l = &inputs.urdf.links[link];
        acc[body].add(&l.inertial, &body_from_link);
        for (ci, c) in l.collision.iter().enumerate() {
            let geometry = geometry_of(&c.geometry).ok_or_else(|| {
                inputs.bad_urdf(
                    format!("link `{}`.collision[{ci}]", l.name),
                    "only box, sphere, capsule and cylinder collisions are supported",
                )
            })?;
            let name = c.name.clone().unwrap_or_default();
            bodies[body].shapes.push(Shape {
                is_sole: name == inputs.config.sole_collision,
                name,
                body_from_shape: body_from_link * pose_of(&c.origin),
                geometry,
            });
        }
    }
    for (b, a) in bodies.iter_mut().zip(acc) {
        let (m, com, inertia) = a.finish();
        if m <= 0.0 || m.is_nan() {
            return Err(inputs.bad_urdf(
                format!("link `{}`.inertial", b.name),
                "moving body without mass",
            ));
        }
        b.mass_kg = m;
        b.com_b = com;
        b.inertia_kgm2 = inertia;
    }
    Ok(())
}

/// The extra frames of robot.toml, after the links' frames; an extra frame may not take a
/// link's name, and its parent must be a link (or an earlier extra frame).
fn add_extra_frames(inputs: &Inputs, frames: &mut Vec<Frame>) -> Result<(), RobotError> {
    for (name, fc) in &inputs.config.frames {
        if frames.iter().any(|f| &f.name == name) {
            return Err(inputs.bad_toml(
                format!("frames.{name}"),
                "a URDF link has that name already",
            ));
        }
        let frame = extra_frame(name, fc, frames).ok_or_else(|| {
            inputs.bad_toml(
                format!("frames.{name}.parent"),
                format!("no URDF link `{}`", fc.parent),
            )
        })?;
        frames.push(frame);
    }
    Ok(())
}

/// The index of frame `name`; `field` names where robot.toml referred to it.
fn frame_index(
    inputs: &Inputs,
    frames: &[Frame],
    name: &str,
    field: String,
) -> Result<usize, RobotError> {
    frames
        .iter()
        .position(|f| f.name == name)
        .ok_or_else(|| inputs.bad_toml(field, format!("unknown body or frame `{name}`")))
}

/// The keypoint sets (upper-body frames, then lower-body ones); the `default` set is
/// required, and no set may be empty.
fn keypoint_sets(inputs: &Inputs, frames: &[Frame]) -> Result<Vec<KeypointSet>, RobotError> {
    let config = inputs.config;
    if !config.keypoints.contains_key("default") {
        return Err(inputs.bad_toml(
            "keypoints.default",
            "the `default` keypoint set is required",
        ));
    }
    let mut keypoint_sets = Vec::new();
    for (name, kc) in &config.keypoints {
        let mut idx = Vec::new();
        for (part, list) in [("upper", &kc.upper), ("lower", &kc.lower)] {
            for (k, f) in list.iter().enumerate() {
                idx.push(frame_index(
                    inputs,
                    frames,
                    f,
                    format!("keypoints.{name}.{part}[{k}]"),
                )?);
            }
        }
        if idx.is_empty() {
            return Err(inputs.bad_toml(format!("keypoints.{name}"), "empty keypoint set"));
        }
        keypoint_sets.push(KeypointSet {
            name: name.clone(),
            frames: idx,
            n_upper: kc.upper.len(),
        });
    }
    Ok(keypoint_sets)
}

/// The `side` hand: the frame it is attached to, its contact point and its force sensor's
/// orientation.
fn hand(
    inputs: &Inputs,
    frames: &[Frame],
    side: &str,
    hc: &HandConfig,
) -> Result<Hand, RobotError> {
    Ok(Hand {
        frame: frame_index(inputs, frames, &hc.frame, format!("hands.{side}.frame"))?,
        point_hand: Point3::from(hc.point_xyz),
        hand_from_sensor: rpy(hc.hand_from_sensor_rpy),
    })
}

fn new_body(
    link: &urdf_rs::Link,
    parent: Option<usize>,
    joint: Option<usize>,
    parent_from_joint: Isometry3<f64>,
    axis: Unit<Vector3<f64>>,
) -> Body {
    Body {
        name: link.name.clone(),
        parent,
        joint,
        parent_from_joint,
        axis,
        mass_kg: 0.0,
        com_b: Vector3::zeros(),
        inertia_kgm2: Matrix3::zeros(),
        shapes: Vec::new(),
    }
}

fn extra_frame(name: &str, fc: &FrameConfig, frames: &[Frame]) -> Option<Frame> {
    let parent = frames.iter().find(|f| f.name == fc.parent)?;
    let parent_from_frame =
        Isometry3::from_parts(Translation3::from(Vector3::from(fc.xyz)), rpy(fc.rpy));
    Some(Frame {
        name: name.to_string(),
        body: parent.body,
        body_from_frame: parent.body_from_frame * parent_from_frame,
    })
}

/// URDF roll-pitch-yaw (fixed axes x, then y, then z).
pub(crate) fn rpy(r: [f64; 3]) -> UnitQuaternion<f64> {
    UnitQuaternion::from_euler_angles(r[0], r[1], r[2])
}

fn pose_of(p: &urdf_rs::Pose) -> Isometry3<f64> {
    Isometry3::from_parts(Translation3::from(Vector3::from(p.xyz.0)), rpy(p.rpy.0))
}

fn geometry_of(g: &urdf_rs::Geometry) -> Option<Geometry> {
    Some(match *g {
        urdf_rs::Geometry::Box { ref size } => Geometry::Box {
            half_extents: [size.0[0] / 2.0, size.0[1] / 2.0, size.0[2] / 2.0],
        },
        urdf_rs::Geometry::Sphere { radius } => Geometry::Sphere { radius },
        urdf_rs::Geometry::Capsule { radius, length } => Geometry::Capsule {
            radius,
            half_length: length / 2.0,
        },
        urdf_rs::Geometry::Cylinder { radius, length } => Geometry::Cylinder {
            radius,
            half_length: length / 2.0,
        },
        urdf_rs::Geometry::Mesh { .. } => return None,
    })
}

/// Sums link inertials expressed in a common body frame (parallel-axis theorem).
#[derive(Debug, Clone, Default)]
struct MassAccumulator {
    parts: Vec<(f64, Vector3<f64>, Matrix3<f64>)>, // mass, com in body frame, inertia about own com in body axes
}

impl MassAccumulator {
    fn add(&mut self, inertial: &urdf_rs::Inertial, body_from_link: &Isometry3<f64>) {
        let m = inertial.mass.value;
        if m <= 0.0 {
            return;
        }
        let i = &inertial.inertia;
        let i_inertial = Matrix3::new(
            i.ixx, i.ixy, i.ixz, i.ixy, i.iyy, i.iyz, i.ixz, i.iyz, i.izz,
        );
        let body_from_inertial = body_from_link * pose_of(&inertial.origin);
        let r = body_from_inertial.rotation.to_rotation_matrix();
        let inertia_b = r.matrix() * i_inertial * r.matrix().transpose();
        self.parts
            .push((m, body_from_inertial.translation.vector, inertia_b));
    }

    fn finish(self) -> (f64, Vector3<f64>, Matrix3<f64>) {
        let m: f64 = self.parts.iter().map(|p| p.0).sum();
        if m <= 0.0 {
            return (0.0, Vector3::zeros(), Matrix3::zeros());
        }
        let com = self.parts.iter().map(|p| p.1 * p.0).sum::<Vector3<f64>>() / m;
        let inertia = self
            .parts
            .iter()
            .fold(Matrix3::zeros(), |acc, (mk, ck, ik)| {
                let d = ck - com;
                acc + ik + (Matrix3::identity() * d.dot(&d) - d * d.transpose()) * *mk
            });
        (m, com, inertia)
    }
}

/// The directory of a robot shipped with ThorArena (`data/robots/<name>`).
pub fn bundled_robot_dir(name: &str) -> PathBuf {
    crate::data_dir().join("robots").join(name)
}
