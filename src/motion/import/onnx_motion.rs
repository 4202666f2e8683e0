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
use crate::robot::{forward_kinematics, frame_pose, RobotModel};
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};
use std::path::Path;
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
    let format_err = |reason: String| ImportError::Format {
        path: path.to_path_buf(),
        format: FORMAT,
        reason,
    };
    let tract_err = |e: TractError| format_err(format!("{e:#}"));
    if !path.exists() {
        return Err(ImportError::Io {
            path: path.to_path_buf(),
            source: std::io::Error::from(std::io::ErrorKind::NotFound),
        });
    }
    let model = onnx().model_for_path(path).map_err(tract_err)?;
    let props: std::collections::HashMap<String, String> = model
        .properties
        .iter()
        .filter_map(|(k, v)| {
            let key = k.strip_prefix("onnx.metadata_props.")?;
            let plain = v.try_as_plain_ram().ok()?;
            Some((key.to_string(), plain.to_scalar::<String>().ok()?.clone()))
        })
        .collect();
    let meta = crate::policy::beyondmimic::FileMetadata::from_props(&props).map_err(format_err)?;
    let label = |o: &OutletId| {
        model
            .outlet_label(*o)
            .map(str::to_string)
            .unwrap_or_else(|| model.node(o.node).name.clone())
    };
    let inputs: Vec<String> = model
        .input_outlets()
        .map_err(tract_err)?
        .iter()
        .map(label)
        .collect();
    let outputs: Vec<String> = model
        .output_outlets()
        .map_err(tract_err)?
        .iter()
        .map(label)
        .collect();
    let missing: Vec<&str> = MOTION_OUTPUTS
        .iter()
        .copied()
        .filter(|m| !outputs.iter().any(|o| o == m))
        .collect();
    if !missing.is_empty() {
        return Err(format_err(format!(
            "the network has no motion outputs {missing:?} (it has {outputs:?}): only networks with their reference motion embedded can be imported"
        )));
    }
    let Some(time_input) = inputs.iter().position(|i| i == "time_step") else {
        return Err(format_err(format!(
            "the network has no `time_step` input (it has {inputs:?})"
        )));
    };
    // Every other input (the observation) is fed zeros: the motion outputs depend on the
    // step alone.
    let mut model = model;
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
        let dims = dims.ok_or_else(|| format_err(format!("input `{name}` has no fixed shape")))?;
        // Zeros are allocated for it: a declared shape is not trusted with memory.
        let values = dims.iter().try_fold(1usize, |n, &d| n.checked_mul(d));
        if values.is_none_or(|n| n > MAX_INPUT_VALUES) {
            return Err(format_err(format!(
                "input `{name}` declares shape {dims:?}, more than {MAX_INPUT_VALUES} values: not a policy's observation"
            )));
        }
        model = model
            .with_input_fact(i, f32::fact(dims.clone()).into())
            .map_err(tract_err)?;
        zeros.push(Some(Tensor::zero::<f32>(&dims).map_err(tract_err)?));
    }
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
    let [jp, jv, rp, rq] = MOTION_OUTPUTS.map(slot);
    let eval = |step: usize| -> Result<Vec<Vec<f64>>, ImportError> {
        let feed: TVec<TValue> = zeros
            .iter()
            .map(|z| match z {
                Some(t) => Ok(t.clone().into()),
                None => Tensor::from_shape(&[1, 1], &[step as f32]).map(Into::into),
            })
            .collect::<TractResult<_>>()
            .map_err(tract_err)?;
        let out = plan.run(feed).map_err(tract_err)?;
        [jp, jv, rp, rq]
            .iter()
            .map(|&i| {
                let view = out[i].to_plain_array_view::<f32>().map_err(tract_err)?;
                Ok(view.iter().map(|&v| f64::from(v)).collect())
            })
            .collect()
    };

    let mut frames: Vec<Vec<Vec<f64>>> = Vec::new();
    let mut unchanged = 0usize;
    let mut step = 0usize;
    loop {
        if step > MAX_STEPS {
            return Err(format_err(format!(
                "the motion outputs still change after {MAX_STEPS} steps: not a clamped, embedded motion"
            )));
        }
        let f = eval(step)?;
        if let Some(k) = f.iter().position(|v| v.iter().any(|x| !x.is_finite())) {
            return Err(format_err(format!(
                "output `{}` is not finite at step {step}",
                MOTION_OUTPUTS[k]
            )));
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
    let joint_names: Vec<String> = meta
        .joint_names
        .unwrap_or_else(|| robot.joints.iter().map(|j| j.name.clone()).collect());
    let first = &frames[0];
    if first[0].len() != joint_names.len() || first[1].len() != joint_names.len() {
        return Err(format_err(format!(
            "joint_pos has {} values and joint_vel {}, for {} joint names",
            first[0].len(),
            first[1].len(),
            joint_names.len()
        )));
    }
    if first[2].len() != 3 || first[3].len() != 4 {
        return Err(format_err(format!(
            "ref_pos_xyz has {} values and ref_quat_xyzw {} (3 and 4 expected)",
            first[2].len(),
            first[3].len()
        )));
    }
    let to_canonical: Vec<Option<usize>> =
        joint_names.iter().map(|j| robot.joint_index(j)).collect();
    let body = robot.frame_index(reference_body).ok_or_else(|| {
        format_err(format!(
            "reference body `{reference_body}` is not a body of {}",
            robot.name
        ))
    })?;
    let mut poses = Vec::new();
    let mut root_pos = Vec::with_capacity(frames.len());
    let mut root_quat_wxyz = Vec::with_capacity(frames.len());
    for f in &frames {
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
    let mut provenance = serde_json::Map::new();
    for (k, v) in [
        ("format", serde_json::json!(FORMAT)),
        ("source_file", serde_json::json!(path.file_name().map(|s| s.to_string_lossy().to_string()))),
        ("frames", serde_json::json!(frames.len())),
        ("reference_body", serde_json::json!(reference_body)),
        ("note", serde_json::json!("motion read from the network's outputs at every time_step; the root pose derived from the reference body's pose through the robot's kinematics; no forces recorded")),
    ] {
        provenance.insert(k.to_string(), v);
    }
    Ok(RawMotion {
        fps: 1.0 / control_dt_s,
        root_pos,
        root_quat_wxyz,
        joint_names,
        joint_pos: frames.iter().map(|f| f[0].clone()).collect(),
        joint_vel: Some(frames.iter().map(|f| f[1].clone()).collect()),
        provenance,
    })
}
