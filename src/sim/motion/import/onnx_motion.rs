//! The reference motion embedded in a BeyondMimic-style tracking network (holosoma's
//! exports: `fastsac_g1_29dof_dancing.onnx`), read by evaluating the network — no Python.
//!
//! Such a network takes `time_step` [1, 1] next to its observation and returns, besides
//! `actions`, the motion it was trained on at that step: `joint_pos`, `joint_vel`
//! [1, n] (its joint order, `joint_names` / `dof_names` metadata), and the pose of its
//! reference body — `ref_pos_xyz` [1, 3] and `ref_quat_xyzw` [1, 4], **x, y, z, w** — which
//! in holosoma is `torso_link`, not the pelvis (`inference/policies/wbt.py`,
//! `body_name_ref`). The root pose therefore follows from our kinematics: pelvis = torso ·
//! (pelvis → torso at that frame's waist joints)⁻¹.
//!
//! The network clamps `time_step` to its last frame, so the motion ends where the outputs
//! stop changing: the first step whose outputs equal the previous step's and stay equal for
//! [`END_CONFIRM_STEPS`] more. The frame rate is the control rate the policy runs at (the
//! profile's), since the network's steps are its control steps.

use super::{ImportError, RawMotion};
use crate::sim::robot::{forward_kinematics, frame_pose, RobotModel};
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};
use std::path::Path;
use std::sync::Arc;
use tract_onnx::prelude::*;

const FORMAT: &str = "onnx-motion";

/// Steps of unchanged outputs that confirm the motion has ended (5 s at 50 Hz: no
/// captured motion holds every joint bit-for-bit still that long).
pub const END_CONFIRM_STEPS: usize = 250;

/// Longest motion read, control steps (2 hours at 50 Hz): a network whose outputs never
/// settle is an error rather than a hang.
pub const MAX_STEPS: usize = 360_000;

/// Most values an input other than the time step may declare (observations are a few
/// hundred; this is 4 MB of zeros).
pub const MAX_INPUT_VALUES: usize = 1 << 20;

/// The motion outputs a network must have.
pub const MOTION_OUTPUTS: [&str; 4] = ["joint_pos", "joint_vel", "ref_pos_xyz", "ref_quat_xyzw"];

/// Reads the motion embedded in the network at `path`, for `robot`, whose reference body
/// is `reference_body`, at control step `control_dt_s`.
pub fn read_onnx_motion(
    path: &Path,
    robot: &RobotModel,
    reference_body: &str,
    control_dt_s: f64,
) -> Result<RawMotion, ImportError> {
    if !path.exists() {
        return Err(ImportError::Io {
            path: path.to_path_buf(),
            source: std::io::Error::from(std::io::ErrorKind::NotFound),
        });
    }
    let (model, _) = crate::policy::network_kernels::load_onnx(path).map_err(tract_error(path))?;
    let props = crate::policy::onnx_export::metadata_props(&model);
    let meta = crate::policy::onnx_export::FileMetadata::from_props(&props)
        .map_err(|reason| format_error(path, reason))?;
    let probe = MotionProbe::new(model, path)?;
    let frames = probe.play(path)?;
    let joint_names: Vec<String> = meta
        .joint_names
        .unwrap_or_else(|| robot.joints.iter().map(|j| j.name.clone()).collect());
    check_frame_widths(&frames[0], &joint_names).map_err(|reason| format_error(path, reason))?;
    let (root_pos, root_quat_wxyz) = root_poses(robot, reference_body, &joint_names, &frames)
        .map_err(|reason| format_error(path, reason))?;
    Ok(RawMotion {
        fps: 1.0 / control_dt_s,
        root_pos,
        root_quat_wxyz,
        joint_names,
        joint_pos: frames.iter().map(|f| f[0].clone()).collect(),
        joint_vel: Some(frames.iter().map(|f| f[1].clone()).collect()),
        provenance: provenance(path, frames.len(), reference_body),
    })
}

/// The file is not a network with an embedded motion (or the motion is unusable).
fn format_error(path: &Path, reason: String) -> ImportError {
    ImportError::Format {
        path: path.to_path_buf(),
        format: FORMAT,
        reason,
    }
}

/// tract could not load, prepare or run the network.
fn tract_error(path: &Path) -> impl Fn(TractError) -> ImportError + Copy + '_ {
    move |e| format_error(path, crate::files::log_text::causes_once(e.as_ref()))
}

/// One step's motion outputs, in [`MOTION_OUTPUTS`] order: joint positions, joint
/// velocities (policy order), reference body position and quaternion (x, y, z, w).
type MotionFrame = Vec<Vec<f64>>;

