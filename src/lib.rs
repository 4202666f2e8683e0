//! ThorArena scores humanoid whole-body control policies on human motion–force
//! demonstrations: a simulated Unitree G1 tracks a reference motion while recorded hand
//! forces are replayed on its hands.
//!
//! ```
//! use thorarena::robot;
//! let g1 = robot::load_bundled("g1_29dof").unwrap();
//! assert_eq!(g1.n_joints(), 29);
//! ```
#![warn(missing_docs)]

pub mod cli;
pub mod episode;
pub mod metrics;
pub mod motion;
pub mod physics;
pub mod policy;
pub mod profile;
pub mod replay;
pub mod report;
pub mod robot;
pub mod runner;
pub mod scenario;

use std::path::PathBuf;

/// The directory holding robots, profiles and the sample dataset.
///
/// `THORARENA_DATA` overrides it; by default it is the `data/` folder of this source tree,
/// so the binary works from any working directory of a checkout.
pub fn data_dir() -> PathBuf {
    std::env::var_os("THORARENA_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/data")))
}
