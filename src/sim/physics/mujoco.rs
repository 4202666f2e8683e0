//! The MuJoCo backend (cargo feature `mujoco`; `mujoco-rs` 7.0.0 bound to MuJoCo 3.17.0):
//! the same robot behind the same [`Physics`] trait, on an MJCF of the robot — generated
//! from the robot model ([`super::mjcf_of`]), or a user's (`--mjcf`, e.g. TWIST2's
//! `g1_sim2sim_29dof.xml`) with joints and bodies matched to the robot model by name.
//!
//! The benchmark's PD law, as in rapier: `clamp(kp·(q* − q), ±effort)` as an explicit joint
//! torque (`qfrc_applied`) plus `kd` as joint damping (`dof_damping`, which MuJoCo's Euler
//! and implicit integrators integrate implicitly; the MJCF's own damping is replaced), or
//! the whole law explicit ([`PdForm::Explicit`]). The MJCF's actuators stay at zero
//! control; its contacts, friction, solver, armature and joint friction are its own. Hand
//! forces go through `xfrc_applied`, moved from the force point to the body's centre of
//! mass. Applied torques are reported from the law, the same way as rapier's.
//!
//! MuJoCo resets an unstable state by itself (`mjWARN_BADQACC`); the backend then reads the
//! state as not finite until the next reset, so the reset state never passes for physics
//! and the episode ends as `physics_diverged`. A user's MJCF is refused when a robot joint
//! is missing, is not a hinge, moves another body or turns about another axis; the library
//! loaded at run time must be `MUJOCO_VERSION`; the run names a user's MJCF by its SHA-256
//! (`Engine::mujoco_on`).

use super::payload::{Inertial, PointMass};
use super::settings::{PdForm, PhysicsSettings};
use super::state::{ExternalForce, GroundContact, PdGains, PhysicsState, ResetState, RootState};
use super::Physics;
use crate::sim::robot::RobotModel;
use mujoco_rs::prelude::*;
use nalgebra::{
    Isometry3, Matrix3, Point3, Quaternion, Rotation3, Translation3, UnitQuaternion, Vector3,
};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The MuJoCo version this build binds ([`mujoco_rs::mujoco_c::mjVERSION_HEADER`]).
pub const MUJOCO_VERSION: u32 = mujoco_rs::mujoco_c::mjVERSION_HEADER;

/// Why an MJCF cannot simulate the robot.
#[derive(Debug, thiserror::Error)]
pub enum MujocoError {
    /// The MuJoCo library loaded at run time is not the one this build binds.
    #[error("the MuJoCo library loaded is version {found}, this thorarena was built for {expected} (install the matching wheel: pip install mujoco=={expected_text})", expected_text = version_text(*expected))]
    Version {
        /// `mj_version()` of the library.
        found: i32,
        /// What the bindings expect.
        expected: u32,
    },
    /// MuJoCo could not load the file.
    #[error("loading the MJCF {path}: {message}")]
    Load {
        /// The MJCF.
        path: PathBuf,
        /// MuJoCo's message.
        message: String,
    },
    /// The MJCF does not describe the robot model.
    #[error("the MJCF {path} does not fit robot `{robot}`: {reason}")]
    Mismatch {
        /// The MJCF.
        path: PathBuf,
        /// The robot model.
        robot: String,
        /// What is missing or different.
        reason: String,
    },
}

fn version_text(v: u32) -> String {
    format!("{}.{}.{}", v / 1_000_000, (v / 1000) % 1000, v % 1000)
}

/// Where each of the robot's joints and bodies lives in the MuJoCo model.
struct Indices {
    /// Per robot joint: (qpos address, dof address).
    joints: Vec<(usize, usize)>,
    /// Per robot body: MuJoCo body id.
    bodies: Vec<usize>,
    /// qpos / dof address of the free joint of the root (None: fixed base).
    free: Option<(usize, usize)>,
    /// Per MuJoCo body id: the robot body it is, if any.
    robot_body_of: Vec<Option<usize>>,
}

