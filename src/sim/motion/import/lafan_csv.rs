//! Retargeted G1 motions as CSV: Unitree's LAFAN1 layout and SoftMimic's, which adds two
//! foot-contact flags.
//!
//! One frame per line, no header: root position x y z (m), root orientation as a
//! quaternion in **x y z w** order, then the 29 joint angles (rad) in
//! [`G1_CANONICAL_JOINTS`] order — 36 numbers. SoftMimic's clips
//! (github.com/Improbable-AI/softmimic, `motions/*.csv`) append the left and right foot
//! contact flags, 38 numbers (1 in contact; the walking clips hold soft values in [0, 1]); its reader
//! (`deploy/motion_lib/motion_lib_from_multi_csv.py`, `feet_contacts=True`) takes the
//! joints in the hardware order, the canonical one here, and drops the flags when a policy
//! does not ask for them. Neither layout carries a frame rate (both datasets are 30 fps,
//! SoftMimic's at `30 · speed`), so the caller passes it.

use std::io::BufReader;
use std::path::Path;

use serde_json::Value;

use super::{ImportError, RawMotion, G1_CANONICAL_JOINTS};

/// Columns of a LAFAN1 row: root position (3) + quaternion (4) + joints (29).
const COLUMNS: usize = 3 + 4 + G1_CANONICAL_JOINTS.len();

/// Which CSV layout a file is read as.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CsvLayout {
    /// Unitree's LAFAN1 retargeting: exactly 36 columns.
    Lafan,
    /// SoftMimic's clips: 38 columns (the two foot-contact flags last), or 36 when a clip
    /// was written without them.
    SoftMimic,
}

impl CsvLayout {
    /// The name errors and provenance use.
    fn format_name(self) -> &'static str {
        match self {
            CsvLayout::Lafan => "LAFAN1 CSV",
            CsvLayout::SoftMimic => "SoftMimic CSV",
        }
    }

    /// The provenance tag.
    fn tag(self) -> &'static str {
        match self {
            CsvLayout::Lafan => "lafan1-csv",
            CsvLayout::SoftMimic => "softmimic-csv",
        }
    }

    /// Whether a row of `n` columns fits, and whether its last two are contact flags.
    fn contact_flags(self, n: usize) -> Option<bool> {
        match (self, n) {
            (_, COLUMNS) => Some(false),
            (CsvLayout::SoftMimic, n) if n == COLUMNS + 2 => Some(true),
            _ => None,
        }
    }

    /// The column counts it accepts, for an error message.
    fn expected(self) -> String {
        match self {
            CsvLayout::Lafan => COLUMNS.to_string(),
            CsvLayout::SoftMimic => format!(
                "{} (with the two foot-contact flags) or {COLUMNS}",
                COLUMNS + 2
            ),
        }
    }

    /// Fewest frames a file must hold: SoftMimic's reader pads shorter clips to 3 frames
    /// (`MIN_FRAMES_PER_FILE`) for its velocity estimates, which would invent a motion;
    /// a LAFAN1 file needs one.
    fn min_frames(self) -> usize {
        match self {
            CsvLayout::Lafan => 1,
            CsvLayout::SoftMimic => 3,
        }
    }
}

/// Reads a Unitree LAFAN1-retargeted CSV recorded at `fps` (30 for the published dataset).
///
/// Errors name the offending line as `row N` (1-based, as an editor shows it) and, for an
/// unparsable or non-finite number, `row N, column M` (1-based).
pub fn read_lafan_csv(path: &Path, fps: f64) -> Result<RawMotion, ImportError> {
    read_retargeted_csv(path, fps, CsvLayout::Lafan)
}

/// Reads a SoftMimic clip (`motions/*.csv` of its repository) played at `fps` (30 for the
/// published clips at speed 1). Every row must have the same layout, and contact flags
/// must lie in [0, 1]; the frames with a flag of at least 0.5 are counted in the
/// provenance, the flags themselves are not kept.
pub fn read_softmimic_csv(path: &Path, fps: f64) -> Result<RawMotion, ImportError> {
    read_retargeted_csv(path, fps, CsvLayout::SoftMimic)
}

