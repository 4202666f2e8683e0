//! The synthetic dataset written to disk, one sequence at a time as it is made, replacing
//! an earlier one only when asked to, and then only once its successor is complete.
//!
//! Why beside and then swapped: removing the old dataset first and writing the new one
//! after loses both to a kill or a full disk in between. A replacement is written into a
//! fresh sibling directory (same parent, so on the same file system, created
//! exclusively) and exchanged with the old directory in one `renameat2(RENAME_EXCHANGE)`
//! (two renames where the file system cannot exchange); until then the old dataset is
//! untouched, and a failed write removes only its own directory. Why streamed: a sequence
//! is about 0.2 MB in memory, so holding the documented maximum before writing would
//! take tens of gigabytes; here one sequence is held at a time and the manifest's entries.

use super::{synthesize_each, SynthError, SynthOptions};
use crate::sim::motion::dataset::MAX_MANIFEST_BYTES;
use crate::sim::motion::{DataError, Dataset, DatasetWriter, Manifest, MANIFEST};
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
    /// Writing the replacement failed; the old dataset is as it was.
    #[error("{source}; the dataset in {} is as it was", .dir.display())]
    Replacing {
        /// The dataset directory kept.
        dir: PathBuf,
        /// What failed.
        source: Box<SynthWriteError>,
    },
}

/// The most sequences per task a synthetic dataset holds (the paper has 60; a million
/// sequences would be ~100 GB).
pub const MAX_PER_TASK: usize = 100_000;

/// What a synthesis replaced.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Replaced {
    /// Sequences of the dataset replaced.
    pub sequences: usize,
    /// Files of the old directory that were not the old dataset's and could not be moved
    /// into the new one (a name the new dataset took): where they were left.
    pub left_in: Option<PathBuf>,
}

impl std::fmt::Display for Replaced {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "replaced the dataset of {} sequences", self.sequences)?;
        match &self.left_in {
            Some(dir) => write!(
                f,
                "; files of the old directory whose names the new dataset took are in {}",
                dir.display()
            ),
            None => Ok(()),
        }
    }
}

/// Generates the sequences `opts` asks for and writes them as a dataset in `out`, each
/// as it is made, calling `progress(done, total)` after each is on disk (`replace`: a
/// dataset already in `out` is replaced once the new one is complete, its directory's
/// other files kept). Returns the dataset and, when one was replaced, what was.
pub fn write_synthetic(
    out: &Path,
    robot: &RobotModel,
    opts: &SynthOptions,
    replace: bool,
    mut progress: impl FnMut(usize, usize),
) -> Result<(Dataset, Option<Replaced>), SynthWriteError> {
    if !(1..=MAX_PER_TASK).contains(&opts.per_task) {
        return Err(SynthWriteError::PerTask(opts.per_task));
    }
    // A manifest that is a link, a FIFO or a device counts as there (and is refused when
    // read), so `exists` (which follows links) is not the test.
    if std::fs::symlink_metadata(out.join(MANIFEST)).is_err() {
        std::fs::create_dir_all(out).map_err(io(out))?;
        return Ok((write_into(out, robot, opts, &mut progress)?, None));
    }
    if !replace {
        return Err(SynthWriteError::Exists(out.to_path_buf()));
    }
    let old = old_manifest(out)?;
    // The directory itself (a link to it is the user's path): the swap happens there.
    let real = std::fs::canonicalize(out).map_err(io(out))?;
    let staging = create_sibling(&real)?;
    let written = (|| {
        if let Ok(meta) = std::fs::metadata(&real) {
            std::fs::set_permissions(&staging, meta.permissions()).map_err(io(&staging))?;
        }
        write_into(&staging, robot, opts, &mut progress)
    })();
    let mut ds = match written {
        Ok(ds) => ds,
        Err(e) => {
            let _ = std::fs::remove_dir_all(&staging);
            return Err(SynthWriteError::Replacing {
                dir: out.to_path_buf(),
                source: Box::new(e),
            });
        }
    };
    if let Err(e) = exchange(&staging, &real) {
        let _ = std::fs::remove_dir_all(&staging);
        return Err(SynthWriteError::Replacing {
            dir: out.to_path_buf(),
            source: Box::new(io(&real)(e).into()),
        });
    }
    sync_dir(real.parent().unwrap_or(Path::new("/")));
    // `staging` now holds the old dataset: its own files go, anything else moves back.
    let retired = staging;
    remove_listed(&retired, &old);
    move_back(&retired, &real);
    let left_in = if std::fs::remove_dir(&retired).is_ok() {
        None
    } else {
        Some(retired)
    };
    ds.dir = out.to_path_buf();
    let replaced = Replaced {
        sequences: old.sequences.len(),
        left_in,
    };
    Ok((ds, Some(replaced)))
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> DataError {
    let path = path.to_path_buf();
    move |source| DataError::Io { path, source }
}

/// Streams the sequences into a new dataset in `dir` (which holds no manifest).
fn write_into(
    dir: &Path,
    robot: &RobotModel,
    opts: &SynthOptions,
    progress: &mut impl FnMut(usize, usize),
) -> Result<Dataset, SynthWriteError> {
    let mut writer = DatasetWriter::create(dir, robot)?;
    synthesize_each(robot, opts, |seq, done, total| {
        writer.add(&seq)?;
        progress(done, total);
        Ok::<(), SynthWriteError>(())
    })?;
    Ok(writer.finish()?)
}

/// The old dataset's manifest, read bounded (a FIFO or device is refused, naming it), its
/// files checked to lie inside the directory.
fn old_manifest(dir: &Path) -> Result<Manifest, SynthWriteError> {
    let path = dir.join(MANIFEST);
    let text = crate::files::bounded_read::read_to_string(&path, "manifest", MAX_MANIFEST_BYTES)
        .map_err(io(&path))?;
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
    }
    Ok(manifest)
}

