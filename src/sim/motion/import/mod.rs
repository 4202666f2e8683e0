//! Importers: motion files in the formats users already have, turned into canonical
//! sequences. Each format reader produces a [`RawMotion`]; mapping to the robot's
//! canonical joint order, attaching forces and validating happen once, here.

mod batch;
pub mod bounds;
pub mod canonical;
pub mod force_csv;
pub mod lafan_csv;
pub mod news;
pub mod npz;
pub mod onnx_motion;
mod pickle_depth;
pub mod twist_pkl;

pub use batch::{import_batch, BatchError, ImportBatch, ImportObserver, SourceFormat};

use std::path::PathBuf;

/// The largest input file an importer reads, bytes (1 GiB): hours of motion in any of the
/// formats; a device or FIFO given as an input is refused before it is read.
pub const MAX_IMPORT_BYTES: u64 = 1 << 30;

/// The G1 29-DoF joint order of the Unitree URDF, MJCF and SDK motor indices, which this
/// project treats as canonical (GMR/TWIST pickles and LAFAN CSVs use it too): left leg, right leg, waist, left arm, right arm.
pub const G1_CANONICAL_JOINTS: [&str; 29] = [
    "left_hip_pitch_joint",
    "left_hip_roll_joint",
    "left_hip_yaw_joint",
    "left_knee_joint",
    "left_ankle_pitch_joint",
    "left_ankle_roll_joint",
    "right_hip_pitch_joint",
    "right_hip_roll_joint",
    "right_hip_yaw_joint",
    "right_knee_joint",
    "right_ankle_pitch_joint",
    "right_ankle_roll_joint",
    "waist_yaw_joint",
    "waist_roll_joint",
    "waist_pitch_joint",
    "left_shoulder_pitch_joint",
    "left_shoulder_roll_joint",
    "left_shoulder_yaw_joint",
    "left_elbow_joint",
    "left_wrist_roll_joint",
    "left_wrist_pitch_joint",
    "left_wrist_yaw_joint",
    "right_shoulder_pitch_joint",
    "right_shoulder_roll_joint",
    "right_shoulder_yaw_joint",
    "right_elbow_joint",
    "right_wrist_roll_joint",
    "right_wrist_pitch_joint",
    "right_wrist_yaw_joint",
];

/// A motion as a format reader found it, before it becomes a canonical sequence.
#[derive(Debug, Clone, PartialEq)]
pub struct RawMotion {
    /// Frame rate, Hz.
    pub fps: f64,
    /// Root (pelvis) position per frame, world frame, m, z up.
    pub root_pos: Vec<[f64; 3]>,
    /// Root orientation per frame as (w, x, y, z) — readers convert from the file's order.
    pub root_quat_wxyz: Vec<[f64; 4]>,
    /// Names of the columns of `joint_pos` (robot joint names, e.g. `left_knee_joint`).
    pub joint_names: Vec<String>,
    /// Joint angles per frame, rad, in the order of `joint_names`.
    pub joint_pos: Vec<Vec<f64>>,
    /// Joint velocities per frame if the file has them, rad/s, same order.
    pub joint_vel: Option<Vec<Vec<f64>>>,
    /// What the reader wants recorded about the source (format, file, notes).
    pub provenance: serde_json::Map<String, serde_json::Value>,
}

/// Why a file could not be imported. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum ImportError {
    /// The file could not be read.
    #[error("cannot read {path}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The file's content is not what the format requires.
    #[error("{path}: field `{field}`: {reason}")]
    BadField {
        /// The file.
        path: PathBuf,
        /// The entry or column at fault (e.g. `dof_pos`, `row 12`).
        field: String,
        /// What is wrong.
        reason: String,
    },
    /// The file is not in the expected format at all.
    #[error("{path}: not a {format} file: {reason}")]
    Format {
        /// The file.
        path: PathBuf,
        /// The format expected.
        format: &'static str,
        /// The decoder's explanation.
        reason: String,
    },
    /// The root jumps between consecutive frames farther than a human can move: a
    /// teleoperation glitch. Leading and trailing ones are repaired only on request
    /// (`--trim-glitches`); interior ones never.
    #[error(
        "{path}: sequence `{sequence_id}`: implausible root jump(s) (root speed above {} m/s \
         between consecutive frames): {}; {}",
        crate::sim::motion::MAX_HUMAN_ROOT_SPEED_M_PER_S,
        list_jumps(&.scan.jumps),
        glitch_advice(.scan, *.trim_requested)
    )]
    RootGlitch {
        /// The file.
        path: PathBuf,
        /// The sequence the file would have become.
        sequence_id: String,
        /// The jumps and how they classify.
        scan: crate::sim::motion::GlitchScan,
        /// Whether `--trim-glitches` was given (the glitch is then not trimmable).
        trim_requested: bool,
    },
}

fn list_jumps(jumps: &[crate::sim::motion::RootJump]) -> String {
    let items: Vec<String> = jumps.iter().map(|j| j.to_string()).collect();
    items.join(", ")
}

/// What the user can do about a glitch, given what the scan found.
fn glitch_advice(scan: &crate::sim::motion::GlitchScan, trim_requested: bool) -> String {
    if !scan.interior.is_empty() {
        let at: Vec<String> = scan.interior.iter().map(|j| j.frame.to_string()).collect();
        return format!(
            "the jump(s) at frame {} lie inside the motion (more than {} s from either end), \
             which `option.trim_glitches` does not repair: it only drops leading and trailing \
             glitch frames{}",
            at.join(", "),
            crate::sim::motion::EDGE_GLITCH_WINDOW_S,
            if trim_requested {
                ", so the file is not imported even with it"
            } else {
                ""
            }
        );
    }
    if scan.kept_frames() < 2 {
        return format!(
            "trimming the glitch frames would leave {} of {} frames, too few for a motion",
            scan.kept_frames(),
            scan.frames
        );
    }
    format!(
        "these are teleoperation glitches at the {}; give `option.trim_glitches` to drop {} leading \
         and {} trailing frame(s)",
        match (scan.leading_frames > 0, scan.trailing_frames > 0) {
            (true, true) => "start and the end",
            (true, false) => "start",
            _ => "end",
        },
        scan.leading_frames,
        scan.trailing_frames
    )
}

/// Reads the next CSV record; returns the 1-based file line it came from (rows are named by
/// file line, as an editor shows them: the csv reader skips blank lines), `None` at the end,
/// or a `row N` error.
pub(crate) fn next_csv_row<R: std::io::Read>(
    reader: &mut csv::Reader<R>,
    record: &mut csv::ByteRecord,
    index: &mut u64,
    path: &std::path::Path,
) -> Result<Option<u64>, ImportError> {
    *index += 1;
    match reader.read_byte_record(record) {
        Ok(true) => Ok(Some(record.position().map_or(*index, |p| p.line()))),
        Ok(false) => Ok(None),
        Err(e) => Err(ImportError::BadField {
            path: path.to_path_buf(),
            field: format!("row {}", e.position().map_or(*index, |p| p.line())),
            reason: format!("unreadable CSV: {e}"),
        }),
    }
}
