//! The BeyondMimic family of whole-body tracking policies in process: `--policy
//! beyondmimic:FILE.onnx` runs an exported network (mjlab, whole_body_tracking, holosoma)
//! on tract, no Python.
//!
//! Everything policy-specific comes from the file where it says it, else from the profile
//! (`[beyondmimic]` and the action mapping): joint order (`joint_names` / `dof_names`,
//! mapped to the robot's by name), default pose and action scale, observation terms
//! (`observation_names`; else the profile's; else the known layout whose width is the
//! network's input), anchor body. Gains are the profile's (the simulator applies them);
//! where the file's kp, kd, default pose or action scale differ from the profile's, the
//! difference is reported ([`BeyondMimicPolicy::disagreements`], and logged). A network
//! with a `time_step` input is fed the episode's control step.
//!
//! Actions: the policy means `target = default + scale · a` with its own numbers; the raw
//! action handed to the profile is the one giving exactly that target under the profile's
//! mapping (the same when they agree), and the `actions` term inverts the same mapping on
//! the last action that reached the robot. The Python adapter
//! (`adapters/python/thorarena/adapters/beyondmimic.py`) does the same and is tested
//! against this one.

mod metadata;
mod observation;

pub use metadata::FileMetadata;
pub use observation::{
    build_observation, layout_width, reference_anchor_in_robot_anchor, ObservationSpec, Scratch,
    Term, LAYOUT_154, LAYOUT_160,
};

use super::{ActOutcome, Observation, Policy};
use crate::profile::Profile;
use crate::robot::RobotModel;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
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

/// A loaded BeyondMimic-style network and how to talk to it.
pub struct BeyondMimicPolicy {
    plan: Arc<TypedRunnableModel>,
    robot: Arc<RobotModel>,
    spec: ObservationSpec,
    obs_width: usize,
    /// Input slot of `time_step`, if the network has one.
    time_step_input: Option<usize>,
    /// Output slot of `actions`.
    actions_output: usize,
    /// The policy's action scale, policy order.
    action_scale: Vec<f64>,
    /// The profile's action offset and scale, canonical order.
    profile_offset: Vec<f64>,
    profile_scale: Vec<f64>,
    disagreements: Vec<String>,
    scratch: Scratch,
    input: Vec<f32>,
    last_inputs: Vec<Vec<f32>>,
}

/// The network's metadata properties as text (tract keeps them as `onnx.metadata_props.*`
/// string scalars).
fn metadata_props(model: &InferenceModel) -> HashMap<String, String> {
    model
        .properties
        .iter()
        .filter_map(|(k, v)| {
            let key = k.strip_prefix("onnx.metadata_props.")?;
            let plain = v.try_as_plain_ram().ok()?;
            let text = plain.to_scalar::<String>().ok()?.clone();
            Some((key.to_string(), text))
        })
        .collect()
}

/// Index of the model input or output named `name`.
fn slot(model: &InferenceModel, outlets: &[OutletId], name: &str) -> Option<usize> {
    outlets
        .iter()
        .position(|o| model.outlet_label(*o) == Some(name) || model.node(o.node).name == name)
}

/// `what` per joint, compared between file and profile (both canonical order); a sentence
/// when they differ by more than `tolerance` (relative).
fn compare(
    what: &str,
    file: &[f64],
    profile: &[f64],
    names: &[String],
    tol: f64,
) -> Option<String> {
    let worst = file
        .iter()
        .zip(profile)
        .enumerate()
        .map(|(j, (f, p))| (j, (f - p).abs() / p.abs().max(1e-9)))
        .filter(|(_, rel)| *rel > tol)
        .max_by(|a, b| a.1.total_cmp(&b.1))?;
    let j = worst.0;
    Some(format!(
        "{what}: the file and the profile differ (largest at {}: file {}, profile {})",
        names[j], file[j], profile[j]
    ))
}

