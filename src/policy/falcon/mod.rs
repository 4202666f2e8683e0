//! FALCON (Zhang et al., "FALCON: Learning Force-Adaptive Humanoid Loco-Manipulation",
//! RSS 2025; github.com/LeCAR-Lab/FALCON, MIT), its released G1 29-DoF network in process:
//! `--policy falcon:g1_29dof_falcon.onnx` under the `falcon` profile.
//!
//! FALCON was trained with a force curriculum on both hands, and it follows **commands**,
//! not a reference's joints: a velocity, a yaw rate, a base height, a stand flag, three
//! waist angles and the fourteen arm joints. [`commands`] derives them from the reference
//! at each step; [`observation`] builds the 575 inputs as the deploy does. The network's
//! output is 15 lower-body actions (legs and waist, relative to the default pose) and 14
//! arm actions, a residual on the commanded arm joints (`residual_upper_body_action`); the
//! profile maps every action as default + 0.25 · a, so the adapter adds the arms'
//! reference offset to the raw action it hands on, and keeps the network's own output for
//! the `actions` term.
//!
//! **Joint order.** FALCON's config (`sim2real/config/robot/g1_29dof_falcon.yaml`,
//! LeCAR-Lab/FALCON 25ad085) labels its first hip joints `hip_yaw, hip_roll, hip_pitch`,
//! but everything at those indices is in the canonical pitch/roll/yaw order: the
//! default-angle comments (`cfg:153-156`, index 0 `left_hip_pitch_joint` at −0.1 rad), the
//! position limits (`cfg:217`: index 0 [−2.5307, 2.8798] is the URDF's hip pitch, index 2
//! [−2.7576, 2.7576] its hip yaw), the identity motor map (`cfg:38-48`) and the training
//! robot's `dof_names`. The output is the lower-body actor (canonical 0–14), then the
//! upper-body one (15–28), read from the ONNX graph. So network index i is canonical joint
//! i and the adapter permutes nothing; `tests/falcon.rs` fails on a swap through its
//! golden actions. The score stays FATS: a command follower's keypoint error includes the
//! drift its commands leave uncorrected.

pub mod commands;
pub mod observation;

use super::batch_plans::BatchPlans;
use super::{ActOutcome, Observation, Policy, Wiring};
use crate::sim::profile::Profile;
use commands::{CommandRules, UPPER};
use observation::{History, N_JOINTS, OBS_LEN};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use tract_onnx::prelude::*;

/// FALCON's default joint angles, canonical order (`DEFAULT_DOF_ANGLES`,
/// `sim2real/config/robot/g1_29dof_falcon.yaml:153-183`).
pub const DEFAULT_POSE: [f64; N_JOINTS] = {
    let mut q = [0.0; N_JOINTS];
    q[0] = -0.1;
    q[3] = 0.3;
    q[4] = -0.2;
    q[6] = -0.1;
    q[9] = 0.3;
    q[10] = -0.2;
    q
};
/// Action scale (`loco_manip.py:21`, `action_scale: 0.25`).
pub const ACTION_SCALE: f64 = 0.25;
/// The network's output is clipped to ±this before use and in the `actions` term
/// (`loco_manip.py:86`).
pub const ACTION_CLIP: f64 = 100.0;
/// Control period, s (`rl_rate` 50 Hz, `loco_manip.py:21`).
pub const CONTROL_DT_S: f64 = 0.02;
/// The deploy clips every joint target to these before sending it (`loco_manip.py:137-138`,
/// `motor_pos_lower_limit_list` / `motor_pos_upper_limit_list`, `g1_29dof_falcon.yaml:217-230`),
/// rad, canonical order. They are the G1's joint ranges except the waist's roll and pitch
/// (±0.52) and matter where a stiff joint would otherwise be driven into its stop: the
/// ankle roll (±0.2618) and the waist at kp 300.
#[allow(clippy::approx_constant)] // the deploy's numbers as its config writes them
pub const MOTOR_POS_LOWER_RAD: [f64; N_JOINTS] = [
    -2.5307,
    -0.5236,
    -2.7576,
    -0.087267,
    -0.87267,
    -0.2618, //
    -2.5307,
    -2.9671,
    -2.7576,
    -0.087267,
    -0.87267,
    -0.2618, //
    -2.618,
    -0.52,
    -0.52, //
    -3.0892,
    -1.5882,
    -2.618,
    -1.0472,
    -1.972222054,
    -1.61443,
    -1.61443, //
    -3.0892,
    -2.2515,
    -2.618,
    -1.0472,
    -1.972222054,
    -1.61443,
    -1.61443,
];
/// Upper bounds of [`MOTOR_POS_LOWER_RAD`], rad.
#[allow(clippy::approx_constant)] // as above
pub const MOTOR_POS_UPPER_RAD: [f64; N_JOINTS] = [
    2.8798,
    2.9671,
    2.7576,
    2.8798,
    0.5236,
    0.2618, //
    2.8798,
    0.5236,
    2.7576,
    2.8798,
    0.5236,
    0.2618, //
    2.618,
    0.52,
    0.52, //
    2.6704,
    2.2515,
    2.618,
    2.0944,
    1.972222054,
    1.61443,
    1.61443, //
    2.6704,
    1.5882,
    2.618,
    2.0944,
    1.972222054,
    1.61443,
    1.61443,
];

