//! Shards of one evaluation read back as the single run they add up to (`merge`, a
//! sweep's `collect`): one common header, every episode once, and what no shard holds.

use super::{ResultsError, RunDir, RunHeader};
use crate::eval::{EpisodeKey, EpisodeRecord};
use std::collections::BTreeMap;
use std::path::PathBuf;

/// Why shards cannot be merged.
#[derive(Debug, thiserror::Error)]
pub enum MergeError {
    /// No run was given.
    #[error("no run to merge")]
    NoRuns,
    /// A run of another evaluation than the first.
    #[error("{run} is not a shard of the same evaluation as {first}: it differs in {} ({first}'s first; the network, policy, profile, dataset, keypoints, termination and settings must agree)", differences.join(", "))]
    NotAShard {
        /// The odd run.
        run: PathBuf,
        /// The first run.
        first: PathBuf,
        /// What differs ([`RunHeader::differences`]).
        differences: Vec<String>,
    },
    /// A shard whose last record was cut short.
    #[error("{run}: episodes.jsonl ends in a line cut short (the shard was killed mid-write); resume it (`option.resume`) first")]
    TornShard {
        /// The shard.
        run: PathBuf,
    },
    /// Two shards recorded one episode differently.
    #[error("{run}: episode {key} differs from another shard's")]
    ShardsDisagree {
        /// The shard read second.
        run: PathBuf,
        /// The episode.
        key: EpisodeKey,
    },
    /// Planned episodes that no shard holds.
    #[error("{} episodes are in no shard: {}", missing.len(), missing.iter().take(5).map(ToString::to_string).collect::<Vec<_>>().join(", "))]
    Missing {
        /// Every missing episode, in schedule order.
        missing: Vec<EpisodeKey>,
    },
}

/// The shards of one evaluation, read as one run.
#[derive(Debug)]
pub struct Shards {
    /// The common header, without a shard (the merged run's).
    pub header: RunHeader,
    /// Every episode once.
    pub records: BTreeMap<EpisodeKey, EpisodeRecord>,
}

impl Shards {
    /// The planned episodes of the whole run that no shard holds, in schedule order.
    pub fn missing(&self) -> Vec<EpisodeKey> {
        self.header
            .planned_jobs()
            .into_iter()
            .map(|job| self.header.job_key(job))
            .filter(|k| !self.records.contains_key(k))
            .collect()
    }

    /// The records, in no particular order ([`RunDir::rewrite`] sorts them).
    pub fn into_records(self) -> Vec<EpisodeRecord> {
        self.records.into_values().collect()
    }
}

/// Reads `runs`, shards of one evaluation: every header must agree but for its shard,
/// no shard may end in a torn line, and an episode two shards hold must be recorded
/// identically by both.
pub fn read_shards(runs: &[RunDir]) -> Result<Shards, ResultsError> {
    let first = runs.first().ok_or(MergeError::NoRuns)?;
    let mut header = first.read_header()?;
    let mut records = BTreeMap::new();
    for run in runs {
        let own = run.read_header()?;
        let mut h = own.clone();
        h.shard = header.shard;
        if h != header {
            return Err(MergeError::NotAShard {
                run: run.path().to_path_buf(),
                first: first.path().to_path_buf(),
                differences: header.differences(&h),
            }
            .into());
        }
        let log = run.read_log(&own)?;
        if log.torn_tail {
            return Err(MergeError::TornShard {
                run: run.path().to_path_buf(),
            }
            .into());
        }
        for r in log.records {
            let key = r.key();
            match records.get(&key) {
                Some(existing) if existing != &r => {
                    return Err(MergeError::ShardsDisagree {
                        run: run.path().to_path_buf(),
                        key,
                    }
                    .into())
                }
                _ => {
                    records.insert(key, r);
                }
            }
        }
    }
    header.shard = None;
    Ok(Shards { header, records })
}