impl BeyondMimicPolicy {
    /// Loads `path` for `robot` under `profile` (whose action mapping and gains the
    /// benchmark applies).
    pub fn load(
        path: &Path,
        robot: Arc<RobotModel>,
        profile: &Profile,
    ) -> Result<Self, BeyondMimicError> {
        let load_err = |e: TractError| BeyondMimicError::Load {
            path: path.to_path_buf(),
            message: format!("{e:#}"),
        };
        let unusable = |reason: String| BeyondMimicError::Unusable {
            path: path.to_path_buf(),
            reason,
        };
        let n = robot.n_joints();
        let model = onnx().model_for_path(path).map_err(load_err)?;
        let meta = FileMetadata::from_props(&metadata_props(&model)).map_err(unusable)?;
        let inputs = model.input_outlets().map_err(load_err)?.to_vec();
        let outputs = model.output_outlets().map_err(load_err)?.to_vec();
        let obs_input = slot(&model, &inputs, "obs").unwrap_or(0);
        let time_step_input = slot(&model, &inputs, "time_step");
        let actions_output = slot(&model, &outputs, "actions").unwrap_or(0);
        let obs_width = {
            let fact = model.input_fact(obs_input).map_err(load_err)?;
            fact.shape
                .dims()
                .last()
                .and_then(tract_onnx::tract_hir::infer::Factoid::concretize)
                .and_then(|d| d.as_i64())
                .and_then(|d| usize::try_from(d).ok())
                .ok_or_else(|| unusable("the observation input has no fixed width".into()))?
        };

        // Joint order: the file's names, mapped to the robot's.
        let joint_names: Vec<String> = meta
            .joint_names
            .clone()
            .unwrap_or_else(|| robot.joints.iter().map(|j| j.name.clone()).collect());
        if joint_names.len() != n {
            return Err(unusable(format!(
                "the policy has {} joints, the robot {} has {n}",
                joint_names.len(),
                robot.name
            )));
        }
        let to_canonical = joint_names
            .iter()
            .map(|name| {
                robot.joint_index(name).ok_or_else(|| {
                    unusable(format!(
                        "joint `{name}` of the policy is not a joint of {}",
                        robot.name
                    ))
                })
            })
            .collect::<Result<Vec<usize>, _>>()?;
        let mut seen = vec![false; n];
        for (&c, name) in to_canonical.iter().zip(&joint_names) {
            if std::mem::replace(&mut seen[c], true) {
                return Err(unusable(format!(
                    "joint `{name}` is named twice in the file's joint order"
                )));
            }
        }
        let policy_order = |canonical: &[f64]| -> Vec<f64> {
            to_canonical.iter().map(|&c| canonical[c]).collect()
        };
        let per_joint = |what: &str, v: Option<Vec<f64>>, fallback: Vec<f64>| match v {
            Some(v) if v.len() == 1 => Ok(vec![v[0]; n]),
            Some(v) if v.len() == n => Ok(v),
            Some(v) => Err(unusable(format!(
                "metadata {what} has {} values for {n} joints",
                v.len()
            ))),
            None => Ok(fallback),
        };
        let default_pos = per_joint(
            "default_joint_pos",
            meta.default_joint_pos.clone(),
            policy_order(&profile.action_offset_rad),
        )?;
        let action_scale = per_joint(
            "action_scale",
            meta.action_scale.clone(),
            policy_order(&profile.action_scale),
        )?;
        // A zero scale ignores the network (and the `actions` term divides by it).
        if let Some(i) = action_scale
            .iter()
            .position(|a| !a.is_finite() || *a == 0.0)
        {
            return Err(unusable(format!(
                "action scale {} for joint `{}`: it must be finite and non-zero",
                action_scale[i], joint_names[i]
            )));
        }
        if let Some(i) = default_pos.iter().position(|a| !a.is_finite()) {
            return Err(unusable(format!(
                "default_joint_pos {} for joint `{}` is not finite",
                default_pos[i], joint_names[i]
            )));
        }

        // What the file says against what the profile applies, canonical order.
        let canonical = |policy: &[f64]| {
            let mut c = vec![0.0; n];
            for (i, &ci) in to_canonical.iter().enumerate() {
                c[ci] = policy[i];
            }
            c
        };
        let names: Vec<String> = robot.joints.iter().map(|j| j.name.clone()).collect();
        let mut disagreements = Vec::new();
        for (what, file, applied) in [
            ("kp", meta.kp.clone(), &profile.gains.kp),
            ("kd", meta.kd.clone(), &profile.gains.kd),
            (
                "default pose",
                meta.default_joint_pos.clone(),
                &profile.action_offset_rad,
            ),
            (
                "action scale",
                meta.action_scale.clone(),
                &profile.action_scale,
            ),
        ] {
            let Some(file) = file else { continue };
            let file = per_joint(what, Some(file), Vec::new())?;
            // 1e-3 relative: the metadata of mjlab exports is written with 3 decimals.
            if let Some(d) = compare(what, &canonical(&file), applied, &names, 1e-3) {
                disagreements.push(format!("{d}; the profile `{}` is applied", profile.name));
            }
        }

        // Observation terms: the file's, the profile's, or the layout of the right width.
        let profile_bm = profile.beyondmimic.as_ref();
        let (terms, from) = if let Some(names) = &meta.observation_names {
            (
                parse_terms(names).map_err(unusable)?,
                "the file's observation_names",
            )
        } else if let Some(bm) = profile_bm.filter(|b| !b.observation_names.is_empty()) {
            (
                parse_terms(&bm.observation_names).map_err(unusable)?,
                "the profile's [beyondmimic] observation_names",
            )
        } else if let Some(l) = [&LAYOUT_160[..], &LAYOUT_154[..]]
            .into_iter()
            .find(|l| layout_width(l, n) == obs_width)
        {
            (l.to_vec(), "the known layout of that width")
        } else {
            return Err(unusable(format!(
                "no observation_names in the file or the profile, and its input width {obs_width} is neither {} nor {}",
                layout_width(&LAYOUT_160, n),
                layout_width(&LAYOUT_154, n)
            )));
        };
        if layout_width(&terms, n) != obs_width {
            return Err(unusable(format!(
                "{from} make {} inputs, the network takes {obs_width}",
                layout_width(&terms, n)
            )));
        }
        let anchor_body = meta
            .anchor_body
            .clone()
            .or_else(|| profile_bm.map(|b| b.anchor_body.clone()))
            .unwrap_or_else(|| "torso_link".into());
        let anchor_frame = robot.frame_index(&anchor_body).ok_or_else(|| {
            unusable(format!(
                "anchor body `{anchor_body}` is not a body of {}",
                robot.name
            ))
        })?;

        let mut model = model
            .with_input_fact(obs_input, f32::fact([1, obs_width]).into())
            .map_err(load_err)?;
        if let Some(t) = time_step_input {
            model = model
                .with_input_fact(t, f32::fact([1, 1]).into())
                .map_err(load_err)?;
        }
        let typed = model.into_optimized().map_err(load_err)?;
        // One action per joint, or every step fails (a wrong width once scored as a
        // network answering zeros).
        let action_width = typed
            .output_fact(actions_output)
            .ok()
            .and_then(|f| f.shape.as_concrete().map(|s| s.to_vec()));
        if action_width.as_deref().and_then(|s| s.last()) != Some(&n)
            || action_width
                .as_deref()
                .is_some_and(|s| s.iter().product::<usize>() != n)
        {
            return Err(unusable(format!(
                "the `actions` output has shape {action_width:?}, not one value per joint ({n})"
            )));
        }
        let plan = typed.into_runnable().map_err(load_err)?;
        for d in &disagreements {
            log::warn!("{}: {d}", path.display());
        }
        Ok(Self {
            plan,
            spec: ObservationSpec {
                terms,
                to_canonical,
                default_pos,
                anchor_frame,
            },
            robot,
            obs_width,
            time_step_input,
            actions_output,
            action_scale,
            profile_offset: profile.action_offset_rad.clone(),
            profile_scale: profile.action_scale.clone(),
            disagreements,
            scratch: Scratch::default(),
            input: Vec::new(),
            last_inputs: Vec::new(),
        })
    }

