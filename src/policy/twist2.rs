//! TWIST2 (Ze et al. 2025, github.com/amazon-far/TWIST2, MIT), the released whole-body
//! tracking policy, in process: its 1432-dim observation built from the benchmark signals
//! and the ONNX network run with tract.
//!
//! The observation is the one TWIST2's student policy was trained with (SOURCES.md, Policies, read
//! from `deploy_real/server_low_level_g1_sim.py`, `deploy_real/server_motion_lib.py` and
//! `g1_mimic_distill_config.py` of that repository):
//!
//! ```text
//! mimic(frame)  = [v_x, v_y (root linear velocity in the root frame), root height,
//!                  roll, pitch, yaw rate (root frame), joint_pos (29)]                 35
//! proprio       = [ω_base·0.25 (3), roll, pitch, q − q_default (29),
//!                  q̇·0.05 with the 4 ankle entries zeroed (29), last action (29)]      92
//! single        = mimic(reference at t + 0.02 s) ++ proprio                            127
//! observation   = single ++ 10 past singles (oldest first) ++ mimic(reference at t)   1432
//! ```
//!
//! clipped to ±100, float32. The history is zero before an episode's first step, filled
//! with the current `single` after steps 0 and 1 (as TWIST2's training environment refills
//! it after a reset), then shifted. The action is the raw network output; the `twist2`
//! profile clips it to ±10 and scales it by 0.5 around the default pose. The Python adapter
//! (`adapters/python/thorarena/adapters/twist2.py`) builds the same vector and is tested
//! against this one.

use super::batch_plans::BatchPlans;
use super::{ActOutcome, Observation, Policy};
use crate::sim::motion::ReferenceFrame;
use nalgebra::UnitQuaternion;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use tract_onnx::prelude::*;

/// Length of `mimic(frame)`.
pub const MIMIC_LEN: usize = 35;
/// Length of one observation frame (`mimic ++ proprio`).
pub const SINGLE_LEN: usize = 127;
/// Past frames in the observation.
pub const HISTORY_LEN: usize = 10;
/// Length of the whole observation.
pub const OBS_LEN: usize = SINGLE_LEN * (HISTORY_LEN + 1) + MIMIC_LEN;
/// Joints of the G1 the network was trained on.
pub const N_JOINTS: usize = 29;
/// The mimic frame is the reference one 50 Hz step ahead.
pub const MIMIC_LOOKAHEAD_S: f64 = 0.02;
/// Rows of every tract call [`Twist2Policy`]'s `act` makes, padded with zeros when fewer
/// environments observe. One call shape for every call keeps an environment's action
/// independent of how many others share its call: tract's kernels for other row counts
/// round differently (about 1e-6 against batch one, `tests/batched_inference.rs`), which
/// would make records depend on `--envs`. Batches of 4 cost 0.59× batch one per
/// environment (`thorarena bench inference`), but that rounding difference alone moves
/// TWIST2's tracking of the released walks in MuJoCo by up to 8 % (walk_002: 33.5 mm
/// against 31.1 mm in TWIST2's own harness, outside the 5 % `tests/mujoco_engine.rs`
/// holds it to) and its 30 N survival by 0.08 — so the published figures keep batch one.
pub const INFERENCE_BATCH: usize = 1;
/// Ankle joints (canonical indices) whose velocities the observation hides.
const ANKLES: [usize; 4] = [4, 5, 10, 11];

/// Why the policy could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum Twist2Error {
    /// tract could not load or prepare the network.
    #[error("loading the TWIST2 network {path}: {message}")]
    Load {
        /// The ONNX file.
        path: PathBuf,
        /// tract's message.
        message: String,
    },
    /// The robot or profile is not the one the network was trained for.
    #[error("TWIST2 needs the 29-joint G1 (got {0} joints)")]
    Joints(usize),
}

