//! What a sweep's collected cell holds: its shards merged into one run, and what the
//! shards' policy I/O adds up to — what `results.csv` and the sweep's report read.

use crate::results::Summary;
use std::path::PathBuf;

/// What a cell's collected run holds.
pub struct CellResult {
    /// The cell's merged run directory.
    pub dir: PathBuf,
    /// Episodes in it.
    pub episodes: usize,
    /// Every planned episode of the cell is there, none cut short.
    pub complete: bool,
    /// Its scores.
    pub summary: Summary,
    /// Summed over shards: deadline misses, invalid actions, policy failures.
    pub faults: [u64; 3],
    /// p50, p99, p99.9 µs of a single-shard cell (shards keep separate histograms).
    pub latency_us: Option<[f64; 3]>,
}