/// The robot simulated by MuJoCo.
pub struct MujocoPhysics {
    model: Arc<RobotModel>,
    settings: PhysicsSettings,
    gains: PdGains,
    targets: Vec<f64>,
    /// Added to the PD torques before their clamp, N·m (`Physics::set_feedforward`).
    feedforward_nm: Vec<f64>,
    external: Vec<ExternalForce>,
    applied_torque_nm: Vec<f64>,
    /// The PD torques applied through `qfrc_applied` in the current step.
    explicit_torque_nm: Vec<f64>,
    data: MjData<Box<MjModel>>,
    idx: Indices,
    mjcf: PathBuf,
    /// MuJoCo met an unstable acceleration since the last reset ("Nan, Inf or huge value
    /// in QACC"): it then resets the state itself, which must not pass for physics — the
    /// state reads as not finite, so the episode ends as `physics_diverged`.
    unstable: bool,
    /// Point masses to fold into their bodies at the next reset (`Physics::set_payloads`),
    /// and whether the model's inertials must be rewritten for them.
    payloads: Vec<PointMass>,
    payloads_changed: bool,
    /// Every MuJoCo body's inertial as loaded (mass, `ipos`, `iquat`, diagonal inertia,
    /// `sameframe`), restored before payloads are folded in again.
    loaded_inertials: Vec<LoadedInertial>,
}

/// A MuJoCo body's inertial as the file gave it.
#[derive(Debug, Clone, Copy)]
struct LoadedInertial {
    mass: f64,
    ipos: [f64; 3],
    iquat: [f64; 4],
    inertia: [f64; 3],
    sameframe: MjtSameFrame,
}

// SAFETY: `MjData<Box<MjModel>>` owns both the model and the data, and is `Send` by the
// bindings' own bound; the rest are plain values.
const _: fn() = || {
    fn send<T: Send>() {}
    send::<MjData<Box<MjModel>>>();
};

impl MujocoPhysics {
    /// Loads `mjcf` for `robot` (`None`: the MJCF generated from the robot model): every
    /// robot joint must be a joint of the same name, every robot body a body of the same
    /// name, and the root body must carry a free joint; a fixed base (`settings.fixed_base`)
    /// is supported on the generated MJCF only, the root then welded where `reset` puts it.
    /// `settings.dt_s` and `settings.gravity` replace the file's.
    pub fn new(
        mjcf: Option<&Path>,
        model: Arc<RobotModel>,
        settings: PhysicsSettings,
        gains: PdGains,
    ) -> Result<Self, MujocoError> {
        check_library_version()?;
        let label = mjcf.map_or_else(
            || PathBuf::from(format!("<generated from {}>", model.name)),
            Path::to_path_buf,
        );
        let mismatch = |reason: String| MujocoError::Mismatch {
            path: label.clone(),
            robot: model.name.clone(),
            reason,
        };
        if settings.fixed_base && mjcf.is_some() {
            return Err(mismatch(
                "a fixed base is supported on the generated MJCF only".into(),
            ));
        }
        let loaded = match mjcf {
            Some(path) => MjModel::from_xml(path),
            None => MjModel::from_xml_string(&super::mjcf_of(&model, &settings)),
        };
        let mut mj = loaded.map_err(|e| MujocoError::Load {
            path: label.clone(),
            message: format!("{e:?}"),
        })?;
        let idx = Indices::find(&mj, &model, settings.fixed_base).map_err(mismatch)?;
        {
            let opt = mj.opt_mut();
            opt.timestep = settings.dt_s;
            opt.gravity = settings.gravity;
        }
        let n = model.n_joints();
        let loaded_inertials = (0..mj.body_mass().len())
            .map(|b| LoadedInertial {
                mass: mj.body_mass()[b],
                ipos: mj.body_ipos()[b],
                iquat: mj.body_iquat()[b],
                inertia: mj.body_inertia()[b],
                sameframe: mj.body_sameframe()[b],
            })
            .collect();
        let data = MjData::new(Box::new(mj));
        let mut physics = Self {
            targets: model.default_pose(),
            feedforward_nm: vec![0.0; n],
            applied_torque_nm: vec![0.0; n],
            explicit_torque_nm: vec![0.0; n],
            external: Vec::new(),
            model,
            settings,
            gains: gains.clone(),
            data,
            idx,
            mjcf: label,
            unstable: false,
            payloads: Vec::new(),
            payloads_changed: false,
            loaded_inertials,
        };
        physics.set_gains(&gains);
        let state = super::rapier::standing_default_pose(&physics.model);
        physics.reset(&state);
        Ok(physics)
    }