/// The network made runnable with every input but the time step fed zeros, which it
/// evaluates step by step for the motion outputs alone.
struct MotionProbe {
    plan: Arc<TypedRunnableModel>,
    /// Per input: the zeros it is fed, or `None` for the `time_step` input.
    zeros: Vec<Option<Tensor>>,
    /// Output slots of [`MOTION_OUTPUTS`].
    motion_outputs: [usize; 4],
}

impl MotionProbe {
    /// Checks that the network has the motion outputs and a `time_step` input, fixes the
    /// input shapes and makes it runnable.
    fn new(model: InferenceModel, path: &Path) -> Result<Self, ImportError> {
        let tract_err = tract_error(path);
        let (inputs, outputs) = io_labels(&model).map_err(tract_err)?;
        let missing: Vec<&str> = MOTION_OUTPUTS
            .iter()
            .copied()
            .filter(|m| !outputs.iter().any(|o| o == m))
            .collect();
        if !missing.is_empty() {
            return Err(format_error(path, format!(
                "the network has no motion outputs {missing:?} (it has {outputs:?}): only networks with their reference motion embedded can be imported"
            )));
        }
        let Some(time_input) = inputs.iter().position(|i| i == "time_step") else {
            return Err(format_error(
                path,
                format!("the network has no `time_step` input (it has {inputs:?})"),
            ));
        };
        let (model, zeros) = fix_inputs(model, &inputs, time_input, path)?;
        let plan = model
            .into_optimized()
            .and_then(|m| m.into_runnable())
            .map_err(tract_err)?;
        let slot = |name: &str| {
            outputs
                .iter()
                .position(|o| o == name)
                .expect("checked above")
        };
        Ok(Self {
            plan,
            zeros,
            motion_outputs: MOTION_OUTPUTS.map(slot),
        })
    }

    /// The motion outputs at control step `step`.
    fn eval(&self, step: usize) -> TractResult<MotionFrame> {
        let feed: TVec<TValue> = self
            .zeros
            .iter()
            .map(|z| match z {
                Some(t) => Ok(t.clone().into()),
                None => Tensor::from_shape(&[1, 1], &[step as f32]).map(Into::into),
            })
            .collect::<TractResult<_>>()?;
        let out = self.plan.run(feed)?;
        self.motion_outputs
            .iter()
            .map(|&i| {
                let view = out[i].to_plain_array_view::<f32>()?;
                Ok(view.iter().map(|&v| f64::from(v)).collect())
            })
            .collect()
    }

    /// Steps the network from 0 until its outputs stop changing (it clamps `time_step` to
    /// its last frame): the frames up to the last change, a pause that ended kept.
    fn play(&self, path: &Path) -> Result<Vec<MotionFrame>, ImportError> {
        let mut frames: Vec<MotionFrame> = Vec::new();
        let mut unchanged = 0usize;
        let mut step = 0usize;
        loop {
            if step > MAX_STEPS {
                return Err(format_error(path, format!(
                    "the motion outputs still change after {MAX_STEPS} steps: not a clamped, embedded motion"
                )));
            }
            let f = self.eval(step).map_err(tract_error(path))?;
            if let Some(k) = f.iter().position(|v| v.iter().any(|x| !x.is_finite())) {
                return Err(format_error(
                    path,
                    format!(
                        "output `{}` is not finite at step {step}",
                        MOTION_OUTPUTS[k]
                    ),
                ));
            }
            if frames.last() == Some(&f) {
                unchanged += 1;
                if unchanged >= END_CONFIRM_STEPS {
                    break;
                }
            } else {
                // A pause that ended was motion after all: keep its frames.
                for _ in 0..unchanged {
                    let last = frames.last().expect("a frame before a repeat").clone();
                    frames.push(last);
                }
                unchanged = 0;
                frames.push(f);
            }
            step += 1;
        }
        Ok(frames)
    }
}

/// The labels of the network's inputs and outputs (an outlet's label, else its node's
/// name).
fn io_labels(model: &InferenceModel) -> TractResult<(Vec<String>, Vec<String>)> {
    let label = |o: &OutletId| {
        model
            .outlet_label(*o)
            .map(str::to_string)
            .unwrap_or_else(|| model.node(o.node).name.clone())
    };
    let inputs = model.input_outlets()?.iter().map(label).collect();
    let outputs = model.output_outlets()?.iter().map(label).collect();
    Ok((inputs, outputs))
}

