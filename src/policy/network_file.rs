//! A network file as a run names it: where it was read, its SHA-256 and its size — the
//! identity `run.json` records, so `merge`, `--resume`, the leaderboard and sweeps never
//! join the episodes of two networks under one label.
//!
//! The bytes are read once and parsed from memory ([`super::network_kernels::load_onnx`]):
//! the hash is of the bytes the policy runs, not of the file read again later, so copying
//! another network over the file mid-run cannot make a run claim a network it did not run.
//! What is read is bounded: anything but a regular file (a directory, a FIFO, `/dev/zero`)
//! is refused before a byte is read, and a file over [`MAX_NETWORK_BYTES`] is refused
//! rather than read into memory.

use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The largest network file read, bytes (1 GiB). The published G1 policies are 0.3–13 MB;
/// a larger ONNX file stores its weights as external data, which is read beside it.
pub const MAX_NETWORK_BYTES: u64 = 1 << 30;

/// Hex digits of a hash shown beside a label (`network 126ab9089b6c`).
pub const SHORT_HASH_DIGITS: usize = 12;

/// A network file, by content.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct NetworkFile {
    /// The path it was read from, as given (for people: two copies of one network in two
    /// places are the same network).
    pub file: String,
    /// SHA-256 of its bytes, lowercase hex.
    pub sha256: String,
    /// Its size, bytes.
    pub bytes: u64,
}

/// Two network files are the same network when their bytes are: the path is not part of
/// the identity.
impl PartialEq for NetworkFile {
    fn eq(&self, other: &Self) -> bool {
        self.sha256 == other.sha256 && self.bytes == other.bytes
    }
}

/// Why a network file could not be read.
#[derive(Debug, thiserror::Error)]
pub enum NetworkFileError {
    /// The file cannot be opened or read, is no regular file, or is over
    /// [`MAX_NETWORK_BYTES`].
    #[error("reading network {}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
}

impl NetworkFile {
    /// Reads `path` whole (bounded, a regular file only) and says what it is by content.
    pub fn read(path: &Path) -> Result<(Vec<u8>, Self), NetworkFileError> {
        let bytes = crate::files::bounded_read::read(path, "network file", MAX_NETWORK_BYTES)
            .map_err(|source| NetworkFileError::Io {
                path: path.to_path_buf(),
                source,
            })?;
        let identity = Self {
            file: path.display().to_string(),
            sha256: crate::files::content_hash::sha256_hex(&bytes),
            bytes: bytes.len() as u64,
        };
        Ok((bytes, identity))
    }

    /// The hash's first [`SHORT_HASH_DIGITS`] digits, as a table shows it.
    pub fn short_hash(&self) -> &str {
        short_hash(&self.sha256)
    }
}

/// The first [`SHORT_HASH_DIGITS`] digits of a hex hash (all of a shorter one).
pub fn short_hash(sha256: &str) -> &str {
    &sha256[..sha256.len().min(SHORT_HASH_DIGITS)]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_network_is_its_bytes_not_its_path() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b, c) = (
            dir.path().join("a.onnx"),
            dir.path().join("b.onnx"),
            dir.path().join("c.onnx"),
        );
        std::fs::write(&a, b"one network").unwrap();
        std::fs::write(&b, b"one network").unwrap();
        std::fs::write(&c, b"another network").unwrap();
        let (bytes, na) = NetworkFile::read(&a).unwrap();
        assert_eq!(bytes, b"one network");
        assert_eq!(na.bytes, 11);
        assert_eq!(na.sha256.len(), 64);
        assert_eq!(na.short_hash().len(), SHORT_HASH_DIGITS);
        assert_eq!(na, NetworkFile::read(&b).unwrap().1);
        assert_ne!(na, NetworkFile::read(&c).unwrap().1);
    }

    #[test]
    fn only_a_regular_file_is_read() {
        let dir = tempfile::tempdir().unwrap();
        let e = NetworkFile::read(dir.path()).unwrap_err().to_string();
        assert!(e.contains("is a directory, not a file"), "{e}");
        let e = NetworkFile::read(Path::new("/dev/zero"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("is a device"), "{e}");
        let fifo = dir.path().join("fifo");
        let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
        // SAFETY: a valid NUL-terminated path; mkfifo does not retain it.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        let e = NetworkFile::read(&fifo).unwrap_err().to_string();
        assert!(e.contains("is a FIFO"), "{e}");
        let e = NetworkFile::read(&dir.path().join("absent.onnx"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("absent.onnx"), "{e}");
    }
}
