//! The synthetic dataset written to disk: generated, then stored as a canonical dataset,
//! replacing an earlier one only when asked to (and then only its own files).

use super::{synthesize, SynthError, SynthOptions};
use crate::sim::motion::{DataError, Dataset, DatasetWriter, Manifest, Sequence, MANIFEST};
use crate::sim::robot::RobotModel;
use std::path::{Path, PathBuf};

/// Why the synthetic dataset was not written.
#[derive(Debug, thiserror::Error)]
pub enum SynthWriteError {
    /// A number of sequences per task that is none, or more than anyone needs.
    #[error("`option.per_task` {0}: give 1 to {MAX_PER_TASK} sequences per task")]
    PerTask(usize),
    /// The directory holds a dataset and replacing it was not asked for.
    #[error("{} already holds a dataset; it is replaced only when asked to", .0.display())]
    Exists(PathBuf),
    /// The old dataset's manifest lists a file outside its directory.
    #[error("{}: refusing to delete `{file}` outside the dataset", .manifest.display())]
    OutsideDataset {
        /// The manifest.
        manifest: PathBuf,
        /// The file it lists.
        file: String,
    },
    /// Generation failed.
    #[error(transparent)]
    Synth(#[from] SynthError),
    /// The dataset could not be read, removed or written.
    #[error(transparent)]
    Data(#[from] DataError),
}

/// The most sequences per task a synthetic dataset holds (the paper has 60; a million
/// sequences would be ~100 GB).
pub const MAX_PER_TASK: usize = 100_000;

/// Generates the sequences `opts` asks for and writes them as a dataset in `out`
/// (`replace`: an existing dataset there is removed first); returns the dataset and the
/// sequences.
pub fn write_synthetic(
    out: &Path,
    robot: &RobotModel,
    opts: &SynthOptions,
    replace: bool,
    progress: impl FnMut(usize, usize),
) -> Result<(Dataset, Vec<Sequence>), SynthWriteError> {
    if !(1..=MAX_PER_TASK).contains(&opts.per_task) {
        return Err(SynthWriteError::PerTask(opts.per_task));
    }
    if out.join(MANIFEST).exists() {
        if !replace {
            return Err(SynthWriteError::Exists(out.to_path_buf()));
        }
        remove_dataset(out)?;
    }
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| DataError::Io { path, source }
    };
    std::fs::create_dir_all(out).map_err(io(out))?;
    let seqs = synthesize(robot, opts, progress)?;
    let mut writer = DatasetWriter::create(out, robot)?;
    for s in &seqs {
        writer.add(s)?;
    }
    Ok((writer.finish()?, seqs))
}

/// Removes a dataset's manifest and the sequence files it lists (nothing else in `dir`).
fn remove_dataset(dir: &Path) -> Result<(), SynthWriteError> {
    let path = dir.join(MANIFEST);
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| DataError::Io { path, source }
    };
    let text = std::fs::read_to_string(&path).map_err(io(&path))?;
    let manifest: Manifest = serde_json::from_str(&text).map_err(|e| DataError::BadField {
        path: path.clone(),
        field: "(file)".into(),
        reason: e.to_string(),
    })?;
    for e in &manifest.sequences {
        if Path::new(&e.file).is_absolute() || e.file.split('/').any(|c| c == "..") {
            return Err(SynthWriteError::OutsideDataset {
                manifest: path,
                file: e.file.clone(),
            });
        }
        let f = dir.join(&e.file);
        if f.exists() {
            std::fs::remove_file(&f).map_err(io(&f))?;
        }
    }
    std::fs::remove_file(&path).map_err(io(&path))?;
    Ok(())
}
