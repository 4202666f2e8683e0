//! Building a rapier world holding one robot as a multibody.

use super::convert::{pose_to_rapier, vec_to_rapier};
use crate::sim::physics::payload::{Inertial, PointMass};
use crate::sim::physics::settings::{ContactMode, PdForm, PhysicsSettings};
use crate::sim::physics::state::{PdGains, ResetState};
use crate::sim::robot::{forward_kinematics, Geometry, RobotModel};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use rapier3d::prelude::*;

/// A rapier world with the robot in it, and the handles needed to drive it.
pub(super) struct World {
    pub world: PhysicsWorld,
    /// Rigid body per model body.
    pub bodies: Vec<RigidBodyHandle>,
    /// The robot's multibody.
    pub multibody: MultibodyIndex,
    /// Per joint (canonical order): multibody link id and generalized-coordinate index.
    pub links: Vec<(usize, usize)>,
    /// Root centre of mass in the root frame: the rapier root body frame sits there
    /// (see [`build_world`]).
    pub root_com_b: Vector3<f64>,
    /// The ground's collider.
    pub ground: ColliderHandle,
    /// Every robot collider: its model body and its pose in that body's (model) frame.
    pub robot_colliders: Vec<RobotCollider>,
}

/// A robot collider, its model body, and its pose in that body's (model) frame.
pub(super) type RobotCollider = (ColliderHandle, usize, Isometry3<f64>);

/// Builds a world with the robot in `state`.
///
/// Two of rapier 0.36's multibody pitfalls are handled here (ARCHITECTURE.md, rapier pitfalls):
/// - a floating root is integrated as if its centre of mass were at its frame origin, so
///   the root rigid body's frame is moved to the centre of mass and the root's child
///   joints are shifted by the same offset; readouts shift back;
/// - every new joint gets 0.1 damping on angular DoFs (the free root too): all damping is
///   zeroed, and the hybrid PD's kd is written in its place.
pub(super) fn build_world(
    model: &RobotModel,
    settings: &PhysicsSettings,
    gains: &PdGains,
    state: &ResetState,
    payloads: &[PointMass],
) -> World {
    let mut world = empty_world(settings);
    let ground = insert_ground(&mut world, settings);
    let root_com_b = model.bodies[0].com_b;
    let root_shift =
        Isometry3::from_parts(Translation3::from(root_com_b), UnitQuaternion::identity());
    let (bodies, robot_colliders) =
        insert_bodies(&mut world, model, settings, state, root_shift, payloads);
    let joint_handles = insert_joints(&mut world, model, settings, &bodies, root_shift);
    let (multibody, links) = settle_multibody(&mut world, bodies[0], &joint_handles);
    let mb = world
        .multibody_joints
        .get_multibody_mut(multibody)
        .expect("exists");
    set_joint_dynamics(mb, model, settings, gains, &links);
    set_joint_angles(mb, state, &links);
    mb.forward_kinematics(&world.bodies, true);
    mb.update_rigid_bodies(&mut world.bodies, true);
    set_velocities(mb, settings, state, root_com_b, &links);
    World {
        world,
        bodies,
        multibody,
        links,
        root_com_b,
        ground,
        robot_colliders,
    }
}

/// A world with the settings' gravity, time step and solver iterations, and nothing in it.
fn empty_world(settings: &PhysicsSettings) -> PhysicsWorld {
    let mut world = PhysicsWorld {
        gravity: Vector::new(
            settings.gravity[0] as f32,
            settings.gravity[1] as f32,
            settings.gravity[2] as f32,
        ),
        ..PhysicsWorld::default()
    };
    world.integration_parameters.dt = settings.dt_s as f32;
    world.integration_parameters.num_solver_iterations = settings.solver_iterations.max(1);
    world
}

/// The ground: the top face of a large box at z = 0.
fn insert_ground(world: &mut PhysicsWorld, settings: &PhysicsSettings) -> ColliderHandle {
    let ground_body =
        world.insert_body(RigidBodyBuilder::fixed().translation(Vector::new(0.0, 0.0, -0.5)));
    world.insert_collider(
        ColliderBuilder::cuboid(100.0, 100.0, 0.5).friction(settings.friction as f32),
        Some(ground_body),
    )
}

