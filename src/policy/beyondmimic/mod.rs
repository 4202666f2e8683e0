//! The BeyondMimic family of whole-body tracking policies in process: `--policy
//! beyondmimic:FILE.onnx` runs an exported network (mjlab, whole_body_tracking, holosoma)
//! on tract, no Python.
//!
//! Everything policy-specific comes from the file where it says it, else from the profile
//! (`[beyondmimic]` and the action mapping): joint order (`joint_names` / `dof_names`,
//! mapped to the robot's by name; a bare export's order from the profile's
//! `[beyondmimic] joint_names`), default pose and action scale, observation terms
//! (`observation_names`; else the profile's; else the known layout whose width is the
//! network's input), anchor body. Gains are the profile's (the simulator applies them);
//! where the file's kp, kd, default pose or action scale differ from the profile's, the
//! difference is reported ([`BeyondMimicPolicy::disagreements`], and logged). A network
//! with a `time_step` input is fed the episode's control step.
//!
//! Actions: the policy means `target = base + scale · a` with its own numbers, where the
//! base is its default pose (`default_relative`, mjlab's and holosoma's exports) or the
//! reference's joint positions at that step (`reference_residual`, wbc-mjlab's general
//! tracker; the file's `action_mode`, else the profile's). The raw action handed to the
//! profile is the one giving exactly that target under the profile's mapping (the same
//! when they agree), and the `actions` term inverts the same mapping on the last action
//! that reached the robot (a residual policy asks for the previous step's reference
//! frame too, to subtract the base that action was added to). The Python adapter
//! (`adapters/python/thorarena/adapters/beyondmimic.py`) does the same and is tested
//! against this one.

mod load;
mod observation;

pub use crate::policy::onnx_export::FileMetadata;
pub use observation::{
    build_observation, layout_width, reference_anchor_in_robot_anchor, ObservationSpec,
    ReferenceAnchor, Scratch, Term, KNOWN_LAYOUTS, LAYOUT_132_WBC, LAYOUT_154, LAYOUT_154_MJLAB,
    LAYOUT_160,
};

use super::{ActOutcome, Observation, Policy, Wiring};
use crate::sim::motion::ReferenceFrame;
use crate::sim::profile::ActionMode;
use crate::sim::robot::RobotModel;
use std::path::PathBuf;
use std::sync::Arc;
use tract_onnx::prelude::*;

/// Why a BeyondMimic network could not be used.
#[derive(Debug, thiserror::Error)]
pub enum BeyondMimicError {
    /// tract could not load or prepare the network.
    #[error("loading the network {path}: {message}")]
    Load {
        /// The ONNX file.
        path: PathBuf,
        /// tract's message.
        message: String,
    },
    /// The file and the profile cannot describe a policy the benchmark can run.
    #[error("{path}: {reason}")]
    Unusable {
        /// The ONNX file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
}

/// Who named a network's joint order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum JointOrderFrom {
    /// The file's `joint_names` (or `dof_names`) metadata.
    File,
    /// The profile's `[beyondmimic] joint_names`.
    Profile,
    /// Neither: the robot's own order is assumed (shown by `policy check`).
    Robot,
}

impl JointOrderFrom {
    /// How `policy check` and errors name it.
    pub fn name(self) -> &'static str {
        match self {
            Self::File => "the file",
            Self::Profile => "the profile",
            Self::Robot => "the robot",
        }
    }
}

/// Rows of every network call: a worker's environments go through the network this many
/// at a time, the last call zero-padded, so an environment's action never depends on how
/// many others share its call (records are the same for any `--envs` and `--workers`;
/// `tests/batched_inference.rs`). Eight: wbc-mjlab's tracker costs 167 µs per call of one
/// row and 30 µs per row in calls of eight (`thorarena bench inference`), which takes a
/// rapier run from 1.21 to 1.08 of its physics floor (docs/performance.md, "Measured"). Any count from
/// 2 to 16 gives the same records here (tract runs one kernel for all of them); one row
/// runs another and rounds differently (~1e-6). That rounding once looked like a cost:
/// holosoma's FastSAC dance on MuJoCo dances all 135 s at one row and falls at 29.6 s at
/// more. It is the dance, not the call shape: with its first input nudged by 1e-6 to
/// 2e-5, 2 of 24 runs fall there, one at one row and one at four. A network whose graph
/// plans for one row only runs one row per call whatever this is.
pub const INFERENCE_BATCH: usize = 8;

