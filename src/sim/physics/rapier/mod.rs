//! The rapier3d multibody backend (reduced coordinates; impulse joints are far too loose
//! for the G1's light ankle and waist links next to heavy bodies).

mod build;
mod convert;

use super::payload::PointMass;
use super::settings::{PdForm, PhysicsSettings};
use super::state::{ExternalForce, GroundContact, PdGains, PhysicsState, ResetState, RootState};
use super::Physics;
use crate::sim::robot::RobotModel;
use build::{build_world, World};
use convert::{point_to_rapier, pose_from_rapier, vec_to_rapier};
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use std::sync::Arc;

/// The robot simulated by rapier3d as one multibody.
///
/// The PD law runs here, every physics step, in the form policies were trained with (see
/// [`PdForm`]); applied torques are recomputed from that law because rapier does not
/// report multibody motor impulses.
pub struct RapierPhysics {
    model: Arc<RobotModel>,
    settings: PhysicsSettings,
    gains: PdGains,
    targets: Vec<f64>,
    /// Added to the PD torques before their clamp, N·m (`Physics::set_feedforward`).
    feedforward_nm: Vec<f64>,
    external: Vec<ExternalForce>,
    /// Point masses folded into their bodies at each reset (`Physics::set_payloads`).
    payloads: Vec<PointMass>,
    applied_torque_nm: Vec<f64>,
    world: World,
    time_s: f64,
}

impl RapierPhysics {
    /// A robot at rest in its default pose, standing with its lowest sole point on the
    /// ground, with the given gains.
    pub fn new(model: Arc<RobotModel>, settings: PhysicsSettings, gains: PdGains) -> Self {
        let n = model.n_joints();
        assert_eq!(gains.kp.len(), n, "kp length");
        assert_eq!(gains.kd.len(), n, "kd length");
        assert_eq!(gains.effort_limit_nm.len(), n, "effort length");
        let state = standing_default_pose(&model);
        let world = build_world(&model, &settings, &gains, &state, &[]);
        Self {
            targets: state.q.clone(),
            feedforward_nm: vec![0.0; n],
            applied_torque_nm: vec![0.0; n],
            external: Vec::new(),
            payloads: Vec::new(),
            model,
            settings,
            gains,
            world,
            time_s: 0.0,
        }
    }

    fn multibody(&self) -> &rapier3d::prelude::Multibody {
        self.world
            .world
            .multibody_joints
            .get_multibody(self.world.multibody)
            .expect("robot multibody")
    }

    fn root_state(&self) -> RootState {
        let rb = &self.world.world.bodies[self.world.bodies[0]];
        let world_from_com = pose_from_rapier(rb.position());
        let shift = Isometry3::from_parts(
            Translation3::from(-self.world.root_com_b),
            UnitQuaternion::identity(),
        );
        let world_from_root = world_from_com * shift;
        if self.settings.fixed_base {
            return RootState::at_rest(world_from_root);
        }
        // Link velocities lag one substep in rapier; the generalized velocity does not.
        let gv = self.multibody().generalized_velocity();
        let v_com = Vector3::new(gv[0] as f64, gv[1] as f64, gv[2] as f64);
        let w = Vector3::new(gv[3] as f64, gv[4] as f64, gv[5] as f64);
        let r = world_from_root.translation.vector - world_from_com.translation.vector;
        RootState {
            world_from_root,
            lin_vel_w: v_com + w.cross(&r),
            ang_vel_w: w,
        }
    }
}

/// The default pose at rest, lifted so that the lowest sole point touches z = 0.
pub fn standing_default_pose(model: &RobotModel) -> ResetState {
    let q = model.default_pose();
    let mut poses = Vec::new();
    crate::sim::robot::forward_kinematics(model, &Isometry3::identity(), &q, &mut poses);
    let lowest = crate::sim::robot::lowest_sole_point_z(model, &poses).unwrap_or(-1.0);
    let root = Isometry3::translation(0.0, 0.0, -lowest);
    ResetState {
        root: RootState::at_rest(root),
        qd: vec![0.0; q.len()],
        q,
    }
}

impl Physics for RapierPhysics {
    fn model(&self) -> &RobotModel {
        &self.model
    }

    fn settings(&self) -> &PhysicsSettings {
        &self.settings
    }

    fn reset(&mut self, state: &ResetState) {
        let n = self.model.n_joints();
        assert_eq!(state.q.len(), n, "reset q length");
        assert_eq!(state.qd.len(), n, "reset qd length");
        // A fresh world: no contact cache or solver warm start leaks between episodes, so an
        // episode's result never depends on what ran before it in the same slot.
        self.world = build_world(
            &self.model,
            &self.settings,
            &self.gains,
            state,
            &self.payloads,
        );
        self.external.clear();
        self.applied_torque_nm.fill(0.0);
        self.time_s = 0.0;
    }

    fn set_gains(&mut self, gains: &PdGains) {
        let n = self.model.n_joints();
        assert!(gains.kp.len() == n && gains.kd.len() == n && gains.effort_limit_nm.len() == n);
        self.gains = gains.clone();
        let hybrid = self.settings.pd_form == PdForm::Hybrid;
        let links = self.world.links.clone();
        let mb = self
            .world
            .world
            .multibody_joints
            .get_multibody_mut(self.world.multibody)
            .expect("robot multibody");
        for (j, &(_, dof)) in links.iter().enumerate() {
            mb.damping_mut()[dof] = if hybrid { gains.kd[j] as f32 } else { 0.0 };
        }
    }

    fn set_targets(&mut self, q_target: &[f64]) {
        assert_eq!(q_target.len(), self.targets.len(), "target length");
        self.targets.copy_from_slice(q_target);
    }