/// Roll and pitch of a rotation (x-y-z convention, as TWIST2 computes them).
fn roll_pitch(q: &UnitQuaternion<f64>) -> (f64, f64) {
    let (w, x, y, z) = (q.w, q.i, q.j, q.k);
    let roll = (2.0 * (w * x + y * z)).atan2(1.0 - 2.0 * (x * x + y * y));
    let pitch = (2.0 * (w * y - z * x)).clamp(-1.0, 1.0).asin();
    (roll, pitch)
}

/// `mimic(frame)`: what TWIST2 sees of one reference frame, appended to `out`.
pub fn mimic(frame: &ReferenceFrame, out: &mut Vec<f64>) {
    let start = out.len();
    out.resize(start + MIMIC_LEN, 0.0);
    mimic_into(frame, &mut out[start..]);
}

/// `mimic(frame)` into `out` ([`MIMIC_LEN`] values).
fn mimic_into(frame: &ReferenceFrame, out: &mut [f64]) {
    let r = &frame.world_from_root.rotation;
    let v = r.inverse_transform_vector(&frame.root_lin_vel_w);
    let w = r.inverse_transform_vector(&frame.root_ang_vel_w);
    let (roll, pitch) = roll_pitch(r);
    let (head, joints) = out.split_at_mut(6);
    head.copy_from_slice(&[
        v.x,
        v.y,
        frame.world_from_root.translation.z,
        roll,
        pitch,
        w.z,
    ]);
    joints.copy_from_slice(&frame.joint_pos);
}

/// The current frame `mimic(reference at t + 0.02 s) ++ proprio` of one environment.
/// `reference[1]` must be the frame at t + 0.02 s ([`Twist2Policy::reference_offsets_s`]).
pub fn single_frame(obs: &Observation, default_pose: &[f64]) -> Vec<f64> {
    let mut s = [0.0; SINGLE_LEN];
    single_frame_into(obs, default_pose, &mut s);
    s.to_vec()
}

/// [`single_frame`] into `s`, without allocating (the simulator builds 64 of them per
/// step on a policy process's critical path).
fn single_frame_into(obs: &Observation, default_pose: &[f64], s: &mut [f64; SINGLE_LEN]) {
    let (mimic, proprio) = s.split_at_mut(MIMIC_LEN);
    mimic_into(&obs.reference[1], mimic);
    let w = obs.root.ang_vel_b();
    let (roll, pitch) = roll_pitch(&obs.root.world_from_root.rotation);
    proprio[..5].copy_from_slice(&[0.25 * w.x, 0.25 * w.y, 0.25 * w.z, roll, pitch]);
    let (q, rest) = proprio[5..].split_at_mut(N_JOINTS);
    let (qd, last_action) = rest.split_at_mut(N_JOINTS);
    for ((out, q), d) in q.iter_mut().zip(&obs.q).zip(default_pose) {
        *out = q - d;
    }
    for (out, qd) in qd.iter_mut().zip(&obs.qd) {
        *out = 0.05 * qd;
    }
    for j in ANKLES {
        qd[j] = 0.0;
    }
    last_action.copy_from_slice(&obs.last_action);
}

/// One environment's past frames.
#[derive(Debug, Clone)]
pub struct History {
    frames: Vec<Vec<f64>>,
}

impl Default for History {
    fn default() -> Self {
        Self {
            frames: vec![vec![0.0; SINGLE_LEN]; HISTORY_LEN],
        }
    }
}

impl History {
    /// After building step `step`'s observation: refill on steps 0 and 1, else shift.
    pub fn push(&mut self, single: &[f64], step: usize) {
        if step <= 1 {
            self.frames
                .iter_mut()
                .for_each(|f| f.copy_from_slice(single));
        } else {
            self.frames.rotate_left(1);
            self.frames[HISTORY_LEN - 1].copy_from_slice(single);
        }
    }
}

/// The whole observation of one environment; updates its history.
pub fn observation(obs: &Observation, default_pose: &[f64], history: &mut History) -> Vec<f32> {
    let mut out = vec![0.0; OBS_LEN];
    observation_into(obs, default_pose, history, &mut out);
    out
}

