//! The robot model as the rest of ThorArena sees it: actuated joints in canonical order,
//! rigid bodies after fixed links are merged, named frames, keypoints and hands.

use nalgebra::{Isometry3, Matrix3, Point3, Unit, Vector3};

/// A loaded, validated robot.
///
/// Bodies are in topological order (a parent always precedes its children) and body 0 is
/// the root. Fixed URDF links are merged into their parent body; their names survive as
/// [`Frame`]s, so a keypoint or hand may name any URDF link.
#[derive(Debug, Clone)]
pub struct RobotModel {
    /// Robot name (the directory name under `data/robots/`).
    pub name: String,
    /// Actuated joints in canonical order.
    pub joints: Vec<Joint>,
    /// Rigid bodies, root first, parents before children.
    pub bodies: Vec<Body>,
    /// Every URDF link and every extra frame of `robot.toml`, by name.
    pub frames: Vec<Frame>,
    /// Keypoint sets by name; `default` always exists.
    pub keypoint_sets: Vec<KeypointSet>,
    /// Left and right hand, in that order.
    pub hands: [Hand; 2],
}

/// An actuated revolute joint.
#[derive(Debug, Clone)]
pub struct Joint {
    /// URDF joint name.
    pub name: String,
    /// The body this joint moves (its child).
    pub body: usize,
    /// Lower position limit, rad.
    pub lower_rad: f64,
    /// Upper position limit, rad.
    pub upper_rad: f64,
    /// Torque limit, N·m.
    pub effort_nm: f64,
    /// Velocity limit, rad/s.
    pub velocity_rad_s: f64,
    /// Reflected rotor inertia, kg·m².
    pub armature_kgm2: f64,
    /// Angle in the default standing pose, rad.
    pub default_rad: f64,
}

/// A rigid body: one moving URDF link plus every link fixed to it.
#[derive(Debug, Clone)]
pub struct Body {
    /// Name of the moving URDF link.
    pub name: String,
    /// Parent body; `None` for the root.
    pub parent: Option<usize>,
    /// The actuated joint connecting this body to its parent (`None` for the root).
    pub joint: Option<usize>,
    /// Joint frame in the parent body frame; the body frame coincides with the joint frame
    /// at zero angle (URDF convention).
    pub parent_from_joint: Isometry3<f64>,
    /// Joint axis in the body frame.
    pub axis: Unit<Vector3<f64>>,
    /// Mass, kg (including merged fixed links).
    pub mass_kg: f64,
    /// Centre of mass in the body frame, m.
    pub com_b: Vector3<f64>,
    /// Inertia about the centre of mass, body axes, kg·m².
    pub inertia_kgm2: Matrix3<f64>,
    /// Collision shapes (including those of merged links).
    pub shapes: Vec<Shape>,
}

/// A primitive collision shape attached to a body.
#[derive(Debug, Clone)]
pub struct Shape {
    /// The URDF collision `name`.
    pub name: String,
    /// A sole shape (its name is `robot.toml`'s `sole_collision`): touches the ground in
    /// the default contact mode.
    pub is_sole: bool,
    /// Shape pose in the body frame.
    pub body_from_shape: Isometry3<f64>,
    /// The shape itself.
    pub geometry: Geometry,
}

/// Primitive geometry; capsules and cylinders lie along their local z axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Geometry {
    /// Box with half extents, m.
    Box {
        /// Half extents along x, y, z, m.
        half_extents: [f64; 3],
    },
    /// Sphere.
    Sphere {
        /// Radius, m.
        radius: f64,
    },
    /// Capsule along z.
    Capsule {
        /// Radius, m.
        radius: f64,
        /// Half the distance between the hemisphere centres, m.
        half_length: f64,
    },
    /// Cylinder along z.
    Cylinder {
        /// Radius, m.
        radius: f64,
        /// Half height, m.
        half_length: f64,
    },
}

/// A named frame rigidly attached to a body.
#[derive(Debug, Clone)]
pub struct Frame {
    /// Frame name (URDF link name or `robot.toml` frame name).
    pub name: String,
    /// The body carrying it.
    pub body: usize,
    /// Frame pose in the body frame.
    pub body_from_frame: Isometry3<f64>,
}

/// A keypoint set for the tracking metrics.
#[derive(Debug, Clone)]
pub struct KeypointSet {
    /// Set name (`default`, `twist9`, …).
    pub name: String,
    /// Frame indices, upper-body ones first.
    pub frames: Vec<usize>,
    /// Number of leading entries of `frames` that belong to the upper body.
    pub n_upper: usize,
}

/// A hand on which a recorded interaction force is replayed.
#[derive(Debug, Clone)]
pub struct Hand {
    /// Frame index of the hand.
    pub frame: usize,
    /// Application point in the hand frame, m.
    pub point_hand: Point3<f64>,
    /// Default rotation from sensor to hand frame.
    pub hand_from_sensor: nalgebra::UnitQuaternion<f64>,
}

impl RobotModel {
    /// SHA-256 of the resolved model — joints with their limits, bodies with their mass,
    /// inertia and shapes, frames, keypoint sets, hands — lowercase hex: the robot's part of
    /// a run's identity (`run.json`). Of the resolved values (exact: `Debug` prints every
    /// `f64` as its shortest round trip), so a URDF reformatted changes nothing and any
    /// number the simulation reads does.
    pub fn fingerprint(&self) -> String {
        crate::files::content_hash::sha256_hex(format!("{self:?}").as_bytes())
    }

    /// Number of actuated joints.
    pub fn n_joints(&self) -> usize {
        self.joints.len()
    }

    /// Total mass, kg.
    pub fn total_mass_kg(&self) -> f64 {
        self.bodies.iter().map(|b| b.mass_kg).sum()
    }

    /// Index of a joint by URDF name.
    pub fn joint_index(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.name == name)
    }

    /// Index of a body by the name of its moving URDF link.
    pub fn body_index(&self, name: &str) -> Option<usize> {
        self.bodies.iter().position(|b| b.name == name)
    }

    /// Index of a frame by name (any URDF link or extra frame).
    pub fn frame_index(&self, name: &str) -> Option<usize> {
        self.frames.iter().position(|f| f.name == name)
    }

    /// A keypoint set by name.
    pub fn keypoint_set(&self, name: &str) -> Option<&KeypointSet> {
        self.keypoint_sets.iter().find(|k| k.name == name)
    }

    /// Joint angles of the default pose in canonical order, rad.
    pub fn default_pose(&self) -> Vec<f64> {
        self.joints.iter().map(|j| j.default_rad).collect()
    }
}
