//! What a sweep's collected cell holds: its shards merged into one run, and what the
//! shards' policy I/O adds up to — what `results.csv` and the sweep's report read.

use crate::eval::results::{read_shards, ResultsError, RunDir, Summary};
use crate::eval::task_thresholds;
use crate::sim::motion::Sequence;
use std::path::PathBuf;

/// The policy's faults summed over a cell's shards.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CellFaults {
    /// Control steps whose actions missed the budget.
    pub deadline_misses: u64,
    /// Control steps with unusable actions.
    pub invalid_actions: u64,
    /// Times the policy process died or left.
    pub policy_failures: u64,
}

/// Latency percentiles of a cell's policy, µs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CellLatency {
    /// Median.
    pub p50_us: f64,
    /// 99th percentile.
    pub p99_us: f64,
    /// 99.9th percentile.
    pub p999_us: f64,
}

/// What a cell's collected run holds.
#[derive(Debug)]
pub struct CellResult {
    /// The cell's merged run directory.
    pub dir: PathBuf,
    /// Episodes in it.
    pub episodes: usize,
    /// Every planned episode of the cell is there, none cut short.
    pub complete: bool,
    /// Its scores.
    pub summary: Summary,
    /// Summed over shards.
    pub faults: CellFaults,
    /// Of a single-shard cell (shards keep separate histograms, which do not add up).
    pub latency: Option<CellLatency>,
}

impl CellResult {
    /// Merges the done `shards` of a cell planning `expected` episodes into `out`, scored
    /// against the cell's own sequences of `sequences` (its dataset, loaded).
    pub fn collect(
        shards: &[RunDir],
        out: &RunDir,
        sequences: &[Sequence],
        expected: usize,
    ) -> Result<Self, ResultsError> {
        let read = read_shards(shards)?;
        let header = read.header.clone();
        let thresholds = task_thresholds(&header.planned_sequences(sequences), header.control_dt_s);
        let summary = out.rewrite(&header, &mut read.into_records(), thresholds)?;
        let mut faults = CellFaults::default();
        let mut latency = None;
        for shard in shards {
            let Some(io) = shard.read_summary()?.policy_io else {
                continue;
            };
            faults.deadline_misses += io.deadline_misses;
            faults.invalid_actions += io.invalid_actions;
            faults.policy_failures += io.transport.map_or(0, |t| t.policy_failures);
            if shards.len() == 1 {
                let l = io.latency;
                latency = Some(CellLatency {
                    p50_us: l.p50_us,
                    p99_us: l.p99_us,
                    p999_us: l.p999_us,
                });
            }
        }
        Ok(Self {
            dir: out.path().to_path_buf(),
            episodes: summary.episodes,
            complete: summary.episodes == expected && summary.complete,
            summary,
            faults,
            latency,
        })
    }
}