/// [`observation`] written into `out` (its [`OBS_LEN`] values), each term computed in
/// `f64` and rounded once; the simulator builds a policy process's input with it, straight
/// into shared memory.
pub fn observation_into(
    obs: &Observation,
    default_pose: &[f64],
    history: &mut History,
    out: &mut [f32],
) {
    observation_onto(obs, default_pose, history, out, false);
}

/// [`observation_into`], onto a row whose history rows may already hold `history`
/// (`history_written`: [`history_into`] wrote them since `history`'s last push). Then only
/// the current and the future frame are written — a fifth of the row — unless the episode
/// starts (step 0), whose history is zeros. The result is [`observation_into`]'s, bit for
/// bit.
pub fn observation_onto(
    obs: &Observation,
    default_pose: &[f64],
    history: &mut History,
    out: &mut [f32],
    history_written: bool,
) {
    let starts = obs.step == 0;
    if starts {
        history.frames.iter_mut().for_each(|f| f.fill(0.0));
    }
    let mut single = [0.0; SINGLE_LEN];
    single_frame_into(obs, default_pose, &mut single);
    let mut future = [0.0; MIMIC_LEN];
    mimic_into(&obs.reference[0], &mut future);
    // Slice by slice: a chained iterator over the segments would not vectorise, and costs
    // several times the arithmetic.
    clip_into(&single, &mut out[..SINGLE_LEN]);
    if starts || !history_written {
        history_into(history, out);
    }
    clip_into(&future, &mut out[SINGLE_LEN * (HISTORY_LEN + 1)..]);
    history.push(&single, obs.step);
}

/// The history rows of observation row `out` ([`OBS_LEN`] values) from `history`: what
/// the environment's next observation holds there, unless its episode starts anew. The
/// simulator writes them while the policy process computes the current step.
pub fn history_into(history: &History, out: &mut [f32]) {
    let past = &mut out[SINGLE_LEN..SINGLE_LEN * (HISTORY_LEN + 1)];
    for (frame, row) in history.frames.iter().zip(past.chunks_exact_mut(SINGLE_LEN)) {
        clip_into(frame, row);
    }
}

/// `out = clamp(values, ±100)` rounded to `f32`, element by element.
fn clip_into(values: &[f64], out: &mut [f32]) {
    for (o, v) in out.iter_mut().zip(values) {
        *o = v.clamp(-100.0, 100.0) as f32;
    }
}

/// TWIST2 in process: `--policy twist2:PATH.onnx` with `--profile twist2`.
pub struct Twist2Policy {
    plans: BatchPlans,
    /// The plan of `act`'s call shape ([`INFERENCE_BATCH`] rows), taken once.
    act_plan: Arc<TypedRunnableModel>,
    /// The file loaded, by content (`run.json`'s network).
    network: super::network_file::NetworkFile,
    default_pose: Vec<f64>,
    histories: Vec<History>,
    last_inputs: Vec<Vec<f32>>,
    /// The batch's inputs, row-major (kept between steps).
    batch_input: Vec<f32>,
}

impl Twist2Policy {
    /// Loads the network (input `[N, 1432]` float32, output `[N, 29]`); `default_pose` is
    /// the profile's action offset (TWIST2's default joint angles).
    pub fn load(path: &Path, default_pose: Vec<f64>) -> Result<Self, Twist2Error> {
        if default_pose.len() != N_JOINTS {
            return Err(Twist2Error::Joints(default_pose.len()));
        }
        let load = || -> TractResult<(BatchPlans, Arc<TypedRunnableModel>, _)> {
            let (model, network) = super::network_kernels::load_onnx(path)?;
            let plans = BatchPlans::new(model, OBS_LEN, Some(N_JOINTS))?;
            let act_plan = plans.plan(INFERENCE_BATCH)?;
            Ok((plans, act_plan, network))
        };
        let (plans, act_plan, network) = load().map_err(|e| Twist2Error::Load {
            path: path.to_path_buf(),
            message: crate::files::log_text::causes_once(e.as_ref()),
        })?;
        Ok(Self {
            plans,
            act_plan,
            network,
            default_pose,
            histories: Vec::new(),
            last_inputs: Vec::new(),
            batch_input: Vec::new(),
        })
    }