/// Why the policy could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum FalconError {
    /// tract could not load or prepare the network.
    #[error("loading the FALCON network {path}: {message} (FALCON's network takes [1, {OBS_LEN}] and gives [1, {N_JOINTS}])")]
    Load {
        /// The ONNX file.
        path: PathBuf,
        /// tract's message.
        message: String,
    },
    /// The robot is not the 29-joint G1.
    #[error("FALCON needs the 29-joint G1 (got {0} joints)")]
    Joints(usize),
}

/// One environment's state between steps.
#[derive(Debug, Clone, Default)]
struct Slot {
    history: History,
    /// The network's last output, clipped (the `actions` term).
    last_raw: Vec<f64>,
    /// The command sample in force and the step it was taken at (`None` before an
    /// episode's first step).
    held: Option<(commands::Sample, usize)>,
}

/// FALCON in process.
pub struct FalconPolicy {
    plans: BatchPlans,
    plan: Arc<TypedRunnableModel>,
    /// The file loaded, by content (`run.json`'s network).
    network: crate::policy::network_file::NetworkFile,
    /// The profile's action offset and scale, to express the arms' residual as a raw action.
    profile_offset: Vec<f64>,
    profile_scale: Vec<f64>,
    /// What the profile contradicts in FALCON's own wiring.
    disagreements: Vec<String>,
    /// Scale of the arms' residual as applied (1: as trained; 0: the arms held at their
    /// commanded joints, the ablation `falcon:F.onnx@arm_residual=0`). The `actions` term
    /// of the observation keeps the network's own output either way.
    arm_residual_scale: f64,
    /// How the commands keep or leave training's distribution (as on the board unless
    /// ablated).
    command_rules: CommandRules,
    slots: Vec<Slot>,
    input: Vec<f32>,
    last_inputs: Vec<Vec<f32>>,
}

impl FalconPolicy {
    /// Loads the network (input `[1, 575]` float32, output `[1, 29]`) to run under
    /// `profile` (FALCON's is `falcon`; another is reported by [`Policy::wiring`]).
    pub fn load(path: &Path, profile: &Profile) -> Result<Self, FalconError> {
        if profile.action_offset_rad.len() != N_JOINTS {
            return Err(FalconError::Joints(profile.action_offset_rad.len()));
        }
        let load = || -> TractResult<(BatchPlans, Arc<TypedRunnableModel>, _)> {
            let (model, network) = super::network_kernels::load_onnx(path)?;
            let plans = BatchPlans::new(model, OBS_LEN, Some(N_JOINTS))?;
            let plan = plans.plan(1)?;
            Ok((plans, plan, network))
        };
        let (plans, plan, network) = load().map_err(|e| FalconError::Load {
            path: path.to_path_buf(),
            message: crate::files::log_text::causes_once(e.as_ref()),
        })?;
        Ok(Self {
            plans,
            plan,
            network,
            profile_offset: profile.action_offset_rad.clone(),
            profile_scale: profile.action_scale.clone(),
            disagreements: disagreements(profile),
            arm_residual_scale: 1.0,
            command_rules: CommandRules::BENCHMARK,
            slots: Vec::new(),
            input: vec![0.0; OBS_LEN],
            last_inputs: Vec::new(),
        })
    }