/// One rigid body per model body, posed as `state` puts it, with the colliders
/// `settings.contacts` asks for. The root body's frame sits at its centre of mass
/// (`root_shift` from the model's root frame; see [`build_world`]). Returns the bodies and
/// every robot collider with its model body and its pose in that body's model frame.
fn insert_bodies(
    world: &mut PhysicsWorld,
    model: &RobotModel,
    settings: &PhysicsSettings,
    state: &ResetState,
    root_shift: Isometry3<f64>,
    payloads: &[PointMass],
) -> (Vec<RigidBodyHandle>, Vec<RobotCollider>) {
    let mut world_from_body = Vec::new();
    forward_kinematics(
        model,
        &state.root.world_from_root,
        &state.q,
        &mut world_from_body,
    );
    let mut bodies = Vec::with_capacity(model.bodies.len());
    let mut robot_colliders = Vec::new();
    for (i, body) in model.bodies.iter().enumerate() {
        let inertial =
            Inertial::of(body).with_point_masses(payloads.iter().filter(|p| p.body == i && i != 0));
        let (pose, local_com) = if i == 0 {
            (world_from_body[0] * root_shift, Vector3::zeros())
        } else {
            (world_from_body[i], inertial.com_b)
        };
        let builder = if i == 0 && settings.fixed_base {
            RigidBodyBuilder::fixed()
        } else {
            RigidBodyBuilder::dynamic()
        };
        let handle = world.insert_body(
            builder
                .pose(pose_to_rapier(&pose))
                .can_sleep(false)
                .additional_mass_properties(mass_properties(&inertial, &local_com)),
        );
        let body_shift = if i == 0 {
            root_shift.inverse()
        } else {
            Isometry3::identity()
        };
        for shape in &body.shapes {
            let collides = match settings.contacts {
                ContactMode::Soles => shape.is_sole,
                ContactMode::AllShapes => true,
                ContactMode::None => false,
            };
            if !collides {
                continue;
            }
            let (collider, shape_from_collider) = collider_of(&shape.geometry);
            let body_from_collider = shape.body_from_shape * shape_from_collider;
            let collider = collider
                .position(pose_to_rapier(&(body_shift * body_from_collider)))
                .density(0.0)
                .friction(settings.friction as f32);
            let c = world.insert_collider(collider, Some(handle));
            robot_colliders.push((c, i, body_from_collider));
        }
        bodies.push(handle);
    }
    (bodies, robot_colliders)
}

/// The body's mass and inertia (its payloads included), with its centre of mass at
/// `local_com` in the rigid body's frame (colliders get zero density: the model's inertials
/// are the whole mass).
fn mass_properties(body: &Inertial, local_com: &Vector3<f64>) -> MassProperties {
    let inertia = body.inertia_kgm2.map(|x| x as f32);
    MassProperties::with_inertia_matrix(
        vec_to_rapier(local_com),
        body.mass_kg as f32,
        Matrix::from_cols_array(&[
            inertia[(0, 0)],
            inertia[(1, 0)],
            inertia[(2, 0)],
            inertia[(0, 1)],
            inertia[(1, 1)],
            inertia[(2, 1)],
            inertia[(0, 2)],
            inertia[(1, 2)],
            inertia[(2, 2)],
        ]),
    )
}

/// A revolute multibody joint per model joint (canonical order), with the URDF limits when
/// `settings.joint_limits`. Joints of the root's children are shifted with the root frame
/// (see [`build_world`]).
fn insert_joints(
    world: &mut PhysicsWorld,
    model: &RobotModel,
    settings: &PhysicsSettings,
    bodies: &[RigidBodyHandle],
    root_shift: Isometry3<f64>,
) -> Vec<MultibodyJointHandle> {
    let mut joint_handles = Vec::with_capacity(model.joints.len());
    for joint in &model.joints {
        let body = &model.bodies[joint.body];
        let parent = body.parent.expect("a jointed body has a parent");
        // Joint frames with their x axis along the joint axis (rapier revolutes turn about x).
        let align =
            UnitQuaternion::rotation_between(&Vector3::x(), &body.axis).unwrap_or_else(|| {
                UnitQuaternion::from_axis_angle(&Vector3::z_axis(), std::f64::consts::PI)
            });
        let align = Isometry3::from_parts(Translation3::identity(), align);
        let parent_shift = if parent == 0 {
            root_shift.inverse()
        } else {
            Isometry3::identity()
        };
        let mut builder = GenericJointBuilder::new(JointAxesMask::LOCKED_REVOLUTE_AXES)
            .local_frame1(pose_to_rapier(
                &(parent_shift * body.parent_from_joint * align),
            ))
            .local_frame2(pose_to_rapier(&align));
        if settings.joint_limits {
            builder = builder.limits(
                JointAxis::AngX,
                [joint.lower_rad as f32, joint.upper_rad as f32],
            );
        }
        let handle = world
            .multibody_joints
            .insert(bodies[parent], bodies[joint.body], builder.build(), true)
            .expect("the robot tree has no loops");
        joint_handles.push(handle);
    }
    joint_handles
}