/// A loaded BeyondMimic-style network and how to talk to it.
pub struct BeyondMimicPolicy {
    /// The name results carry (the family's).
    name: String,
    plan: Arc<TypedRunnableModel>,
    /// The file loaded, by content (`run.json`'s network).
    network: crate::policy::network_file::NetworkFile,
    /// Rows of each call to `plan` ([`INFERENCE_BATCH`], or 1 for a network planned for
    /// one row only).
    call_rows: usize,
    robot: Arc<RobotModel>,
    spec: ObservationSpec,
    obs_width: usize,
    /// Input slot of `time_step`, if the network has one.
    time_step_input: Option<usize>,
    /// Output slot of `actions`.
    actions_output: usize,
    /// The policy's action scale, policy order.
    action_scale: Vec<f64>,
    /// What its actions are added to.
    action_mode: ActionMode,
    /// The control step, s (a residual policy's previous reference frame is this far back).
    control_dt_s: f64,
    /// The profile's action offset and scale, canonical order.
    profile_offset: Vec<f64>,
    profile_scale: Vec<f64>,
    disagreements: Vec<String>,
    /// Who named the joint order.
    joint_order_from: JointOrderFrom,
    scratch: Scratch,
    input: Vec<f32>,
    /// One call's inputs, row-major (kept between steps).
    batch_input: Vec<f32>,
    last_inputs: Vec<Vec<f32>>,
}

impl BeyondMimicPolicy {
    /// Where the file's gains, default pose or action scale differ from the profile's.
    pub fn disagreements(&self) -> &[String] {
        &self.disagreements
    }

    /// The observation terms in use.
    pub fn terms(&self) -> &[Term] {
        &self.spec.terms
    }

    /// Rows of each network call: [`INFERENCE_BATCH`], or 1 for a network whose graph
    /// plans for one row only.
    pub fn call_rows(&self) -> usize {
        self.call_rows
    }

    /// What the network's actions are added to.
    pub fn action_mode(&self) -> ActionMode {
        self.action_mode
    }

    /// The robot's joint index of each of the policy's joints, in the policy's order.
    pub fn joint_order(&self) -> &[usize] {
        &self.spec.to_canonical
    }

    /// Who named the joint order.
    pub fn joint_order_from(&self) -> JointOrderFrom {
        self.joint_order_from
    }

    /// The same policy under another name in results (its family's, e.g. `wbc-mjlab`).
    pub fn named(mut self, name: &str) -> Self {
        self.name = name.to_string();
        self
    }

    /// The target an action of zero means for policy joint `i` (canonical `c`): its
    /// default pose, or the reference's joint position at `frame` for a residual policy.
    fn action_base(&self, i: usize, c: usize, frame: &ReferenceFrame) -> f64 {
        match self.action_mode {
            ActionMode::DefaultRelative => self.spec.default_pos[i],
            ActionMode::ReferenceResidual => frame.joint_pos[c],
        }
    }

    /// The raw action giving `target` on canonical joint `c` under the profile's mapping.
    fn raw_for_target(&self, c: usize, target: f64) -> f64 {
        (target - self.profile_offset[c]) / self.profile_scale[c]
    }

    /// The same network and wiring with no episode started (shares the plan).
    fn fresh_copy(&self) -> Self {
        Self {
            name: self.name.clone(),
            plan: self.plan.clone(),
            network: self.network.clone(),
            call_rows: self.call_rows,
            robot: self.robot.clone(),
            spec: self.spec.clone(),
            obs_width: self.obs_width,
            time_step_input: self.time_step_input,
            actions_output: self.actions_output,
            action_scale: self.action_scale.clone(),
            action_mode: self.action_mode,
            control_dt_s: self.control_dt_s,
            profile_offset: self.profile_offset.clone(),
            profile_scale: self.profile_scale.clone(),
            disagreements: self.disagreements.clone(),
            joint_order_from: self.joint_order_from,
            scratch: Scratch::default(),
            input: Vec::new(),
            batch_input: Vec::new(),
            last_inputs: Vec::new(),
        }
    }

    /// The network's inputs of the last `act`, one per observation (for cross-checks).
    pub fn last_inputs(&self) -> &[Vec<f32>] {
        &self.last_inputs
    }

    /// The policy's last raw action, its order, recovered from the last action that
    /// reached the robot (0 at an episode's start).
    fn policy_last_action(&self, obs: &Observation) -> Vec<f64> {
        let frame = obs.reference.last().expect("a reference frame");
        self.spec
            .to_canonical
            .iter()
            .enumerate()
            .map(|(i, &c)| {
                if obs.step == 0 {
                    return 0.0;
                }
                let target = self.profile_offset[c] + self.profile_scale[c] * obs.last_action[c];
                (target - self.action_base(i, c, frame)) / self.action_scale[i]
            })
            .collect()
    }