    /// The same policy applying `scale` × the arms' residual (1: as trained; 0: the arms
    /// held at their commanded joints — an ablation, not FALCON as deployed).
    pub fn with_arm_residual_scale(mut self, scale: f64) -> Self {
        self.arm_residual_scale = scale;
        self
    }

    /// The same policy under other command rules (an ablation of the adapter's
    /// exceptions to training's command distribution).
    pub fn with_command_rules(mut self, rules: CommandRules) -> Self {
        self.command_rules = rules;
        self
    }

    /// The network's inputs of the last `act`, one per observation (for tests).
    pub fn last_inputs(&self) -> &[Vec<f32>] {
        &self.last_inputs
    }

    /// Runs the network on one observation.
    pub fn infer(&self, input: &[f32]) -> TractResult<Vec<f32>> {
        self.plans.run_on(&self.plan, input, 1)
    }

    /// The raw action (under the profile's mapping) that puts joint `c` at `target`.
    fn raw_for_target(&self, c: usize, target: f64) -> f64 {
        (target - self.profile_offset[c]) / self.profile_scale[c]
    }

    /// The raw actions handed to the simulator for one network output, as the deploy turns
    /// an output into targets (`loco_manip.py:86-138`): clipped to ±[`ACTION_CLIP`]; the
    /// legs and waist at the profile's offset + scale · a, the arms at `upper_command` +
    /// 0.25 · a (the residual, × the arm residual scale, 1 unless ablated); every target
    /// clipped to the motor limits; then expressed
    /// as the raw action that gives that target under the profile. Under FALCON's own
    /// profile the targets are the deploy's.
    pub fn raw_actions(&self, network_out: &[f32], upper_command: &[f64; 14], out: &mut [f64]) {
        for (c, (o, a)) in out.iter_mut().zip(network_out).enumerate() {
            let a = f64::from(*a).clamp(-ACTION_CLIP, ACTION_CLIP);
            let target = if UPPER.contains(&c) {
                upper_command[c - UPPER.start] + ACTION_SCALE * a * self.arm_residual_scale
            } else {
                self.profile_offset[c] + self.profile_scale[c] * a
            };
            let target = target.clamp(MOTOR_POS_LOWER_RAD[c], MOTOR_POS_UPPER_RAD[c]);
            *o = self.raw_for_target(c, target);
        }
    }
}

/// Where `profile` contradicts FALCON's deploy: its rate, action scale and default pose.
fn disagreements(profile: &Profile) -> Vec<String> {
    super::trained_with::TrainedWith {
        family: "FALCON",
        control_dt_s: CONTROL_DT_S,
        action_scale: ACTION_SCALE,
        default_pose: &DEFAULT_POSE,
    }
    .contradictions(profile)
}

impl Policy for FalconPolicy {
    fn name(&self) -> &str {
        "falcon"
    }

    fn network(&self) -> Option<&crate::policy::network_file::NetworkFile> {
        Some(&self.network)
    }

