//! Loading errors of the robot model.

use std::path::PathBuf;

/// Why a robot description could not be loaded. Every variant names the file, and where
/// it applies the field, so a user can fix the description without reading our code.
#[derive(Debug, thiserror::Error)]
pub enum RobotError {
    /// The robot directory or one of its files could not be read.
    #[error("cannot read {path}")]
    Io {
        /// The file that failed.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// `robot.toml` is not valid TOML or does not match the schema.
    #[error("{path}: {message}")]
    Toml {
        /// The file that failed.
        path: PathBuf,
        /// The parser's explanation (with line and column).
        message: String,
    },
    /// The URDF is not valid XML or not a URDF.
    #[error("{path}: not a valid URDF: {message}")]
    Urdf {
        /// The file that failed.
        path: PathBuf,
        /// The parser's explanation.
        message: String,
    },
    /// A field holds a value that contradicts the rest of the description.
    #[error("{path}: field `{field}`: {reason}")]
    BadField {
        /// The file the field is in.
        path: PathBuf,
        /// The field, as a TOML/URDF path (e.g. `joints[3].name`).
        field: String,
        /// What is wrong with it.
        reason: String,
    },
}
