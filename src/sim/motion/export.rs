//! Export of a dataset for Python users: one `.npz` per sequence (numpy's own format, no
//! extra package needed) plus `index.json` with the joint names and per-file metadata.

use super::dataset::Dataset;
use super::error::{bad, DataError};
use super::sequence::{Sequence, LEFT, RIGHT};
use npyz::npz::NpzWriter;
use npyz::zip::write::FileOptions;
use npyz::zip::CompressionMethod;
use npyz::WriterBuilder;
use serde_json::json;
use std::path::{Path, PathBuf};

/// Writes `<out>/<task>/<sequence_id>.npz` for every sequence and `<out>/index.json`;
/// returns the files written.
pub fn export_npz(
    ds: &Dataset,
    out: &Path,
    mut progress: impl FnMut(usize, usize),
) -> Result<Vec<PathBuf>, DataError> {
    let mut written = Vec::new();
    let mut index = Vec::new();
    for i in 0..ds.len() {
        let seq = ds.load(i)?;
        let rel = format!("{}/{}.npz", seq.task, seq.sequence_id);
        let path = out.join(&rel);
        write_sequence_npz(&seq, &path)?;
        index.push(json!({
            "file": rel, "task": seq.task, "sequence_id": seq.sequence_id, "fps": seq.fps,
            "frames": seq.n_frames(), "forces_recorded": seq.forces_recorded,
            "force_frame": seq.force_frame, "provenance": seq.provenance,
        }));
        written.push(path);
        progress(i + 1, ds.len());
    }
    let index_path = out.join("index.json");
    let doc = json!({
        "source_dataset_sha256": ds.content_hash(),
        "robot": ds.manifest.robot,
        "joint_names": ds.manifest.joint_names,
        "quaternion": "wxyz",
        "force_frame": "per sequence: sensor (each hand's sensor frame), or world (a grafted history, world axes of the sequence's own reference)",
        "arrays": {
            "fps": "[] float64, Hz",
            "root_pos": "[T,3] float32, m, world, z up",
            "root_quat_wxyz": "[T,4] float32",
            "joint_pos": "[T,J] float32, rad, order = joint_names",
            "joint_vel": "[T,J] float32, rad/s (only if recorded)",
            "force_left_sensor": "[T,3] float32, N, force on the hand, in the sequence's force_frame",
            "force_right_sensor": "[T,3] float32, N",
            "hand_from_sensor_wxyz": "[2,4] float64, left then right",
            "force_point_hand": "[2,3] float64, m, hand frame",
        },
        "sequences": index,
    });
    let text = serde_json::to_string_pretty(&doc)
        .map_err(|e| bad(&index_path, "(document)", e.to_string()))?;
    crate::files::atomic_file::write(&index_path, text + "\n").map_err(|source| DataError::Io {
        path: index_path.clone(),
        source,
    })?;
    written.push(index_path);
    Ok(written)
}

fn write_sequence_npz(seq: &Sequence, path: &Path) -> Result<(), DataError> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(|source| DataError::Io {
            path: dir.to_path_buf(),
            source,
        })?;
    }
    let io = |e: std::io::Error| DataError::Io {
        path: path.to_path_buf(),
        source: e,
    };
    let mut w = NpzWriter::create(path).map_err(io)?;
    let t = seq.n_frames() as u64;
    let j = seq.joint_names.len() as u64;
    let f32s = |rows: &mut dyn Iterator<Item = f64>| rows.map(|v| v as f32).collect::<Vec<f32>>();
    put(&mut w, "fps", &[], &[seq.fps]).map_err(io)?;
    put(
        &mut w,
        "root_pos",
        &[t, 3],
        &f32s(&mut seq.root_pos.iter().flatten().copied()),
    )
    .map_err(io)?;
    put(
        &mut w,
        "root_quat_wxyz",
        &[t, 4],
        &f32s(&mut seq.root_quat_wxyz.iter().flatten().copied()),
    )
    .map_err(io)?;
    put(
        &mut w,
        "joint_pos",
        &[t, j],
        &f32s(&mut seq.joint_pos.iter().flatten().copied()),
    )
    .map_err(io)?;
    if let Some(v) = &seq.joint_vel {
        put(
            &mut w,
            "joint_vel",
            &[t, j],
            &f32s(&mut v.iter().flatten().copied()),
        )
        .map_err(io)?;
    }
    put(
        &mut w,
        "force_left_sensor",
        &[t, 3],
        &f32s(&mut seq.force_sensor[LEFT].iter().flatten().copied()),
    )
    .map_err(io)?;
    put(
        &mut w,
        "force_right_sensor",
        &[t, 3],
        &f32s(&mut seq.force_sensor[RIGHT].iter().flatten().copied()),
    )
    .map_err(io)?;
    put(
        &mut w,
        "hand_from_sensor_wxyz",
        &[2, 4],
        seq.hand_from_sensor_wxyz.as_flattened(),
    )
    .map_err(io)?;
    put(
        &mut w,
        "force_point_hand",
        &[2, 3],
        seq.force_point_hand.as_flattened(),
    )
    .map_err(io)?;
    w.zip_writer()
        .finish()
        .map_err(|e| io(std::io::Error::other(e)))?;
    Ok(())
}

fn put<T: npyz::AutoSerialize + Copy>(
    w: &mut NpzWriter<std::io::BufWriter<std::fs::File>>,
    name: &str,
    shape: &[u64],
    data: &[T],
) -> std::io::Result<()> {
    let opts = FileOptions::default().compression_method(CompressionMethod::Stored);
    let mut a = w
        .array::<T>(name, opts)?
        .default_dtype()
        .shape(shape)
        .begin_nd()?;
    a.extend(data.iter().copied())?;
    a.finish()
}