    /// Rewrites the inertials of the bodies holding payloads (every other body back to its
    /// loaded inertial), then MuJoCo's derived constants (`mj_setConst`: subtree masses,
    /// inverse weights) for them. A body's loaded inertial is read from the model (a user's
    /// MJCF may differ from the robot model); the combined inertia is diagonalized again,
    /// as MuJoCo keeps a principal frame (`iquat`) and diagonal (`inertia`).
    fn fold_in_payloads(&mut self) {
        // SAFETY: only inertial values change, no size or structure of the model; the data
        // is reset right after (`reset`), and `mj_setConst` recomputes what derives from them.
        let mj = unsafe { self.data.model_mut() };
        for (b, l) in self.loaded_inertials.iter().enumerate() {
            mj.body_mass_mut()[b] = l.mass;
            mj.body_ipos_mut()[b] = l.ipos;
            mj.body_iquat_mut()[b] = l.iquat;
            mj.body_inertia_mut()[b] = l.inertia;
            mj.body_sameframe_mut()[b] = l.sameframe;
        }
        for (i, &b) in self.idx.bodies.iter().enumerate() {
            let held: Vec<&PointMass> = self.payloads.iter().filter(|p| p.body == i).collect();
            if held.is_empty() {
                continue;
            }
            let l = self.loaded_inertials[b];
            let q = UnitQuaternion::from_quaternion(Quaternion::new(
                l.iquat[0], l.iquat[1], l.iquat[2], l.iquat[3],
            ));
            let r = q.to_rotation_matrix();
            let own = Inertial {
                mass_kg: l.mass,
                com_b: Vector3::from(l.ipos),
                inertia_kgm2: r.matrix()
                    * Matrix3::from_diagonal(&Vector3::from(l.inertia))
                    * r.matrix().transpose(),
            };
            let loaded = own.with_point_masses(held);
            let eigen = loaded.inertia_kgm2.symmetric_eigen();
            let mut axes = eigen.eigenvectors;
            if axes.determinant() < 0.0 {
                axes.column_mut(2).neg_mut();
            }
            let principal =
                UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(axes));
            mj.body_mass_mut()[b] = loaded.mass_kg;
            mj.body_ipos_mut()[b] = loaded.com_b.into();
            mj.body_iquat_mut()[b] = [principal.w, principal.i, principal.j, principal.k];
            mj.body_inertia_mut()[b] = eigen.eigenvalues.into();
            mj.body_sameframe_mut()[b] = MjtSameFrame::mjSAMEFRAME_NONE;
        }
        self.data.set_const();
        self.payloads_changed = false;
    }

    /// The MJCF simulated (`<generated from …>` for the generated one).
    pub fn mjcf(&self) -> &Path {
        &self.mjcf
    }

    fn root_state(&self) -> RootState {
        let root = self.idx.bodies[0];
        let pose = body_pose(&self.data, root);
        match self.idx.free {
            None => RootState::at_rest(pose),
            Some((_, dof)) => {
                let v = self.data.qvel();
                // A free joint's velocity: linear in the world frame, angular in the body's.
                let lin = Vector3::new(v[dof], v[dof + 1], v[dof + 2]);
                let ang_b = Vector3::new(v[dof + 3], v[dof + 4], v[dof + 5]);
                RootState {
                    world_from_root: pose,
                    lin_vel_w: lin,
                    ang_vel_w: pose.rotation * ang_b,
                }
            }
        }
    }
}

