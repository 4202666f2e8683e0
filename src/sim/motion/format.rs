//! A sequence on disk: one safetensors file of float32 tensors, with the sequence's
//! metadata as a single JSON string (safetensors keeps metadata in a hash map, so one key
//! keeps the header byte-for-byte deterministic).
//!
//! The tensors are `root_pos`, `root_quat_wxyz`, `joint_pos` (canonical joint order),
//! optionally `joint_vel`, and `force_left_sensor`, `force_right_sensor` (each hand's
//! force in its sensor frame); the metadata's key is `thorarena`. On disk f32, in memory
//! f64: files stay small and mmap-friendly for Python, and every computation on them
//! (interpolation, differences, kinematics) runs in f64.

use super::error::{bad, DataError};
use super::sequence::{ForceFrame, Sequence, LEFT, RIGHT};
use safetensors::{Dtype, SafeTensors, View};
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::path::Path;

/// Version of the on-disk schema (manifest and sequence files).
pub const SCHEMA_VERSION: u32 = 1;
/// The safetensors metadata key holding [`SequenceMeta`].
const META_KEY: &str = "thorarena";

/// Sequence metadata stored beside the tensors.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SequenceMeta {
    schema_version: u32,
    task: String,
    sequence_id: String,
    fps: f64,
    joint_names: Vec<String>,
    hand_from_sensor_wxyz: [[f64; 4]; 2],
    force_point_hand: [[f64; 3]; 2],
    forces_recorded: bool,
    /// Left out for sensor-frame forces, so every file written before it is unchanged.
    #[serde(default, skip_serializing_if = "ForceFrame::is_sensor")]
    force_frame: ForceFrame,
    provenance: serde_json::Value,
}

/// An owned float32 tensor for serialization.
struct F32Tensor {
    shape: Vec<usize>,
    bytes: Vec<u8>,
}

impl F32Tensor {
    fn new<'a>(shape: Vec<usize>, values: impl Iterator<Item = &'a f64>) -> Self {
        let bytes = values.flat_map(|v| (*v as f32).to_le_bytes()).collect();
        Self { shape, bytes }
    }
}

impl View for &F32Tensor {
    fn dtype(&self) -> Dtype {
        Dtype::F32
    }
    fn shape(&self) -> &[usize] {
        &self.shape
    }
    fn data(&self) -> std::borrow::Cow<'_, [u8]> {
        std::borrow::Cow::Borrowed(&self.bytes)
    }
    fn data_len(&self) -> usize {
        self.bytes.len()
    }
}

/// Serializes a validated sequence; returns the bytes to write.
pub fn encode_sequence(seq: &Sequence, file: &Path) -> Result<Vec<u8>, DataError> {
    seq.validate(file)?;
    let t = seq.n_frames();
    let j = seq.joint_names.len();
    let mut tensors: Vec<(&str, F32Tensor)> = vec![
        (
            "root_pos",
            F32Tensor::new(vec![t, 3], seq.root_pos.iter().flatten()),
        ),
        (
            "root_quat_wxyz",
            F32Tensor::new(vec![t, 4], seq.root_quat_wxyz.iter().flatten()),
        ),
        (
            "joint_pos",
            F32Tensor::new(vec![t, j], seq.joint_pos.iter().flatten()),
        ),
        (
            "force_left_sensor",
            F32Tensor::new(vec![t, 3], seq.force_sensor[LEFT].iter().flatten()),
        ),
        (
            "force_right_sensor",
            F32Tensor::new(vec![t, 3], seq.force_sensor[RIGHT].iter().flatten()),
        ),
    ];
    if let Some(v) = &seq.joint_vel {
        tensors.push(("joint_vel", F32Tensor::new(vec![t, j], v.iter().flatten())));
    }
    let meta = SequenceMeta {
        schema_version: SCHEMA_VERSION,
        task: seq.task.clone(),
        sequence_id: seq.sequence_id.clone(),
        fps: seq.fps,
        joint_names: seq.joint_names.clone(),
        hand_from_sensor_wxyz: seq.hand_from_sensor_wxyz,
        force_point_hand: seq.force_point_hand,
        forces_recorded: seq.forces_recorded,
        force_frame: seq.force_frame,
        provenance: seq.provenance.clone(),
    };
    let meta_json =
        serde_json::to_string(&meta).map_err(|e| bad(file, "metadata", e.to_string()))?;
    let info = HashMap::from([(META_KEY.to_string(), meta_json)]);
    safetensors::serialize(tensors.iter().map(|(n, t)| (*n, t)), Some(info))
        .map_err(|e| bad(file, "tensors", e.to_string()))
}

