//! Turning an importer's [`RawMotion`] into a canonical [`Sequence`]: joints mapped by name
//! into the robot's order, forces resampled onto the motion clock, explicit repairs only.

use super::force_csv::ForceLog;
use super::{ImportError, RawMotion};
use crate::motion::{Sequence, LEFT, QUAT_NORM_TOLERANCE, RIGHT};
use crate::robot::RobotModel;
use serde_json::{json, Value};
use std::path::Path;

/// How to import one motion.
#[derive(Debug, Clone)]
pub struct ImportOptions {
    /// Task name of the sequence.
    pub task: String,
    /// Sequence identifier (by default the input file's stem).
    pub sequence_id: String,
    /// Renormalise root quaternions that are off unit norm (otherwise such a file is
    /// rejected). Recorded in the provenance when it changes anything.
    pub renormalize_quaternions: bool,
    /// Left and right force logs (sensor frame), if recorded.
    pub forces: Option<[ForceLog; 2]>,
    /// Force log time = motion time + this offset, s.
    pub force_offset_s: f64,
    /// Multiplies the logged forces: −1 when the sensor reports the force the hand exerts
    /// on the environment (ThorArena stores the force the environment exerts on the hand).
    pub force_sign: f64,
}

/// Builds the canonical sequence for `robot` from a raw motion read from `source`.
pub fn to_sequence(
    raw: RawMotion,
    robot: &RobotModel,
    opts: &ImportOptions,
    source: &Path,
) -> Result<Sequence, ImportError> {
    let bad = |field: &str, reason: String| ImportError::BadField {
        path: source.to_path_buf(),
        field: field.into(),
        reason,
    };
    let t = raw.root_pos.len();
    if raw.root_quat_wxyz.len() != t || raw.joint_pos.len() != t {
        return Err(bad(
            "frames",
            format!(
                "root_pos {t}, root orientation {}, joint angles {} frames",
                raw.root_quat_wxyz.len(),
                raw.joint_pos.len()
            ),
        ));
    }
    if !(raw.fps.is_finite() && raw.fps > 0.0) {
        return Err(bad("fps", format!("must be > 0, got {}", raw.fps)));
    }
    // Joint columns by name: unknown names are an error; robot joints the file lacks are 0.
    let mut column_of = vec![None; robot.n_joints()];
    for (c, name) in raw.joint_names.iter().enumerate() {
        let j = robot.joint_index(name).ok_or_else(|| {
            bad(
                "joint_names",
                format!("unknown joint `{name}` for robot {}", robot.name),
            )
        })?;
        if column_of[j].replace(c).is_some() {
            return Err(bad("joint_names", format!("`{name}` appears twice")));
        }
    }
    let missing: Vec<&str> = robot
        .joints
        .iter()
        .zip(&column_of)
        .filter(|(_, c)| c.is_none())
        .map(|(j, _)| j.name.as_str())
        .collect();
    let remap = |rows: &[Vec<f64>]| -> Vec<Vec<f64>> {
        rows.iter()
            .map(|r| {
                column_of
                    .iter()
                    .map(|c| c.map_or(0.0, |c| r.get(c).copied().unwrap_or(f64::NAN)))
                    .collect()
            })
            .collect()
    };
    for (k, r) in raw.joint_pos.iter().enumerate() {
        if r.len() != raw.joint_names.len() {
            return Err(bad(
                "joint_pos",
                format!(
                    "frame {k} has {} values for {} joint names",
                    r.len(),
                    raw.joint_names.len()
                ),
            ));
        }
    }
    let mut provenance = raw.provenance.clone();
    if !missing.is_empty() {
        provenance.insert("missing_joints_set_to_zero".into(), json!(missing));
    }

    let mut quats = raw.root_quat_wxyz.clone();
    let mut renormalized = 0usize;
    for (k, q) in quats.iter_mut().enumerate() {
        let n = q.iter().map(|x| x * x).sum::<f64>().sqrt();
        if !n.is_finite() || n < 1e-9 {
            return Err(bad(
                "root orientation",
                format!("frame {k}: not a rotation (norm {n})"),
            ));
        }
        if (n - 1.0).abs() > QUAT_NORM_TOLERANCE {
            if !opts.renormalize_quaternions {
                return Err(bad(
                    "root orientation",
                    format!("frame {k}: quaternion norm {n:.6} (pass --renormalize-quaternions to repair)"),
                ));
            }
            renormalized += 1;
        }
        if opts.renormalize_quaternions {
            q.iter_mut().for_each(|x| *x /= n);
        }
    }
    if renormalized > 0 {
        provenance.insert("renormalized_quaternion_frames".into(), json!(renormalized));
    }

    let times: Vec<f64> = (0..t).map(|k| k as f64 / raw.fps).collect();
    let (force_sensor, forces_recorded) = match &opts.forces {
        Some(logs) => {
            let mut out = [Vec::new(), Vec::new()];
            for side in [LEFT, RIGHT] {
                let (f, outside) = logs[side].resample(&times, opts.force_offset_s);
                out[side] = f
                    .into_iter()
                    .map(|v| v.map(|x| x * opts.force_sign))
                    .collect();
                if outside > 0 {
                    let key = if side == LEFT {
                        "left_force_frames_outside_log"
                    } else {
                        "right_force_frames_outside_log"
                    };
                    provenance.insert(key.into(), json!(outside));
                }
            }
            provenance.insert("force_offset_s".into(), json!(opts.force_offset_s));
            provenance.insert("force_sign".into(), json!(opts.force_sign));
            (out, true)
        }
        None => {
            provenance.insert("forces".into(), json!("none recorded: zero forces"));
            ([vec![[0.0; 3]; t], vec![[0.0; 3]; t]], false)
        }
    };

    let hand_quat = |side: usize| {
        let q = robot.hands[side].hand_from_sensor;
        [q.w, q.i, q.j, q.k]
    };
    let point = |side: usize| {
        let p = robot.hands[side].point_hand;
        [p.x, p.y, p.z]
    };
    let seq = Sequence {
        task: opts.task.clone(),
        sequence_id: opts.sequence_id.clone(),
        fps: raw.fps,
        joint_names: robot.joints.iter().map(|j| j.name.clone()).collect(),
        root_pos: raw.root_pos,
        root_quat_wxyz: quats,
        joint_pos: remap(&raw.joint_pos),
        joint_vel: raw.joint_vel.as_deref().map(remap),
        force_sensor,
        hand_from_sensor_wxyz: [hand_quat(LEFT), hand_quat(RIGHT)],
        force_point_hand: [point(LEFT), point(RIGHT)],
        forces_recorded,
        provenance: Value::Object(provenance),
    };
    seq.validate(source)
        .map_err(|e| bad("(sequence)", e.to_string()))?;
    Ok(seq)
}