    fn set_feedforward(&mut self, torque_nm: &[f64]) {
        assert_eq!(
            torque_nm.len(),
            self.feedforward_nm.len(),
            "feed-forward length"
        );
        self.feedforward_nm.copy_from_slice(torque_nm);
    }

    fn set_external_force(&mut self, force: ExternalForce) {
        assert!(force.body < self.model.bodies.len(), "body index");
        ExternalForce::hold(&mut self.external, force);
    }

    fn clear_external_forces(&mut self) {
        self.external.clear();
    }

    fn set_payloads(&mut self, payloads: &[PointMass]) {
        PointMass::check_bodies(payloads, self.model.bodies.len());
        self.payloads = payloads.to_vec();
    }

    fn step(&mut self) {
        let World {
            world,
            bodies,
            multibody,
            links,
            root_com_b,
            ..
        } = &mut self.world;
        // User forces and torques persist across rapier steps: clear them every step.
        for &h in bodies.iter() {
            let rb = &mut world.bodies[h];
            rb.reset_forces(false);
            rb.reset_torques(false);
        }
        let mb = world
            .multibody_joints
            .get_multibody(*multibody)
            .expect("robot multibody");
        let gv = mb.generalized_velocity();
        for (j, joint) in self.model.joints.iter().enumerate() {
            let (link_id, dof) = links[j];
            let q = mb.link(link_id).expect("link").joint().coords()[3] as f64;
            let (tau, reported) = self.gains.torque_nm(
                self.settings.pd_form,
                j,
                (self.targets[j], self.feedforward_nm[j]),
                q,
                gv[dof] as f64,
            );
            self.applied_torque_nm[j] = reported;
            if tau == 0.0 {
                continue;
            }
            let child = bodies[joint.body];
            let parent = bodies[self.model.bodies[joint.body]
                .parent
                .expect("jointed body has a parent")];
            let axis_w = *world.bodies[child].rotation()
                * vec_to_rapier(&self.model.bodies[joint.body].axis);
            let torque = axis_w * tau as f32;
            world.bodies[child].add_torque(torque, false);
            world.bodies[parent].add_torque(-torque, false);
        }
        for f in &self.external {
            let rb = &mut world.bodies[bodies[f.body]];
            let body_frame = if f.body == 0 {
                Isometry3::from_parts(Translation3::from(-*root_com_b), UnitQuaternion::identity())
            } else {
                Isometry3::identity()
            };
            let point_w = pose_from_rapier(rb.position()) * body_frame * f.point_b;
            rb.add_force_at_point(vec_to_rapier(&f.force_w), point_to_rapier(&point_w), false);
        }
        world.step();
        self.time_s += self.settings.dt_s;
    }

    fn read_state(&self, out: &mut PhysicsState) {
        out.time_s = self.time_s;
        out.root = Some(self.root_state());
        let mb = self.multibody();
        let gv = mb.generalized_velocity();
        out.q.clear();
        out.qd.clear();
        for &(link_id, dof) in &self.world.links {
            out.q
                .push(mb.link(link_id).expect("link").joint().coords()[3] as f64);
            out.qd.push(gv[dof] as f64);
        }
        out.world_from_body.clear();
        for (i, &h) in self.world.bodies.iter().enumerate() {
            let pose = pose_from_rapier(self.world.world.bodies[h].position());
            out.world_from_body.push(if i == 0 {
                pose * Isometry3::from_parts(
                    Translation3::from(-self.world.root_com_b),
                    UnitQuaternion::identity(),
                )
            } else {
                pose
            });
        }
        out.applied_torque_nm.clone_from(&self.applied_torque_nm);
    }

    fn time_s(&self) -> f64 {
        self.time_s
    }

    fn contact_count(&self) -> usize {
        self.world
            .world
            .narrow_phase
            .contact_pairs()
            .flat_map(|p| p.manifolds().iter())
            .map(|m| m.points.iter().filter(|p| p.data.impulse != 0.0).count())
            .sum()
    }

    fn ground_contacts(&self, out: &mut Vec<GroundContact>) {
        out.clear();
        let w = &self.world;
        // Impulses over the step, divided by the step: the mean force of the step. Rapier
        // keeps the friction impulse in world axes for the last substep only: with N solver
        // iterations (substeps) the friction read here is 1/N of the step's; the benchmark
        // runs one.
        let inv_dt = 1.0 / self.settings.dt_s;
        for pair in w.world.contact_pairs_with(w.ground) {
            // The robot's side of the pair; the impulses are those on collider 1's body.
            let (robot, sign) = if pair.collider1 == w.ground {
                (pair.collider2, -1.0)
            } else {
                (pair.collider1, 1.0)
            };
            let Some(&(_, body, body_from_collider)) =
                w.robot_colliders.iter().find(|(c, _, _)| *c == robot)
            else {
                continue;
            };
            for manifold in pair.solver_manifolds() {
                for point in &manifold.points {
                    let normal_impulse = point.data.impulse as f64;
                    if normal_impulse <= 0.0 {
                        continue;
                    }
                    let local = if sign > 0.0 {
                        point.local_p1
                    } else {
                        point.local_p2
                    };
                    out.push(GroundContact {
                        body,
                        point_b: body_from_collider
                            * Point3::new(local.x as f64, local.y as f64, local.z as f64),
                        normal_n: normal_impulse * inv_dt,
                        friction_w: convert::vec_from_rapier(point.data.warmstart_tangent_world)
                            * (sign * inv_dt),
                    });
                }
            }
        }
    }
}
