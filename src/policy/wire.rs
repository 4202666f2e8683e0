//! [`Observation`] to and from the wire's environment block (`thorarena-ipc`), the one
//! place where the core's types meet the protocol's. Both directions copy `f64`s
//! unchanged, so a policy that rebuilds an `Observation` from the wire sees exactly what an
//! in-process policy sees (bit for bit) — which is what lets the tests compare them.

use super::Observation;
use crate::sim::motion::ReferenceFrame;
use crate::sim::physics::RootState;
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3};
use thorarena_ipc::{
    ActionBatchMut, EnvHeader, EnvObs, EnvObsMut, ObsBatch, FLAG_ACTIVE, FLAG_RESET,
};

fn put3(dst: &mut [f64], v: &Vector3<f64>) {
    dst.copy_from_slice(&[v.x, v.y, v.z]);
}

fn put_quat(dst: &mut [f64], q: &UnitQuaternion<f64>) {
    dst.copy_from_slice(&[q.w, q.i, q.j, q.k]);
}

fn vec3(s: &[f64]) -> Vector3<f64> {
    Vector3::new(s[0], s[1], s[2])
}

fn pose(pos: &[f64], quat_wxyz: &[f64]) -> Isometry3<f64> {
    // The quaternion was written from a unit quaternion: taking it unchecked keeps every
    // bit (normalising again could change the last one).
    let q = Quaternion::new(quat_wxyz[0], quat_wxyz[1], quat_wxyz[2], quat_wxyz[3]);
    Isometry3::from_parts(
        Translation3::new(pos[0], pos[1], pos[2]),
        UnitQuaternion::new_unchecked(q),
    )
}

/// Writes one environment's observation into its block. `reference_offsets_s` are the
/// offsets its reference frames were sampled at (each frame's `time_s` is the episode time
/// it shows); `extra_flags` adds [`thorarena_ipc::FLAG_PREVIOUS_TERMINATED`] and the like.
pub fn write_observation(
    obs: &Observation,
    reference_offsets_s: &[f64],
    env: &mut EnvObsMut,
    extra_flags: u32,
) {
    let reset = if obs.step == 0 { FLAG_RESET } else { 0 };
    env.set_header(&EnvHeader {
        episode_id: obs.episode_id,
        step: obs.step as u64,
        flags: FLAG_ACTIVE | reset | extra_flags,
        reserved: 0,
        time_s: obs.time_s,
    });
    let root = &obs.root;
    put3(
        env.array("root_pos_w"),
        &root.world_from_root.translation.vector,
    );
    put_quat(env.array("root_quat_wxyz"), &root.world_from_root.rotation);
    put3(env.array("root_lin_vel_w"), &root.lin_vel_w);
    put3(env.array("root_ang_vel_w"), &root.ang_vel_w);
    put3(env.array("root_lin_vel_b"), &root.lin_vel_b());
    put3(env.array("root_ang_vel_b"), &root.ang_vel_b());
    put3(
        env.array("projected_gravity_b"),
        &root.projected_gravity_b(),
    );
    env.array("q").copy_from_slice(&obs.q);
    env.array("qd").copy_from_slice(&obs.qd);
    env.array("last_action").copy_from_slice(&obs.last_action);
    for (i, frame) in obs.reference.iter().enumerate() {
        env.reference(i, "time_s")[0] = obs.time_s + reference_offsets_s[i];
        put3(
            env.reference(i, "root_pos_w"),
            &frame.world_from_root.translation.vector,
        );
        put_quat(
            env.reference(i, "root_quat_wxyz"),
            &frame.world_from_root.rotation,
        );
        put3(env.reference(i, "root_lin_vel_w"), &frame.root_lin_vel_w);
        put3(env.reference(i, "root_ang_vel_w"), &frame.root_ang_vel_w);
        env.reference(i, "joint_pos")
            .copy_from_slice(&frame.joint_pos);
        env.reference(i, "joint_vel")
            .copy_from_slice(&frame.joint_vel);
    }
}

/// Rebuilds the observation of slot `env` from its block (reference hand forces are not on
/// the wire: policies do not see the forces they are about to feel).
pub fn read_observation(env_index: usize, env: &EnvObs, n_refs: usize) -> Observation {
    let h = env.header();
    let root = RootState {
        world_from_root: pose(env.array("root_pos_w"), env.array("root_quat_wxyz")),
        lin_vel_w: vec3(env.array("root_lin_vel_w")),
        ang_vel_w: vec3(env.array("root_ang_vel_w")),
    };
    let reference = (0..n_refs)
        .map(|i| ReferenceFrame {
            world_from_root: pose(
                env.reference(i, "root_pos_w"),
                env.reference(i, "root_quat_wxyz"),
            ),
            root_lin_vel_w: vec3(env.reference(i, "root_lin_vel_w")),
            root_ang_vel_w: vec3(env.reference(i, "root_ang_vel_w")),
            joint_pos: env.reference(i, "joint_pos").to_vec(),
            joint_vel: env.reference(i, "joint_vel").to_vec(),
            force_sensor: [Vector3::zeros(); 2],
        })
        .collect();
    Observation {
        env: env_index,
        episode_id: h.episode_id,
        step: h.step as usize,
        time_s: h.time_s,
        root,
        q: env.array("q").to_vec(),
        qd: env.array("qd").to_vec(),
        last_action: env.array("last_action").to_vec(),
        reference,
    }
}

/// Answers observation batches from the wire with an in-process batched policy: each
/// active environment's [`Observation`] is rebuilt (bit for bit what the simulator
/// observed), the policy is reset for an environment whose episode starts, and its
/// actions are written into the environment's slot. Inactive slots are left alone.
#[derive(Default)]
pub struct WireAnswer {
    observations: Vec<Observation>,
    actions: Vec<Vec<f64>>,
}

impl WireAnswer {
    /// Answers `obs` (with `n_refs` reference frames per environment) into `out`.
    pub fn answer(
        &mut self,
        policy: &mut dyn super::Policy,
        obs: &ObsBatch,
        out: &mut ActionBatchMut,
        n_refs: usize,
    ) {
        let n_joints = obs.env(0).array("q").len();
        self.observations.clear();
        self.observations.extend(
            (0..obs.n_envs())
                .filter(|&i| obs.env(i).is_active())
                .map(|i| read_observation(i, &obs.env(i), n_refs)),
        );
        for o in self.observations.iter().filter(|o| o.step == 0) {
            policy.reset(o.env);
        }
        let n = self.observations.len();
        self.actions.resize_with(n, || vec![0.0; n_joints]);
        policy.act(&self.observations, &mut self.actions[..n]);
        for (o, a) in self.observations.iter().zip(&self.actions) {
            out.env(o.env).copy_from_slice(a);
        }
    }
}