/// The numbers of one CSV row into `values`, each finite (`line`: the row's number in
/// messages).
fn row_values(
    record: &csv::ByteRecord,
    line: u64,
    path: &Path,
    values: &mut Vec<f64>,
) -> Result<(), ImportError> {
    values.clear();
    for (col, raw) in record.iter().enumerate() {
        let value = std::str::from_utf8(raw)
            .ok()
            .and_then(|s| s.parse::<f64>().ok())
            .filter(|v| v.is_finite())
            .ok_or_else(|| ImportError::BadField {
                path: path.to_path_buf(),
                field: format!("row {line}, column {}", col + 1),
                reason: format!("not a finite number: {:?}", String::from_utf8_lossy(raw)),
            })?;
        values.push(value);
    }
    Ok(())
}

/// An imported clip's provenance: its format, file, frames, rate, joint order and, when
/// its rows carry contact flags, the frames each foot is in contact.
fn csv_provenance(
    layout: CsvLayout,
    path: &Path,
    frames: usize,
    fps: f64,
    contact_frames: Option<[usize; 2]>,
) -> serde_json::Map<String, Value> {
    let mut provenance = serde_json::Map::new();
    provenance.insert("format".into(), Value::from(layout.tag()));
    provenance.insert(
        "source_file".into(),
        Value::from(path.display().to_string()),
    );
    provenance.insert("frames".into(), Value::from(frames));
    provenance.insert("source_fps".into(), Value::from(fps));
    provenance.insert("joint_order".into(), Value::from("canonical"));
    if let Some([left, right]) = contact_frames {
        provenance.insert(
            "foot_contact_frames".into(),
            serde_json::json!({"left": left, "right": right}),
        );
    }
    provenance
}

/// Reads `path` in `layout` at `fps`.
pub fn read_retargeted_csv(
    path: &Path,
    fps: f64,
    layout: CsvLayout,
) -> Result<RawMotion, ImportError> {
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
    let file = crate::files::bounded_read::open(path, "motion file", super::MAX_IMPORT_BYTES)
        .map_err(|source| ImportError::Io {
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
    let mut with_flags: Option<bool> = None;
    let mut contact_frames = [0usize; 2];
    let mut record = csv::ByteRecord::new();
    let mut index = 0u64;
    let mut values = Vec::with_capacity(COLUMNS + 2);
    while let Some(line) = super::next_csv_row(&mut reader, &mut record, &mut index, path)? {
        let row = format!("row {line}");
        let flags = layout.contact_flags(record.len()).ok_or_else(|| {
            bad(
                row.clone(),
                format!(
                    "{} columns, expected {}{}",
                    record.len(),
                    layout.expected(),
                    if joint_pos.is_empty() {
                        ""
                    } else {
                        " (a row cut short: is the file truncated?)"
                    }
                ),
            )
        })?;
        if *with_flags.get_or_insert(flags) != flags {
            return Err(bad(
                row,
                format!(
                    "{} columns where the rows before have {}: every row must have the same layout",
                    record.len(),
                    if flags { COLUMNS } else { COLUMNS + 2 }
                ),
            ));
        }
        row_values(&record, line, path, &mut values)?;
        root_pos.push([values[0], values[1], values[2]]);
        // File order x y z w → w x y z.
        root_quat_wxyz.push([values[6], values[3], values[4], values[5]]);
        joint_pos.push(values[7..COLUMNS].to_vec());
        for (side, (&flag, count)) in values[COLUMNS..]
            .iter()
            .zip(contact_frames.iter_mut())
            .enumerate()
        {
            if !(0.0..=1.0).contains(&flag) {
                return Err(bad(
                    format!("row {line}, column {}", COLUMNS + side + 1),
                    format!(
                        "the {} foot-contact flag must lie in [0, 1], got {flag}",
                        ["left", "right"][side]
                    ),
                ));
            }
            *count += usize::from(flag >= 0.5);
        }
    }
    if joint_pos.len() < layout.min_frames() {
        return Err(ImportError::Format {
            path: path.to_path_buf(),
            format: layout.format_name(),
            reason: match joint_pos.len() {
                0 => "no rows".into(),
                n => format!(
                    "{n} frame(s), fewer than the {} a clip needs",
                    layout.min_frames()
                ),
            },
        });
    }

    let provenance = csv_provenance(
        layout,
        path,
        joint_pos.len(),
        fps,
        (with_flags == Some(true)).then_some(contact_frames),
    );
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