    /// Where the file's gains, default pose or action scale differ from the profile's.
    pub fn disagreements(&self) -> &[String] {
        &self.disagreements
    }

    /// The observation terms in use.
    pub fn terms(&self) -> &[Term] {
        &self.spec.terms
    }

    /// The network's inputs of the last `act`, one per observation (for cross-checks).
    pub fn last_inputs(&self) -> &[Vec<f32>] {
        &self.last_inputs
    }

    /// The policy's last raw action, its order, recovered from the last action that
    /// reached the robot (0 at an episode's start).
    fn policy_last_action(&self, obs: &Observation) -> Vec<f64> {
        self.spec
            .to_canonical
            .iter()
            .enumerate()
            .map(|(i, &c)| {
                if obs.step == 0 {
                    return 0.0;
                }
                let target = self.profile_offset[c] + self.profile_scale[c] * obs.last_action[c];
                (target - self.spec.default_pos[i]) / self.action_scale[i]
            })
            .collect()
    }

    /// Runs the network on one observation; returns the raw action in the robot's order.
    fn infer(&self, input: &[f32], step: usize) -> TractResult<Vec<f64>> {
        let n = self.spec.to_canonical.len();
        let mut inputs: TVec<TValue> = tvec!();
        let obs = Tensor::from_shape(&[1, self.obs_width], input)?;
        let time = Tensor::from_shape(&[1, 1], &[step as f32])?;
        match self.time_step_input {
            Some(0) => {
                inputs.push(time.into());
                inputs.push(obs.into());
            }
            Some(_) => {
                inputs.push(obs.into());
                inputs.push(time.into());
            }
            None => inputs.push(obs.into()),
        }
        let out = self.plan.run(inputs)?;
        let a = out[self.actions_output].to_plain_array_view::<f32>()?;
        let a: Vec<f32> = a.iter().copied().collect();
        if a.len() != n {
            return Err(TractError::msg(format!(
                "the network answered {} actions for {n} joints",
                a.len()
            )));
        }
        let mut raw = vec![0.0; n];
        for (i, &c) in self.spec.to_canonical.iter().enumerate() {
            let target = self.spec.default_pos[i] + self.action_scale[i] * f64::from(a[i]);
            raw[c] = (target - self.profile_offset[c]) / self.profile_scale[c];
        }
        Ok(raw)
    }
}