/// The robot's multibody and, per joint, its link id and generalized-coordinate index.
/// Forward kinematics runs first: it settles the root type (free or fixed) and so the DoF
/// indices read here.
fn settle_multibody(
    world: &mut PhysicsWorld,
    root: RigidBodyHandle,
    joint_handles: &[MultibodyJointHandle],
) -> (MultibodyIndex, Vec<(usize, usize)>) {
    let multibody = world
        .multibody_joints
        .rigid_body_link(root)
        .expect("root is in the multibody")
        .multibody;
    world
        .multibody_joints
        .get_multibody_mut(multibody)
        .expect("exists")
        .forward_kinematics(&world.bodies, true);
    let links: Vec<(usize, usize)> = joint_handles
        .iter()
        .map(|h| {
            let (mb, link_id) = world.multibody_joints.get(*h).expect("inserted above");
            (link_id, mb.link(link_id).expect("valid link").assembly_id())
        })
        .collect();
    (multibody, links)
}

/// Armature per joint, and damping: rapier's default damping zeroed everywhere (see
/// [`build_world`]), the hybrid PD's kd written in its place.
fn set_joint_dynamics(
    mb: &mut Multibody,
    model: &RobotModel,
    settings: &PhysicsSettings,
    gains: &PdGains,
    links: &[(usize, usize)],
) {
    mb.damping_mut().fill(0.0);
    for (j, &(_, dof)) in links.iter().enumerate() {
        mb.armature_mut()[dof] = model.joints[j].armature_kgm2 as f32;
        if settings.pd_form == PdForm::Hybrid {
            mb.damping_mut()[dof] = gains.kd[j] as f32;
        }
    }
}

/// Moves every joint to `state`'s angle.
fn set_joint_angles(mb: &mut Multibody, state: &ResetState, links: &[(usize, usize)]) {
    for (j, &(link_id, _)) in links.iter().enumerate() {
        let l = mb.link_mut(link_id).expect("valid link");
        let current = l.joint.coords()[3];
        l.joint.apply_displacement(&[state.q[j] as f32 - current]);
    }
}

/// The generalized velocity of `state`: a free root's [v of the centre of mass, ω] in
/// world (the root frame sits at the centre of mass, `root_com_b`), then joint rates.
fn set_velocities(
    mb: &mut Multibody,
    settings: &PhysicsSettings,
    state: &ResetState,
    root_com_b: Vector3<f64>,
    links: &[(usize, usize)],
) {
    let mut gv = mb.generalized_velocity_mut();
    if !settings.fixed_base {
        let r = state.root.world_from_root.rotation * root_com_b;
        let v_com = state.root.lin_vel_w + state.root.ang_vel_w.cross(&r);
        for k in 0..3 {
            gv[k] = v_com[k] as f32;
            gv[3 + k] = state.root.ang_vel_w[k] as f32;
        }
    }
    for (j, &(_, dof)) in links.iter().enumerate() {
        gv[dof] = state.qd[j] as f32;
    }
}

/// A rapier collider for a primitive, and the collider's pose in the shape frame (rapier
/// cylinders lie along y, ours along z).
fn collider_of(g: &Geometry) -> (ColliderBuilder, Isometry3<f64>) {
    let none = Isometry3::identity();
    match *g {
        Geometry::Box { half_extents: h } => (
            ColliderBuilder::cuboid(h[0] as f32, h[1] as f32, h[2] as f32),
            none,
        ),
        Geometry::Sphere { radius } => (ColliderBuilder::ball(radius as f32), none),
        Geometry::Capsule {
            radius,
            half_length,
        } => (
            ColliderBuilder::capsule_z(half_length as f32, radius as f32),
            none,
        ),
        Geometry::Cylinder {
            radius,
            half_length,
        } => (
            ColliderBuilder::cylinder(half_length as f32, radius as f32),
            Isometry3::rotation(Vector3::x() * std::f64::consts::FRAC_PI_2),
        ),
    }
}