/// How many sibling names a replacement tries before giving up.
const SIBLING_TRIES: u32 = 64;

/// Creates `.<name>.synth-<pid>[-<n>]` beside `dir`, new (never an existing entry or link).
fn create_sibling(dir: &Path) -> Result<PathBuf, DataError> {
    let name = dir
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let pid = std::process::id();
    let mut last = None;
    for n in 0..SIBLING_TRIES {
        let sibling = dir.with_file_name(match n {
            0 => format!(".{name}.synth-{pid}"),
            n => format!(".{name}.synth-{pid}-{n}"),
        });
        match std::fs::create_dir(&sibling) {
            Ok(()) => return Ok(sibling),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => last = Some(e),
            Err(e) => return Err(io(&sibling)(e)),
        }
    }
    Err(io(dir)(last.unwrap_or_else(|| {
        std::io::Error::other("no free name beside it")
    })))
}

/// Exchanges the directories `a` and `b` atomically; where the file system cannot, moves
/// `b` aside, `a` in, and the old `b` to `a`'s name (a failure in between puts `b` back).
fn exchange(a: &Path, b: &Path) -> std::io::Result<()> {
    use std::os::unix::ffi::OsStrExt;
    let c = |p: &Path| {
        std::ffi::CString::new(p.as_os_str().as_bytes())
            .map_err(|_| std::io::Error::new(std::io::ErrorKind::InvalidInput, "a NUL in the path"))
    };
    let (ca, cb) = (c(a)?, c(b)?);
    // SAFETY: two valid NUL-terminated paths, relative to the working directory; the call
    // does not retain them.
    let rc = unsafe {
        libc::renameat2(
            libc::AT_FDCWD,
            ca.as_ptr(),
            libc::AT_FDCWD,
            cb.as_ptr(),
            libc::RENAME_EXCHANGE,
        )
    };
    if rc == 0 {
        return Ok(());
    }
    let e = std::io::Error::last_os_error();
    if !matches!(e.raw_os_error(), Some(libc::EINVAL | libc::ENOSYS)) {
        return Err(e);
    }
    let aside = a.with_file_name(format!(
        "{}.old",
        a.file_name().unwrap_or_default().to_string_lossy()
    ));
    std::fs::rename(b, &aside)?;
    if let Err(e) = std::fs::rename(a, b) {
        let _ = std::fs::rename(&aside, b);
        return Err(e);
    }
    std::fs::rename(&aside, a)
}

/// Removes the manifest and the files it lists from `dir`, then the task directories they
/// leave empty (best effort: what stays is moved back or reported).
fn remove_listed(dir: &Path, manifest: &Manifest) {
    for e in &manifest.sequences {
        let _ = std::fs::remove_file(dir.join(&e.file));
        if let Some(parent) = Path::new(&e.file).parent() {
            if !parent.as_os_str().is_empty() {
                let _ = std::fs::remove_dir(dir.join(parent));
            }
        }
    }
    let _ = std::fs::remove_file(dir.join(MANIFEST));
}

/// Moves what is left in `from` (files that were never the dataset's) to the same place
/// under `to`, where that name is free; directories on both sides are merged.
fn move_back(from: &Path, to: &Path) {
    let Ok(entries) = std::fs::read_dir(from) else {
        return;
    };
    for entry in entries.flatten() {
        let (src, dst) = (entry.path(), to.join(entry.file_name()));
        match std::fs::symlink_metadata(&dst) {
            Err(_) => {
                let _ = std::fs::rename(&src, &dst);
            }
            Ok(d) if d.is_dir() && entry.file_type().is_ok_and(|t| t.is_dir()) => {
                move_back(&src, &dst);
                let _ = std::fs::remove_dir(&src);
            }
            Ok(_) => {}
        }
    }
}

/// Brings a directory's entries to the disk (best effort, as `atomic_file` does).
fn sync_dir(dir: &Path) {
    let dir = if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    };
    if let Ok(d) = std::fs::File::open(dir) {
        let _ = d.sync_all();
    }
}