fn parse_terms(names: &[String]) -> Result<Vec<Term>, String> {
    names
        .iter()
        .map(|n| Term::parse(n).ok_or_else(|| format!("observation term `{n}` is not one of the BeyondMimic family's (command, motion_anchor_pos_b, motion_anchor_ori_b, base_lin_vel, base_ang_vel, joint_pos, joint_vel, actions)")))
        .collect()
}

impl Policy for BeyondMimicPolicy {
    fn name(&self) -> &str {
        "beyondmimic"
    }

    fn act(&mut self, observations: &[Observation], actions: &mut [Vec<f64>]) -> ActOutcome {
        self.last_inputs.clear();
        for (obs, action) in observations.iter().zip(actions.iter_mut()) {
            let last = self.policy_last_action(obs);
            let mut input = std::mem::take(&mut self.input);
            build_observation(
                &self.spec,
                &self.robot,
                obs,
                &obs.reference[0],
                &last,
                &mut self.scratch,
                &mut input,
            );
            match self.infer(&input, obs.step) {
                Ok(raw) => action.copy_from_slice(&raw),
                // A network that fails at run time answers NaN: the runner's miss rule
                // keeps it away from the physics and counts it.
                Err(e) => {
                    log::warn!("beyondmimic: inference failed: {e:#}");
                    action.fill(f64::NAN);
                }
            }
            self.last_inputs.push(input.clone());
            self.input = input;
        }
        ActOutcome::Acted
    }
}