/// Writes a sequence file; returns its sha256 (hex).
pub fn write_sequence(seq: &Sequence, path: &Path) -> Result<String, DataError> {
    let bytes = encode_sequence(seq, path)?;
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(|source| DataError::Io {
            path: dir.to_path_buf(),
            source,
        })?;
    }
    crate::files::atomic_file::write(path, &bytes).map_err(|source| DataError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    Ok(sha256_hex(&bytes))
}

pub use crate::files::content_hash::sha256_hex;

/// Decodes and validates a sequence file's bytes.
pub fn decode_sequence(bytes: &[u8], file: &Path) -> Result<Sequence, DataError> {
    let not_st = |e: safetensors::SafeTensorError| DataError::NotSafetensors {
        path: file.to_path_buf(),
        reason: e.to_string(),
    };
    let (_, header) = SafeTensors::read_metadata(bytes).map_err(not_st)?;
    let tensors = SafeTensors::deserialize(bytes).map_err(not_st)?;
    let meta_json = header
        .metadata()
        .as_ref()
        .and_then(|m| m.get(META_KEY))
        .ok_or_else(|| {
            bad(
                file,
                "metadata",
                format!("no `{META_KEY}` metadata: not a ThorArena sequence"),
            )
        })?;
    let meta: SequenceMeta = serde_json::from_str(meta_json)
        .map_err(|e| bad(file, "metadata", format!("invalid: {e}")))?;
    if meta.schema_version != SCHEMA_VERSION {
        return Err(DataError::SchemaVersion {
            path: file.to_path_buf(),
            found: meta.schema_version.into(),
            supported: SCHEMA_VERSION,
        });
    }
    let j = meta.joint_names.len();
    let read = |name: &str, width: usize| -> Result<Vec<Vec<f64>>, DataError> {
        let view = tensors
            .tensor(name)
            .map_err(|_| bad(file, name, "tensor missing"))?;
        if view.dtype() != Dtype::F32 {
            return Err(bad(
                file,
                name,
                format!("dtype {:?}, expected F32", view.dtype()),
            ));
        }
        let shape = view.shape();
        if shape.len() != 2 || shape[1] != width {
            return Err(bad(
                file,
                name,
                format!("shape {shape:?}, expected [T, {width}]"),
            ));
        }
        let values: Vec<f64> = view
            .data()
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]) as f64)
            .collect();
        Ok(values.chunks(width).map(<[f64]>::to_vec).collect())
    };
    let fixed = |rows: Vec<Vec<f64>>| -> Vec<[f64; 3]> {
        rows.into_iter().map(|r| [r[0], r[1], r[2]]).collect()
    };
    let joint_vel = match tensors.tensor("joint_vel") {
        Ok(_) => Some(read("joint_vel", j)?),
        Err(_) => None,
    };
    let seq = Sequence {
        task: meta.task,
        sequence_id: meta.sequence_id,
        fps: meta.fps,
        joint_names: meta.joint_names,
        root_pos: fixed(read("root_pos", 3)?),
        root_quat_wxyz: read("root_quat_wxyz", 4)?
            .into_iter()
            .map(|r| [r[0], r[1], r[2], r[3]])
            .collect(),
        joint_pos: read("joint_pos", j)?,
        joint_vel,
        force_sensor: [
            fixed(read("force_left_sensor", 3)?),
            fixed(read("force_right_sensor", 3)?),
        ],
        hand_from_sensor_wxyz: meta.hand_from_sensor_wxyz,
        force_point_hand: meta.force_point_hand,
        forces_recorded: meta.forces_recorded,
        force_frame: meta.force_frame,
        provenance: meta.provenance,
    };
    seq.validate(file)?;
    Ok(seq)
}