/// The MuJoCo library loaded at run time must be the version the bindings were made for.
fn check_library_version() -> Result<(), MujocoError> {
    // SAFETY: a plain C call without arguments.
    let found = unsafe { mujoco_rs::mujoco_c::mj_version() };
    if found != MUJOCO_VERSION as i32 {
        return Err(MujocoError::Version {
            found,
            expected: MUJOCO_VERSION,
        });
    }
    Ok(())
}

impl Indices {
    /// Matches the robot model to the MuJoCo model `mj` by name; the error says what does
    /// not match. A free joint on the root is required unless `fixed_base`.
    fn find(mj: &MjModel, model: &RobotModel, fixed_base: bool) -> Result<Self, String> {
        let bodies = body_ids(mj, model)?;
        let joints = joint_addresses(mj, model, &bodies)?;
        let mut robot_body_of = vec![None; mj.ffi().nbody.max(0) as usize];
        for (i, &b) in bodies.iter().enumerate() {
            robot_body_of[b] = Some(i);
        }
        let free = if fixed_base {
            None
        } else {
            Some(free_joint_address(mj, model, bodies[0])?)
        };
        Ok(Self {
            joints,
            bodies,
            free,
            robot_body_of,
        })
    }
}

/// Per robot body, the MuJoCo body of the same name.
fn body_ids(mj: &MjModel, model: &RobotModel) -> Result<Vec<usize>, String> {
    let mut bodies = Vec::with_capacity(model.bodies.len());
    for b in &model.bodies {
        bodies.push(
            mj.name_to_id(MjtObjBase::mjOBJ_BODY, &b.name)
                .ok_or_else(|| format!("no body `{}`", b.name))?,
        );
    }
    Ok(bodies)
}

/// Per robot joint, its (qpos address, dof address): a hinge of the same name, on the body
/// of the same name (`bodies`: their MuJoCo ids), about the same axis (a ball or slide
/// joint of the right name was once scored). Every robot joint must move a robot body.
fn joint_addresses(
    mj: &MjModel,
    model: &RobotModel,
    bodies: &[usize],
) -> Result<Vec<(usize, usize)>, String> {
    let n = model.n_joints();
    let mut joints = vec![(0, 0); n];
    let mut found = vec![false; n];
    for (b, body) in model.bodies.iter().enumerate() {
        let Some(j) = body.joint else { continue };
        let name = &model.joints[j].name;
        let id = mj
            .name_to_id(MjtObjBase::mjOBJ_JOINT, name)
            .ok_or_else(|| format!("no joint `{name}`"))?;
        let kind = mj.jnt_type()[id];
        if kind != MjtJoint::mjJNT_HINGE {
            return Err(format!("joint `{name}` is a {kind:?} joint, not a hinge"));
        }
        if mj.jnt_bodyid()[id] as usize != bodies[b] {
            return Err(format!(
                "joint `{name}` moves another body than `{}`",
                body.name
            ));
        }
        let axis = nalgebra::Vector3::from(mj.jnt_axis()[id]);
        let want = body.axis.normalize();
        if axis.norm() < 1e-9 || axis.normalize().dot(&want) < 0.999 {
            return Err(format!(
                "joint `{name}` turns about ({:.3} {:.3} {:.3}) in its body's frame, the robot's about ({:.3} {:.3} {:.3})",
                axis.x, axis.y, axis.z, want.x, want.y, want.z
            ));
        }
        joints[j] = (mj.jnt_qposadr()[id] as usize, mj.jnt_dofadr()[id] as usize);
        found[j] = true;
    }
    if let Some(j) = found.iter().position(|f| !f) {
        return Err(format!(
            "joint `{}` moves no body of the robot model",
            model.joints[j].name
        ));
    }
    Ok(joints)
}

