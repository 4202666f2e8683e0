//! The datasets the binary carries (`data/<name>/`, extracted with the rest of the bundled
//! data), named by a dataset argument: `--dataset sample` (the synthetic sample) or
//! `--dataset real-walks` (TWIST2's ten real human walks, MIT, with their licence).
//!
//! A directory of that name in the working directory wins: the name is only the bundled
//! dataset where no such path exists, so a user's own `./sample` is never shadowed.

use std::path::PathBuf;

/// The bundled datasets' names: each a directory of `data/` with a `manifest.json`.
pub const BUNDLED_DATASETS: [&str; 2] = ["sample", "real-walks"];

/// What each bundled dataset is, in `data list`'s words (the same order as the names).
const BUNDLED_WHAT: [&str; 2] = [
    "synthetic, two sequences of each of the six tasks (data synth's generator)",
    "TWIST2's ten real human walks, retargeted to the G1 (amazon-far/TWIST2, MIT: LICENSE.TWIST2 beside it)",
];

/// A bundled dataset as `data list` shows it.
#[derive(Debug, Clone)]
pub struct BundledDataset {
    /// Its name, as `--dataset` takes it.
    pub name: &'static str,
    /// What it is.
    pub what: &'static str,
    /// The dataset, opened.
    pub dataset: super::Dataset,
}

/// Every bundled dataset, opened for `robot` (a damaged one is an error naming it).
pub fn bundled_datasets(
    robot: &crate::sim::robot::RobotModel,
) -> Result<Vec<BundledDataset>, super::DataError> {
    BUNDLED_DATASETS
        .iter()
        .zip(BUNDLED_WHAT)
        .map(|(&name, what)| {
            Ok(BundledDataset {
                name,
                what,
                dataset: super::Dataset::open(&crate::data_dir().join(name), robot)?,
            })
        })
        .collect()
}

/// The directory of bundled dataset `name`, when it is one.
pub fn bundled_dataset(name: &str) -> Option<PathBuf> {
    BUNDLED_DATASETS
        .contains(&name)
        .then(|| crate::data_dir().join(name))
}

/// A dataset argument as a directory: `arg` as given when such a path exists or it names
/// no bundled dataset, else the bundled dataset of that name. For clap's `value_parser`.
pub fn dataset_arg(arg: &str) -> Result<PathBuf, String> {
    let given = PathBuf::from(arg);
    if given.exists() {
        return Ok(given);
    }
    Ok(bundled_dataset(arg).unwrap_or(given))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bundled_name_is_its_directory_unless_a_path_of_that_name_exists() {
        let walks = dataset_arg("real-walks").unwrap();
        assert!(walks.join("manifest.json").is_file(), "{}", walks.display());
        assert!(walks.join("LICENSE.TWIST2").is_file());
        assert_eq!(
            dataset_arg("no-such-dataset").unwrap(),
            PathBuf::from("no-such-dataset")
        );
        let here = tempfile::tempdir().unwrap();
        let own = here.path().join("sample");
        std::fs::create_dir(&own).unwrap();
        assert_eq!(dataset_arg(own.to_str().unwrap()).unwrap(), own);
    }
}