    /// The network's inputs of the last `act`, one per observation (for cross-checks).
    pub fn last_inputs(&self) -> &[Vec<f32>] {
        &self.last_inputs
    }

    /// Runs the network on one observation vector.
    pub fn infer(&self, input: &[f32]) -> TractResult<Vec<f32>> {
        self.plans.run(input, 1)
    }

    /// Runs the network on `batch` observation vectors at once (row-major), returning
    /// `batch` actions of [`N_JOINTS`], row-major.
    pub fn infer_batch(&self, inputs: &[f32], batch: usize) -> TractResult<Vec<f32>> {
        self.plans.run(inputs, batch)
    }
}

impl Policy for Twist2Policy {
    fn name(&self) -> &str {
        "twist2"
    }

    fn network(&self) -> Option<&crate::policy::network_file::NetworkFile> {
        Some(&self.network)
    }

    fn network_kernels(&self) -> Option<&'static super::network_kernels::NetworkKernels> {
        Some(super::network_kernels::network_kernels())
    }

    fn reference_offsets_s(&self) -> Vec<f64> {
        vec![0.0, MIMIC_LOOKAHEAD_S]
    }

    fn sanity_exempt(&self) -> Option<&'static str> {
        None
    }

    fn wiring(&self) -> super::Wiring {
        super::Wiring {
            facts: vec![
                format!("{OBS_LEN} inputs: TWIST2's layout (proprioception with {HISTORY_LEN} past frames, mimic frames at t and t + {MIMIC_LOOKAHEAD_S} s)"),
                format!("{N_JOINTS} actions, relative to the default pose"),
            ],
            disagreements: Vec::new(),
        }
    }

    fn worker_copies(&self, n: usize) -> Option<Vec<Box<dyn Policy + Send>>> {
        Some(
            (0..n)
                .map(|_| {
                    Box::new(Self {
                        plans: self.plans.clone(),
                        act_plan: self.act_plan.clone(),
                        network: self.network.clone(),
                        default_pose: self.default_pose.clone(),
                        histories: Vec::new(),
                        last_inputs: Vec::new(),
                        batch_input: Vec::new(),
                    }) as Box<dyn Policy + Send>
                })
                .collect(),
        )
    }

    fn act(&mut self, observations: &[Observation], actions: &mut [Vec<f64>]) -> ActOutcome {
        self.last_inputs.clear();
        self.batch_input.clear();
        for obs in observations {
            if self.histories.len() <= obs.env {
                self.histories.resize_with(obs.env + 1, History::default);
            }
            let input = observation(obs, &self.default_pose, &mut self.histories[obs.env]);
            self.batch_input.extend_from_slice(&input);
            self.last_inputs.push(input);
        }
        let rows = observations.len().div_ceil(INFERENCE_BATCH) * INFERENCE_BATCH;
        self.batch_input.resize(rows * OBS_LEN, 0.0);
        for (call, acts) in actions[..observations.len()]
            .chunks_mut(INFERENCE_BATCH)
            .enumerate()
        {
            let rows =
                &self.batch_input[call * INFERENCE_BATCH * OBS_LEN..][..INFERENCE_BATCH * OBS_LEN];
            match self.plans.run_on(&self.act_plan, rows, INFERENCE_BATCH) {
                Ok(out) => {
                    for (action, row) in acts.iter_mut().zip(out.chunks_exact(N_JOINTS)) {
                        for (a, o) in action.iter_mut().zip(row) {
                            *a = f64::from(*o);
                        }
                    }
                }
                // A network that fails at run time answers NaN: the runner's miss rule
                // keeps it away from the physics and counts it.
                Err(e) => {
                    log::warn!(
                        "twist2: inference failed: {}",
                        crate::files::log_text::causes_once(e.as_ref())
                    );
                    acts.iter_mut().for_each(|a| a.fill(f64::NAN));
                }
            }
        }
        ActOutcome::Acted
    }
}