    fn network_kernels(&self) -> Option<&'static super::network_kernels::NetworkKernels> {
        Some(super::network_kernels::network_kernels())
    }

    fn reference_offsets_s(&self) -> Vec<f64> {
        commands::reference_offsets_s()
    }

    fn follows_commands(&self) -> Option<&'static str> {
        Some("root velocity, heading and base height, arm joints")
    }

    /// What differs from FALCON on the board — the arm residual's scale, the command
    /// rules — so that runs of FALCON as benchmarked name nothing new.
    fn parameters(&self) -> Vec<(&'static str, f64)> {
        let b = CommandRules::BENCHMARK;
        let r = &self.command_rules;
        [
            ("arm_residual_scale", self.arm_residual_scale, 1.0),
            ("command_min_speed_m_s", r.min_speed_m_s, b.min_speed_m_s),
            (
                "command_yaw_feedforward",
                r.yaw_feedforward,
                b.yaw_feedforward,
            ),
            ("command_hold_s", r.hold_s, b.hold_s),
        ]
        .into_iter()
        .filter(|(_, value, default)| value != default)
        .map(|(name, value, _)| (name, value))
        .collect()
    }

    fn sanity_exempt(&self) -> Option<&'static str> {
        None
    }

    fn reset(&mut self, env: usize) {
        if let Some(slot) = self.slots.get_mut(env) {
            *slot = Slot::default();
        }
    }

    fn wiring(&self) -> Wiring {
        Wiring {
            facts: vec![
                format!("{OBS_LEN} inputs: FALCON's 5 frames of 115 (terms in alphabetical order), oldest first"),
                "a command-following policy: velocity, yaw rate, base height, stand flag and waist commands derived from the reference, arm joints one step ahead".into(),
                format!("{N_JOINTS} actions: legs and waist relative to the default pose, arms a residual on the commanded arm joints, scale {ACTION_SCALE}"),
            ],
            disagreements: self.disagreements.clone(),
        }
    }

    fn zero_action(&self, obs: &Observation, out: &mut [f64]) {
        out.fill(0.0);
        for c in UPPER {
            out[c] = self.raw_for_target(c, obs.reference[0].joint_pos[c]);
        }
    }

    fn worker_copies(&self, n: usize) -> Option<Vec<Box<dyn Policy + Send>>> {
        Some(
            (0..n)
                .map(|_| {
                    Box::new(Self {
                        plans: self.plans.clone(),
                        plan: self.plan.clone(),
                        network: self.network.clone(),
                        profile_offset: self.profile_offset.clone(),
                        profile_scale: self.profile_scale.clone(),
                        disagreements: self.disagreements.clone(),
                        arm_residual_scale: self.arm_residual_scale,
                        command_rules: self.command_rules,
                        slots: Vec::new(),
                        input: vec![0.0; OBS_LEN],
                        last_inputs: Vec::new(),
                    }) as Box<dyn Policy + Send>
                })
                .collect(),
        )
    }

    fn act(&mut self, observations: &[Observation], actions: &mut [Vec<f64>]) -> ActOutcome {
        // Kept for tests, in buffers reused from call to call (no allocation per step).
        self.last_inputs.resize_with(observations.len(), Vec::new);
        for (row, (obs, action)) in observations.iter().zip(actions.iter_mut()).enumerate() {
            if self.slots.len() <= obs.env {
                self.slots.resize_with(obs.env + 1, Slot::default);
            }
            let starts = obs.step == 0;
            let slot = &mut self.slots[obs.env];
            if starts || slot.last_raw.len() != N_JOINTS {
                *slot = Slot {
                    last_raw: vec![0.0; N_JOINTS],
                    ..Slot::default()
                };
            }
            let hold_steps = (self.command_rules.hold_s / CONTROL_DT_S).round() as usize;
            let sample = match slot.held {
                Some((held, at)) if obs.step < at + hold_steps.max(1) => held,
                before => {
                    let s = commands::sample(
                        &obs.root,
                        &obs.reference,
                        before.map(|(h, _)| h.walking),
                        &self.command_rules,
                    );
                    slot.held = Some((s, obs.step));
                    s
                }
            };
            let cmd = commands::commands(&obs.root, &obs.reference, &sample);
            let frame = observation::frame(obs, &DEFAULT_POSE, &slot.last_raw, &cmd);
            slot.history.push_into(frame, starts, &mut self.input);
            self.last_inputs[row].clone_from(&self.input);
            match self.plans.run_row(&self.plan, &self.input, "falcon") {
                Some(out) => {
                    let slot = &mut self.slots[obs.env];
                    for (last, o) in slot.last_raw.iter_mut().zip(&out) {
                        *last = f64::from(*o).clamp(-ACTION_CLIP, ACTION_CLIP);
                    }
                    self.raw_actions(&out, &cmd.upper, action);
                }
                None => action.fill(f64::NAN),
            }
        }
        ActOutcome::Acted
    }
}
