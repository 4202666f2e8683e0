//! One rule for every command that writes results or datasets: it never replaces a run or a dataset
//! without `--overwrite`, and never writes over its own inputs, with or without it (the
//! probe found `merge --out` replacing a run, and `report R --out R/episodes.jsonl`
//! writing HTML over the run it read).
//!
//! A run is a directory holding `run.json`; a dataset one holding `manifest.json`. Other
//! existing files — a previous `report.html` — are replaced as before.

use super::run_dir::{RunDir, RUN_FILES};
use crate::sim::motion::MANIFEST;
use std::path::{Path, PathBuf};

/// Why an output was refused. Paths are as given (`out`, `dir`) or resolved (`input`,
/// `holder`).
#[derive(Debug, thiserror::Error)]
pub enum OutputRefused {
    /// The output directory is, lies in or holds an input.
    #[error("`option.out` {} would write over this command's input {}: choose another `option.out`", .out.display(), .input.display())]
    OverInput {
        /// The output.
        out: PathBuf,
        /// The input.
        input: PathBuf,
    },
    /// The output directory holds a run or a dataset.
    #[error("{} already holds {what}: choose another `option.out`, or give `option.overwrite` to replace it", .out.display())]
    Holds {
        /// The output.
        out: PathBuf,
        /// `a run` or `a dataset`.
        what: &'static str,
    },
    /// A run's directory holds a dataset (refused even with `--overwrite`).
    #[error("`option.out` {} holds a dataset: a run is never written over one; choose another `option.out`", .0.display())]
    RunOverDataset(PathBuf),
    /// A run's directory lies inside another run's directory (whose files would mix with
    /// its own, and whose `merge`, `report` and `--resume` would not see it).
    #[error("`option.out` {} lies inside the run {}: a run is never written into another; choose another `option.out`", .out.display(), .run.display())]
    RunInsideRun {
        /// The directory asked for.
        out: PathBuf,
        /// The run it lies in.
        run: PathBuf,
    },
    /// A dataset would be written into a run directory.
    #[error("`option.out` {} holds a run: a dataset is never written over one; choose another `option.out`", .0.display())]
    DatasetOverRun(PathBuf),
    /// An output file names a directory.
    #[error("`option.out` {} is a directory: give a file name", .0.display())]
    FileIsDirectory(PathBuf),
    /// An output file is an input or one of an input run's files.
    #[error("`option.out` {} is part of this command's input {}: choose another `option.out`", .out.display(), .input.display())]
    PartOfInput {
        /// The output.
        out: PathBuf,
        /// The input.
        input: PathBuf,
    },
    /// An output file lies in a run or a dataset.
    #[error("`option.out` {} is a file of {what} ({}): choose another `option.out`, or give `option.overwrite` to replace it", .out.display(), .holder.display())]
    FileOf {
        /// The output.
        out: PathBuf,
        /// `a run` or `a dataset`.
        what: &'static str,
        /// The directory holding it.
        holder: PathBuf,
    },
    /// A file is where the figures directory should be.
    #[error("{} is in the way of the figures directory: it is not a directory", .0.display())]
    FilesDirIsFile(PathBuf),
    /// The figures directory is, lies in or holds an input.
    #[error("the figures directory {} would write over this command's input {}: choose another `option.out`", .dir.display(), .input.display())]
    FilesDirOverInput {
        /// The directory.
        dir: PathBuf,
        /// The input.
        input: PathBuf,
    },
    /// The figures directory holds a run or a dataset.
    #[error("the figures directory {} already holds {what}: choose another `option.out`, or give `option.overwrite` to write into it", .dir.display())]
    FilesDirHolds {
        /// The directory.
        dir: PathBuf,
        /// `a run` or `a dataset`.
        what: &'static str,
    },
}

/// `path` made absolute with symbolic links and `..` resolved, as far as it exists (the
/// output may not exist yet: its nearest existing ancestor is resolved).
fn resolved(path: &Path) -> PathBuf {
    let absolute = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    let mut missing = Vec::new();
    let mut base = absolute.as_path();
    loop {
        if let Ok(real) = base.canonicalize() {
            return missing.iter().rev().fold(real, |p, leaf| p.join(leaf));
        }
        match (base.parent(), base.file_name()) {
            (Some(parent), Some(leaf)) => {
                missing.push(leaf.to_owned());
                base = parent;
            }
            _ => return absolute,
        }
    }
}

/// What a directory holds that must not be replaced silently.
fn holds(dir: &Path) -> Option<&'static str> {
    if RunDir::new(dir).holds_run() {
        Some("a run")
    } else if dir.join(MANIFEST).is_file() {
        Some("a dataset")
    } else {
        None
    }
}

