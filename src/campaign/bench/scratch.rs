//! A benchmark's scratch directory: its sweeps and runs, gone however it ends.

use std::path::{Path, PathBuf};

/// `thorarena-<name>-<pid>` under the system's temporary directory, removed with
/// everything in it when dropped (an error or a panic included).
#[derive(Debug)]
pub struct ScratchDir(PathBuf);

impl ScratchDir {
    /// The directory for benchmark `name` of this process (not created: the benchmark's
    /// first writer does).
    pub fn new(name: &str) -> Self {
        Self(std::env::temp_dir().join(format!("thorarena-{name}-{}", std::process::id())))
    }

    /// Its path.
    pub fn path(&self) -> &Path {
        &self.0
    }
}

impl Drop for ScratchDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}
