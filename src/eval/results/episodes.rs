//! `episodes.jsonl`: one record per finished episode, appended and flushed as each
//! finishes, so a killed run loses at most the line being written.

use super::{ResultsError, RunHeader};
use crate::eval::EpisodeRecord;
use std::collections::HashSet;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The largest `episodes.jsonl` read, bytes: generous (a record is a few KiB, so this is
/// millions of episodes), there to refuse a sparse or endless file rather than fill memory.
pub const MAX_EPISODE_LOG_BYTES: u64 = 16 << 30;

/// The records of a run, read back and checked against its header.
#[derive(Debug, Clone, Default)]
pub struct EpisodeLog {
    /// The file read.
    pub path: PathBuf,
    /// Every complete record, in file order.
    pub records: Vec<EpisodeRecord>,
    /// Bytes up to the end of the last complete record: where a resumed run cuts the file
    /// before appending.
    pub good_end: u64,
    /// The file ended in a line cut short (a run killed mid-write); it is not a record.
    pub torn_tail: bool,
}

impl EpisodeLog {
    /// Reads `path` (a missing file is an empty log) and checks every record against
    /// `header` ([`RunHeader::check_record`]) and against the others (no episode twice).
    /// Only the last line may be cut short — it is then dropped and flagged in
    /// [`Self::torn_tail`]; any other bad line is an error naming its line.
    pub fn read(path: &Path, header: &RunHeader) -> Result<Self, ResultsError> {
        let mut log = Self {
            path: path.to_path_buf(),
            ..Self::default()
        };
        let bytes =
            match crate::files::bounded_read::read(path, "episode log", MAX_EPISODE_LOG_BYTES) {
                Ok(b) => b,
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(log),
                Err(e) => return Err(ResultsError::io(path)(e)),
            };
        let mut seen = HashSet::new();
        let mut start = 0usize;
        let mut line_no = 0usize;
        while start < bytes.len() {
            line_no += 1;
            let Some(len) = bytes[start..].iter().position(|&b| b == b'\n') else {
                log.torn_tail = true; // the last write was cut short
                break;
            };
            let line = &bytes[start..start + len];
            let bad = |reason: String| ResultsError::BadRecord {
                path: path.to_path_buf(),
                line: line_no,
                reason,
            };
            let record: EpisodeRecord =
                serde_json::from_slice(line).map_err(|source| ResultsError::Json {
                    path: path.to_path_buf(),
                    line: Some(line_no),
                    source,
                })?;
            header.check_record(&record).map_err(bad)?;
            if !seen.insert(record.key()) {
                return Err(bad(format!(
                    "episode {}/{} ({}) is recorded twice",
                    record.task, record.sequence_id, record.setting
                )));
            }
            log.records.push(record);
            start += len + 1;
            log.good_end = start as u64;
        }
        Ok(log)
    }

    /// Rewrites the file with `keep` only (a resume drops a torn tail and episodes to run
    /// again), so appending continues from clean records.
    pub fn rewrite(path: &Path, keep: &[EpisodeRecord]) -> Result<(), ResultsError> {
        let io = ResultsError::io(path);
        // Whole or not at all: a kill mid-way must not cost the records kept.
        let mut text = Vec::new();
        for r in keep {
            write_record(&mut text, r).map_err(ResultsError::io(path))?;
        }
        crate::files::atomic_file::write(path, text).map_err(io)
    }
}

/// Appends a record as one JSON line and flushes (a crash loses nothing finished).
pub fn write_record(out: &mut impl Write, record: &EpisodeRecord) -> std::io::Result<()> {
    serde_json::to_writer(&mut *out, record)?;
    out.write_all(b"\n")?;
    out.flush()
}
