//! Unitree's retargeted LAFAN1 motions (CSV).
//!
//! One frame per line, no header, 36 numbers: root position x y z (m), root orientation
//! as a quaternion in **x y z w** order, then the 29 joint angles (rad) in
//! [`G1_CANONICAL_JOINTS`] order. The file carries no frame rate (the dataset is 30 fps),
//! so the caller passes it.

use std::fs::File;
use std::io::BufReader;
use std::path::Path;

use serde_json::Value;

use super::{ImportError, RawMotion, G1_CANONICAL_JOINTS};

/// Columns per row: root position (3) + quaternion (4) + joints (29).
const COLUMNS: usize = 3 + 4 + G1_CANONICAL_JOINTS.len();

/// Reads a Unitree LAFAN1-retargeted CSV recorded at `fps` (30 for the published dataset).
///
/// Errors name the offending line as `row N` (1-based, as an editor shows it) and, for an
/// unparsable or non-finite number, `row N, column M` (1-based).
pub fn read_lafan_csv(path: &Path, fps: f64) -> Result<RawMotion, ImportError> {
    let bad = |field: String, reason: String| ImportError::BadField {
        path: path.to_path_buf(),
        field,
        reason,
    };
    if !(fps.is_finite() && fps > 0.0) {
        return Err(bad(
            "fps".into(),
            format!("must be a positive number, got {fps}"),
        ));
    }
    let file = File::open(path).map_err(|source| ImportError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    // `flexible` so that a short or long row reaches our own check (and message).
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .trim(csv::Trim::All)
        .from_reader(BufReader::new(file));

    let mut root_pos = Vec::new();
    let mut root_quat_wxyz = Vec::new();
    let mut joint_pos = Vec::new();
    let mut record = csv::ByteRecord::new();
    let mut index = 0u64;
    while let Some(line) = super::next_csv_row(&mut reader, &mut record, &mut index, path)? {
        let row = format!("row {line}");
        if record.len() != COLUMNS {
            return Err(bad(
                row,
                format!("{} columns, expected {COLUMNS}", record.len()),
            ));
        }
        let mut values = [0.0f64; COLUMNS];
        for (col, (slot, raw)) in values.iter_mut().zip(record.iter()).enumerate() {
            *slot = std::str::from_utf8(raw)
                .ok()
                .and_then(|s| s.parse::<f64>().ok())
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    bad(
                        format!("row {line}, column {}", col + 1),
                        format!("not a finite number: {:?}", String::from_utf8_lossy(raw)),
                    )
                })?;
        }
        root_pos.push([values[0], values[1], values[2]]);
        // File order x y z w → w x y z.
        root_quat_wxyz.push([values[6], values[3], values[4], values[5]]);
        joint_pos.push(values[7..].to_vec());
    }
    if joint_pos.is_empty() {
        return Err(ImportError::Format {
            path: path.to_path_buf(),
            format: "LAFAN1 CSV",
            reason: "no rows".into(),
        });
    }

    let mut provenance = serde_json::Map::new();
    provenance.insert("format".into(), Value::from("lafan1-csv"));
    provenance.insert(
        "source_file".into(),
        Value::from(path.display().to_string()),
    );
    provenance.insert("frames".into(), Value::from(joint_pos.len()));
    provenance.insert("source_fps".into(), Value::from(fps));
    provenance.insert("joint_order".into(), Value::from("canonical"));

    Ok(RawMotion {
        fps,
        root_pos,
        root_quat_wxyz,
        joint_names: G1_CANONICAL_JOINTS.map(String::from).to_vec(),
        joint_pos,
        joint_vel: None,
        provenance,
    })
}