/// The (qpos address, dof address) of the free joint of the root body (MuJoCo id `root`).
fn free_joint_address(
    mj: &MjModel,
    model: &RobotModel,
    root: usize,
) -> Result<(usize, usize), String> {
    let jnt = mj.body_jntadr()[root];
    let is_free = jnt >= 0 && mj.jnt_type()[jnt as usize] == MjtJoint::mjJNT_FREE;
    if !is_free {
        return Err(format!(
            "the root body `{}` has no free joint",
            model.bodies[0].name
        ));
    }
    Ok((
        mj.jnt_qposadr()[jnt as usize] as usize,
        mj.jnt_dofadr()[jnt as usize] as usize,
    ))
}

fn body_pose(data: &MjData<Box<MjModel>>, body: usize) -> Isometry3<f64> {
    let p = data.xpos()[body];
    let q = data.xquat()[body];
    Isometry3::from_parts(
        Translation3::new(p[0], p[1], p[2]),
        UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3])),
    )
}

impl Physics for MujocoPhysics {
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
        if self.payloads_changed {
            self.fold_in_payloads();
        }
        // mj_resetData: nothing of the previous episode (warm starts, contacts) survives,
        // and its warning counters start from zero.
        self.data.reset();
        self.unstable = false;
        if self.idx.free.is_none() {
            // A fixed base: the root body is welded where the state puts it.
            let root = self.idx.bodies[0];
            let t = state.root.world_from_root.translation.vector;
            let r = state.root.world_from_root.rotation;
            // SAFETY: only the root body's offset values change, no size or structure.
            let mj = unsafe { self.data.model_mut() };
            mj.body_pos_mut()[root] = [t.x, t.y, t.z];
            mj.body_quat_mut()[root] = [r.w, r.i, r.j, r.k];
        }
        {
            let qpos = self.data.qpos_mut();
            for (j, &(adr, _)) in self.idx.joints.iter().enumerate() {
                qpos[adr] = state.q[j];
            }
            if let Some((adr, _)) = self.idx.free {
                let t = state.root.world_from_root.translation.vector;
                let r = state.root.world_from_root.rotation;
                qpos[adr..adr + 7].copy_from_slice(&[t.x, t.y, t.z, r.w, r.i, r.j, r.k]);
            }
        }
        {
            let qvel = self.data.qvel_mut();
            for (j, &(_, dof)) in self.idx.joints.iter().enumerate() {
                qvel[dof] = state.qd[j];
            }
            if let Some((_, dof)) = self.idx.free {
                let v = state.root.lin_vel_w;
                let w_b = state
                    .root
                    .world_from_root
                    .rotation
                    .inverse_transform_vector(&state.root.ang_vel_w);
                qvel[dof..dof + 6].copy_from_slice(&[v.x, v.y, v.z, w_b.x, w_b.y, w_b.z]);
            }
        }
        self.data.forward();
        self.external.clear();
        self.applied_torque_nm.fill(0.0);
    }

    fn set_gains(&mut self, gains: &PdGains) {
        let n = self.model.n_joints();
        assert!(gains.kp.len() == n && gains.kd.len() == n && gains.effort_limit_nm.len() == n);
        self.gains = gains.clone();
        let hybrid = self.settings.pd_form == PdForm::Hybrid;
        // SAFETY: only the damping values change, no size or structure of the model, so
        // the data allocated for it stays valid.
        let mj = unsafe { self.data.model_mut() };
        let damping = mj.dof_damping_mut();
        for (j, &(_, dof)) in self.idx.joints.iter().enumerate() {
            damping[dof] = if hybrid { gains.kd[j] } else { 0.0 };
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
        if self.payloads != payloads {
            self.payloads = payloads.to_vec();
            self.payloads_changed = true;
        }
    }

    fn step(&mut self) {
        // The PD torques first (reading the state), then written into `qfrc_applied`; the
        // reported torques' buffer holds them in between, so a step allocates nothing.
        {
            let (qpos, qvel) = (self.data.qpos(), self.data.qvel());
            for (j, &(a, d)) in self.idx.joints.iter().enumerate() {
                let (tau, reported) = self.gains.torque_nm(
                    self.settings.pd_form,
                    j,
                    (self.targets[j], self.feedforward_nm[j]),
                    qpos[a],
                    qvel[d],
                );
                self.applied_torque_nm[j] = reported;
                self.explicit_torque_nm[j] = tau;
            }
        }
        let qfrc = self.data.qfrc_applied_mut();
        qfrc.fill(0.0);
        for (&tau, &(_, dof)) in self.explicit_torque_nm.iter().zip(&self.idx.joints) {
            qfrc[dof] = tau;
        }
        let xfrc = self.data.xfrc_applied_mut();
        for row in xfrc.iter_mut() {
            *row = [0.0; 6];
        }
        // A force at a point of a body is that force at the body's centre of mass plus the
        // torque of the offset (poses and centres of mass are current: see below).
        for f in &self.external {
            let body = self.idx.bodies[f.body];
            let point_w: Point3<f64> = body_pose(&self.data, body) * f.point_b;
            let c = self.data.xipos()[body];
            let r = point_w.coords - Vector3::new(c[0], c[1], c[2]);
            let t = r.cross(&f.force_w);
            let w = [f.force_w.x, f.force_w.y, f.force_w.z, t.x, t.y, t.z];
            let row = &mut self.data.xfrc_applied_mut()[body];
            for k in 0..6 {
                row[k] += w[k];
            }
        }
        self.data.step();
        self.unstable |= self.data.ffi().warning[MjtWarning::mjWARN_BADQACC as usize].number > 0;
        // mj_step leaves body poses as they were before its integration: bring them (and
        // the centres of mass the hand forces act around) up to the new qpos.
        self.data.kinematics();
        self.data.com_pos();
    }

    fn read_state(&self, out: &mut PhysicsState) {
        out.time_s = self.data.ffi().time;
        out.root = Some(self.root_state());
        let (qpos, qvel) = (self.data.qpos(), self.data.qvel());
        out.q.clear();
        out.qd.clear();
        for &(a, d) in &self.idx.joints {
            out.q.push(qpos[a]);
            out.qd.push(qvel[d]);
        }
        out.world_from_body.clear();
        for &b in &self.idx.bodies {
            out.world_from_body.push(body_pose(&self.data, b));
        }
        out.applied_torque_nm.clone_from(&self.applied_torque_nm);
        if self.unstable {
            out.q.fill(f64::NAN);
        }
    }

    fn time_s(&self) -> f64 {
        self.data.ffi().time
    }

    fn contact_count(&self) -> usize {
        self.data.ffi().ncon.max(0) as usize
    }

    fn ground_contacts(&self, out: &mut Vec<GroundContact>) {
        out.clear();
        let geom_body = self.data.model().geom_bodyid();
        for (i, con) in self.data.contact().iter().enumerate() {
            // Robot against the world body (the ground); robot self-contacts are not ground.
            let side = |g: i32| -> Option<usize> {
                let b = *geom_body.get(usize::try_from(g).ok()?)?;
                *self.idx.robot_body_of.get(usize::try_from(b).ok()?)?
            };
            let world = |g: i32| usize::try_from(g).is_ok_and(|g| geom_body[g] == 0);
            let (body, sign) = match (side(con.geom[0]), side(con.geom[1])) {
                (None, Some(b)) if world(con.geom[0]) => (b, 1.0),
                (Some(b), None) if world(con.geom[1]) => (b, -1.0),
                _ => continue,
            };
            // The force of geom 1 on geom 2 in the contact frame (normal from 1 to 2, then
            // the two tangents), as the constraint solver found it in the last step.
            let f = self.data.contact_force(i);
            let frame = |k: usize| {
                Vector3::new(con.frame[3 * k], con.frame[3 * k + 1], con.frame[3 * k + 2])
            };
            let normal_n = f[0].abs();
            if normal_n <= 0.0 {
                continue;
            }
            let friction_w = (frame(1) * f[1] + frame(2) * f[2]) * sign;
            let pos = Point3::new(con.pos[0], con.pos[1], con.pos[2]);
            let world_from_body = body_pose(&self.data, self.idx.bodies[body]);
            out.push(GroundContact {
                body,
                point_b: world_from_body.inverse_transform_point(&pos),
                normal_n,
                friction_w,
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An absurd force makes MuJoCo's acceleration blow up; MuJoCo then resets the state
    /// itself (its "Nan, Inf or huge value in QACC" warning), which must read as diverged,
    /// not as a robot standing in its initial pose again. A reset clears it.
    #[test]
    fn an_unstable_step_reads_as_diverged_until_the_next_reset() {
        let g1 = Arc::new(crate::sim::robot::load_bundled("g1_29dof").unwrap());
        let gains = crate::sim::physics::standing_gains(&g1);
        let mut p =
            MujocoPhysics::new(None, g1.clone(), PhysicsSettings::default(), gains).unwrap();
        let mut state = PhysicsState::default();
        p.step();
        p.read_state(&mut state);
        assert!(state.q.iter().all(|q| q.is_finite()));
        p.set_external_force(ExternalForce {
            body: 0,
            force_w: Vector3::new(1e300, 0.0, 0.0),
            point_b: Point3::origin(),
        });
        p.step();
        p.read_state(&mut state);
        assert!(state.q.iter().any(|q| !q.is_finite()), "{:?}", state.q);
        p.reset(&crate::sim::physics::rapier::standing_default_pose(&g1));
        p.step();
        p.read_state(&mut state);
        assert!(state.q.iter().all(|q| q.is_finite()));
    }

    /// The generated MJCF, compiled by MuJoCo, is the robot model: every body's mass,
    /// centre of mass and principal moments of inertia, every joint's limits and armature.
    #[test]
    fn the_compiled_generated_mjcf_is_the_robot_model() {
        let g1 = crate::sim::robot::load_bundled("g1_29dof").unwrap();
        let settings = PhysicsSettings::default();
        let mj = MjModel::from_xml_string(&super::super::mjcf_of(&g1, &settings)).unwrap();
        for b in &g1.bodies {
            let id = mj.name_to_id(MjtObjBase::mjOBJ_BODY, &b.name).unwrap();
            assert!(
                (mj.body_mass()[id] - b.mass_kg).abs() < 1e-9,
                "{} mass",
                b.name
            );
            let c = mj.body_ipos()[id];
            let dc = (Vector3::new(c[0], c[1], c[2]) - b.com_b).norm();
            assert!(dc < 1e-9, "{} centre of mass off by {dc} m", b.name);
            let mut ours: Vec<f64> = b
                .inertia_kgm2
                .symmetric_eigenvalues()
                .iter()
                .copied()
                .collect();
            let mut theirs = mj.body_inertia()[id].to_vec();
            ours.sort_by(f64::total_cmp);
            theirs.sort_by(f64::total_cmp);
            for (a, t) in ours.iter().zip(&theirs) {
                assert!(
                    (a - t).abs() < 1e-9 + 1e-6 * a.abs(),
                    "{} inertia {ours:?} vs {theirs:?}",
                    b.name
                );
            }
        }
        for j in &g1.joints {
            let id = mj.name_to_id(MjtObjBase::mjOBJ_JOINT, &j.name).unwrap();
            assert_eq!(
                mj.jnt_range()[id],
                [j.lower_rad, j.upper_rad],
                "{} range",
                j.name
            );
            let dof = mj.jnt_dofadr()[id] as usize;
            assert_eq!(
                mj.dof_armature()[dof],
                j.armature_kgm2,
                "{} armature",
                j.name
            );
            assert_eq!(mj.dof_damping()[dof], 0.0, "{} damping", j.name);
        }
        let total: f64 = mj.body_mass().iter().sum();
        assert!((total - g1.total_mass_kg()).abs() < 1e-9);
    }
}