/// Fixes every input's shape: the time step [1, 1]; every other input (the observation)
/// its declared fixed shape, fed zeros — the motion outputs depend on the step alone.
/// Returns the model and, per input, its zeros (`None` for the time step).
fn fix_inputs(
    mut model: InferenceModel,
    inputs: &[String],
    time_input: usize,
    path: &Path,
) -> Result<(InferenceModel, Vec<Option<Tensor>>), ImportError> {
    let tract_err = tract_error(path);
    let mut zeros = Vec::new();
    for (i, name) in inputs.iter().enumerate() {
        if i == time_input {
            model = model
                .with_input_fact(i, f32::fact([1, 1]).into())
                .map_err(tract_err)?;
            zeros.push(None);
            continue;
        }
        let fact = model.input_fact(i).map_err(tract_err)?;
        let dims: Option<Vec<usize>> = fact
            .shape
            .dims()
            .map(|d| {
                tract_onnx::tract_hir::infer::Factoid::concretize(d)
                    .and_then(|d| d.as_i64())
                    .and_then(|d| usize::try_from(d).ok())
            })
            .collect();
        let dims =
            dims.ok_or_else(|| format_error(path, format!("input `{name}` has no fixed shape")))?;
        // Zeros are allocated for it: a declared shape is not trusted with memory.
        let values = dims.iter().try_fold(1usize, |n, &d| n.checked_mul(d));
        if values.is_none_or(|n| n > MAX_INPUT_VALUES) {
            return Err(format_error(path, format!(
                "input `{name}` declares shape {dims:?}, more than {MAX_INPUT_VALUES} values: not a policy's observation"
            )));
        }
        model = model
            .with_input_fact(i, f32::fact(dims.clone()).into())
            .map_err(tract_err)?;
        zeros.push(Some(Tensor::zero::<f32>(&dims).map_err(tract_err)?));
    }
    Ok((model, zeros))
}

/// The motion outputs must be one value per joint name, and a 3-vector and a quaternion.
fn check_frame_widths(first: &MotionFrame, joint_names: &[String]) -> Result<(), String> {
    if first[0].len() != joint_names.len() || first[1].len() != joint_names.len() {
        return Err(format!(
            "joint_pos has {} values and joint_vel {}, for {} joint names",
            first[0].len(),
            first[1].len(),
            joint_names.len()
        ));
    }
    if first[2].len() != 3 || first[3].len() != 4 {
        return Err(format!(
            "ref_pos_xyz has {} values and ref_quat_xyzw {} (3 and 4 expected)",
            first[2].len(),
            first[3].len()
        ));
    }
    Ok(())
}

/// Per frame, the root position, m, and orientation quaternion (w, x, y, z).
type RootPoses = (Vec<[f64; 3]>, Vec<[f64; 4]>);

/// The root (pelvis) pose of every frame, from the reference body's pose: pelvis = body ·
/// (pelvis → body at that frame's joint angles)⁻¹. Joints the robot lacks are ignored;
/// those the network lacks stay at the default pose.
fn root_poses(
    robot: &RobotModel,
    reference_body: &str,
    joint_names: &[String],
    frames: &[MotionFrame],
) -> Result<RootPoses, String> {
    let to_canonical: Vec<Option<usize>> =
        joint_names.iter().map(|j| robot.joint_index(j)).collect();
    let body = robot.frame_index(reference_body).ok_or_else(|| {
        format!(
            "reference body `{reference_body}` is not a body of {}",
            robot.name
        )
    })?;
    let mut poses = Vec::new();
    let mut root_pos = Vec::with_capacity(frames.len());
    let mut root_quat_wxyz = Vec::with_capacity(frames.len());
    for f in frames {
        let mut q = robot.default_pose();
        for (i, c) in to_canonical.iter().enumerate() {
            if let Some(c) = c {
                q[*c] = f[0][i];
            }
        }
        forward_kinematics(robot, &Isometry3::identity(), &q, &mut poses);
        let body_in_root = frame_pose(robot, &poses, body);
        let (x, y, z, w) = (f[3][0], f[3][1], f[3][2], f[3][3]);
        let world_from_body = Isometry3::from_parts(
            Translation3::new(f[2][0], f[2][1], f[2][2]),
            UnitQuaternion::from_quaternion(Quaternion::new(w, x, y, z)),
        );
        let world_from_root = world_from_body * body_in_root.inverse();
        let t = world_from_root.translation.vector;
        let r = world_from_root.rotation;
        root_pos.push([t.x, t.y, t.z]);
        root_quat_wxyz.push([r.w, r.i, r.j, r.k]);
    }
    Ok((root_pos, root_quat_wxyz))
}

/// Where the motion came from and how it was read.
fn provenance(
    path: &Path,
    n_frames: usize,
    reference_body: &str,
) -> serde_json::Map<String, serde_json::Value> {
    let mut provenance = serde_json::Map::new();
    for (k, v) in [
        ("format", serde_json::json!(FORMAT)),
        ("source_file", serde_json::json!(path.file_name().map(|s| s.to_string_lossy().to_string()))),
        ("frames", serde_json::json!(n_frames)),
        ("reference_body", serde_json::json!(reference_body)),
        ("note", serde_json::json!("motion read from the network's outputs at every time_step; the root pose derived from the reference body's pose through the robot's kinematics; no forces recorded")),
    ] {
        provenance.insert(k.to_string(), v);
    }
    provenance
}
