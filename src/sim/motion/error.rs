//! Errors of the canonical dataset format.

use std::path::PathBuf;

/// Why a dataset or sequence could not be read or written. Every variant names the file,
/// and the field where one is at fault; nothing is repaired silently.
#[derive(Debug, thiserror::Error)]
pub enum DataError {
    /// A file could not be read or written.
    #[error("cannot access {path}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// A field holds a value the format does not allow.
    #[error("{path}: field `{field}`: {reason}")]
    BadField {
        /// The file.
        path: PathBuf,
        /// The field (manifest key, tensor name, metadata key).
        field: String,
        /// What is wrong.
        reason: String,
    },
    /// A sequence file's content does not match the checksum in the manifest.
    #[error("{path}: sha256 {actual} does not match the manifest's {expected} (file changed or corrupt)")]
    Checksum {
        /// The sequence file.
        path: PathBuf,
        /// sha256 recorded in the manifest.
        expected: String,
        /// sha256 of the file as read.
        actual: String,
    },
    /// The file is not a safetensors file, or is truncated.
    #[error("{path}: not a readable safetensors file (truncated or another format): {reason}")]
    NotSafetensors {
        /// The file.
        path: PathBuf,
        /// The decoder's explanation.
        reason: String,
    },
    /// The manifest was written by another version of the schema.
    #[error("{path}: schema version {found}, this ThorArena reads version {supported}")]
    SchemaVersion {
        /// The manifest.
        path: PathBuf,
        /// Version found (as written: a huge number is reported, not truncated).
        found: u64,
        /// Version supported.
        supported: u32,
    },
}

pub(crate) fn bad(
    path: &std::path::Path,
    field: impl Into<String>,
    reason: impl Into<String>,
) -> DataError {
    DataError::BadField {
        path: path.to_path_buf(),
        field: field.into(),
        reason: reason.into(),
    }
}