/// Refuses output directory `out` when it is one of `inputs`, lies in one or holds one
/// (always), or already holds a run or a dataset (unless `overwrite`).
pub fn check_dir(out: &Path, overwrite: bool, inputs: &[PathBuf]) -> Result<(), OutputRefused> {
    let target = resolved(out);
    for input in inputs {
        let input = resolved(input);
        if target.starts_with(&input) || input.starts_with(&target) {
            return Err(OutputRefused::OverInput {
                out: out.to_path_buf(),
                input,
            });
        }
    }
    if let Some(what) = holds(out) {
        if !overwrite {
            return Err(OutputRefused::Holds {
                out: out.to_path_buf(),
                what,
            });
        }
    }
    Ok(())
}

/// Refuses a run directory `out` that holds a dataset (always: a run never replaces
/// one), that is, lies in or holds the run's `dataset`, or that holds a run (unless
/// `overwrite`).
pub fn check_run_dir(
    out: &Path,
    overwrite: bool,
    dataset: Option<&Path>,
) -> Result<(), OutputRefused> {
    if out.join(MANIFEST).is_file() {
        return Err(OutputRefused::RunOverDataset(out.to_path_buf()));
    }
    if let Some(run) = resolved(out)
        .ancestors()
        .skip(1)
        .find(|a| RunDir::new(a).holds_run())
    {
        return Err(OutputRefused::RunInsideRun {
            out: out.to_path_buf(),
            run: run.to_path_buf(),
        });
    }
    let inputs: Vec<PathBuf> = dataset.into_iter().map(Path::to_path_buf).collect();
    check_dir(out, overwrite, &inputs)
}

/// Refuses output file `out` when it exists inside one of `inputs` (always), or inside a
/// run or a dataset (unless `overwrite`).
pub fn check_file(out: &Path, overwrite: bool, inputs: &[PathBuf]) -> Result<(), OutputRefused> {
    if out.is_dir() {
        return Err(OutputRefused::FileIsDirectory(out.to_path_buf()));
    }
    let target = resolved(out);
    for input in inputs {
        let input = resolved(input);
        let of_input = match target.strip_prefix(&input) {
            // The input itself (a file), or anything inside an input directory (a run's
            // own files, or a report dropped among them).
            Ok(rest) => {
                rest.as_os_str().is_empty()
                    || RUN_FILES.iter().any(|f| rest.starts_with(f))
                    || input.is_dir()
            }
            Err(_) => false,
        };
        if of_input {
            return Err(OutputRefused::PartOfInput {
                out: out.to_path_buf(),
                input,
            });
        }
    }
    if !out.exists() {
        return Ok(());
    }
    let parent = target.parent().unwrap_or(Path::new("/"));
    if let Some(what) = holds(parent) {
        if !overwrite {
            return Err(OutputRefused::FileOf {
                out: out.to_path_buf(),
                what,
                holder: parent.to_path_buf(),
            });
        }
    }
    Ok(())
}

/// Refuses a directory of output files written beside an output (`report`'s
/// `<stem>-figures/`) as [`check_file`] refuses each of `files` in it, and the directory
/// itself when it is a file, is or holds one of `inputs`, or is part of an input run
/// (always), or holds a run or a dataset (unless `overwrite`).
pub fn check_files_dir(
    dir: &Path,
    files: &[String],
    overwrite: bool,
    inputs: &[PathBuf],
) -> Result<(), OutputRefused> {
    if dir.exists() && !dir.is_dir() {
        return Err(OutputRefused::FilesDirIsFile(dir.to_path_buf()));
    }
    let target = resolved(dir);
    for input in inputs {
        let input = resolved(input);
        let of_input = input.starts_with(&target)
            || target
                .strip_prefix(&input)
                .is_ok_and(|rest| RUN_FILES.iter().any(|f| rest.starts_with(f)));
        if of_input {
            return Err(OutputRefused::FilesDirOverInput {
                dir: dir.to_path_buf(),
                input,
            });
        }
    }
    if let Some(what) = holds(dir) {
        if !overwrite {
            return Err(OutputRefused::FilesDirHolds {
                dir: dir.to_path_buf(),
                what,
            });
        }
    }
    for f in files {
        check_file(&dir.join(f), overwrite, inputs)?;
    }
    Ok(())
}

/// Refuses to write a dataset into `out` when it holds a run.
pub fn check_dataset_dir(out: &Path) -> Result<(), OutputRefused> {
    if RunDir::new(out).holds_run() {
        return Err(OutputRefused::DatasetOverRun(out.to_path_buf()));
    }
    Ok(())
}
