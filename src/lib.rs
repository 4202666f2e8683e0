//! ThorArena scores humanoid whole-body control policies on human motion–force
//! demonstrations: a simulated Unitree G1 tracks a reference motion while recorded hand
//! forces are replayed on its hands.
//!
//! The library is a handful of rooms, from the ground up: [`files`] (what touches the
//! disk), [`sim`] (the robot, its physics and the motions it tracks), [`policy`] (what
//! drives it, and the names that choose one), [`eval`] (one evaluation, scored and
//! stored), [`report`] (results for people), [`campaign`] (many evaluations: sweeps, the
//! leaderboard, the cost benchmarks) and [`dds`] (the robot's own DDS interface).
//!
//! ```
//! use thorarena::sim::robot;
//! let g1 = robot::load_bundled("g1_29dof").unwrap();
//! assert_eq!(g1.n_joints(), 29);
//! ```
#![warn(missing_docs)]

pub mod campaign;
pub mod dds;
pub mod eval;
pub mod files;
pub mod policy;
pub mod report;
pub mod sim;

use std::path::PathBuf;

/// Environment variable naming a data directory (robots, profiles, sample) to use instead
/// of the bundled one.
pub const DATA_DIR_ENV: &str = "THORARENA_DATA";

/// The directory holding robots, profiles and the sample dataset.
///
/// [`DATA_DIR_ENV`] overrides it (set and not empty: an empty value, as `VAR=` in a script
/// leaves it, is unset, never the working directory). By default it is the copy of `data/` compiled into this
/// binary, written once to a cache directory ([`files::embedded_data`]), so an installed binary
/// needs no checkout and always reads the data it was built with. If no cache directory
/// is writable it falls back to `data/` of the checkout the binary was built from, and a
/// missing file there is reported by whoever reads it, naming the path.
pub fn data_dir() -> PathBuf {
    if let Some(dir) = std::env::var_os(DATA_DIR_ENV).filter(|d| !d.is_empty()) {
        return PathBuf::from(dir);
    }
    files::embedded_data::extracted()
        .unwrap_or_else(|_| PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/data")))
}

/// Environment variable naming the published reference artifacts (docs/policies.md, "Reference
/// artifacts"): the G1 model and TWIST2's MJCF, TWIST2's policy and walks, holosoma's
/// policy. Only checks against real artifacts use them; the benchmark itself does not.
pub const REFERENCE_DIR_ENV: &str = "THORARENA_REFERENCE";

/// The reference artifacts' directory: [`REFERENCE_DIR_ENV`], else `../shared/reference`
/// beside the checkout the binary was built from.
pub fn reference_dir() -> PathBuf {
    std::env::var_os(REFERENCE_DIR_ENV)
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/reference"))
        })
}