    /// Runs the network on one call's rows (`inputs`: [`Self::call_rows`] rows, those past
    /// `observations` zero) and writes each observation's raw action, in the robot's order
    /// for targets `base + scale · a`, the base taken at its reference frame.
    fn infer(
        &self,
        inputs: &[f32],
        observations: &[Observation],
        actions: &mut [Vec<f64>],
    ) -> TractResult<()> {
        let n = self.spec.to_canonical.len();
        let rows = self.call_rows;
        let mut tensors: TVec<TValue> = tvec!();
        let obs = Tensor::from_shape(&[rows, self.obs_width], inputs)?;
        let mut steps = vec![0.0_f32; rows];
        for (t, o) in steps.iter_mut().zip(observations) {
            *t = o.step as f32;
        }
        let time = Tensor::from_shape(&[rows, 1], &steps)?;
        match self.time_step_input {
            Some(0) => {
                tensors.push(time.into());
                tensors.push(obs.into());
            }
            Some(_) => {
                tensors.push(obs.into());
                tensors.push(time.into());
            }
            None => tensors.push(obs.into()),
        }
        let out = self.plan.run(tensors)?;
        let a = out[self.actions_output].to_plain_array_view::<f32>()?;
        let a: Vec<f32> = a.iter().copied().collect();
        if a.len() != rows * n {
            return Err(TractError::msg(format!(
                "the network answered {} actions for {rows} rows of {n} joints",
                a.len()
            )));
        }
        for ((o, row), raw) in observations.iter().zip(a.chunks_exact(n)).zip(actions) {
            let frame = &o.reference[0];
            for (i, &c) in self.spec.to_canonical.iter().enumerate() {
                let target =
                    self.action_base(i, c, frame) + self.action_scale[i] * f64::from(row[i]);
                raw[c] = self.raw_for_target(c, target);
            }
        }
        Ok(())
    }
}

impl Policy for BeyondMimicPolicy {
    fn name(&self) -> &str {
        &self.name
    }

    fn network(&self) -> Option<&crate::policy::network_file::NetworkFile> {
        Some(&self.network)
    }

    fn network_kernels(&self) -> Option<&'static super::network_kernels::NetworkKernels> {
        Some(super::network_kernels::network_kernels())
    }

    fn reference_offsets_s(&self) -> Vec<f64> {
        match self.action_mode {
            ActionMode::DefaultRelative => vec![0.0],
            // The frame the previous action was a residual on, for the `actions` term.
            ActionMode::ReferenceResidual => vec![0.0, -self.control_dt_s],
        }
    }

    fn zero_action(&self, obs: &Observation, out: &mut [f64]) {
        for (i, &c) in self.spec.to_canonical.iter().enumerate() {
            out[c] = self.raw_for_target(c, self.action_base(i, c, &obs.reference[0]));
        }
    }

    fn sanity_exempt(&self) -> Option<&'static str> {
        None
    }

    fn wiring(&self) -> Wiring {
        let terms: Vec<&str> = self.spec.terms.iter().map(|t| t.name()).collect();
        Wiring {
            facts: vec![
                format!("{} inputs: {}", self.obs_width, terms.join(", ")),
                format!(
                    "{} actions, {}",
                    self.spec.to_canonical.len(),
                    self.action_mode.name()
                ),
                match self.joint_order_from {
                    JointOrderFrom::Robot => {
                        "joint order: the robot's (neither the file nor the profile names one)"
                            .to_string()
                    }
                    from => format!("joint order: {}'s", from.name()),
                },
            ],
            disagreements: self.disagreements.clone(),
        }
    }

    fn worker_copies(&self, n: usize) -> Option<Vec<Box<dyn Policy + Send>>> {
        Some(
            (0..n)
                .map(|_| Box::new(self.fresh_copy()) as Box<dyn Policy + Send>)
                .collect(),
        )
    }

    fn act(&mut self, observations: &[Observation], actions: &mut [Vec<f64>]) -> ActOutcome {
        self.last_inputs.clear();
        let (width, rows) = (self.obs_width, self.call_rows);
        let mut batch = std::mem::take(&mut self.batch_input);
        batch.clear();
        batch.resize(observations.len().div_ceil(rows) * rows * width, 0.0);
        for (obs, row) in observations.iter().zip(batch.chunks_exact_mut(width)) {
            let last = self.policy_last_action(obs);
            build_observation(
                &self.spec,
                &self.robot,
                obs,
                &obs.reference[0],
                &last,
                &mut self.scratch,
                &mut self.input,
            );
            row.copy_from_slice(&self.input);
            self.last_inputs.push(self.input.clone());
        }
        let calls = batch
            .chunks_exact(rows * width)
            .zip(observations.chunks(rows).zip(actions.chunks_mut(rows)));
        for (inputs, (obs, action)) in calls {
            // A network that fails at run time answers NaN: the runner's miss rule keeps
            // it away from the physics and counts it.
            if let Err(e) = self.infer(inputs, obs, action) {
                log::warn!(
                    "{}: inference failed: {}",
                    self.name,
                    crate::files::log_text::causes_once(e.as_ref())
                );
                action.iter_mut().for_each(|a| a.fill(f64::NAN));
            }
        }
        self.batch_input = batch;
        ActOutcome::Acted
    }
}
