//! The per-episode series `crosscheck` compares beyond the records (joint angles of the
//! first seconds, the feet's accumulated slip), kept next to each engine's run as episodes
//! finish (`crosscheck-series.jsonl`, one line per episode, flushed) so that a resumed
//! crosscheck still compares the episodes finished before it was killed — they once came
//! back with blank divergence columns and no warning.

use crate::eval::results::{ResultsError, RunDir};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::io::{BufRead, Write};
use std::path::PathBuf;

pub use crate::eval::EpisodeKey;

/// Per episode, a series of vectors (per control step).
pub type SeriesByEpisode = BTreeMap<EpisodeKey, Vec<Vec<f64>>>;

#[derive(Serialize, Deserialize)]
struct Line {
    task: String,
    sequence_id: String,
    setting: String,
    /// Joint angles of the first seconds, rad, per control step.
    first_q: Vec<Vec<f64>>,
    /// Accumulated slip per foot, m, per control step.
    foot_slip_m: Vec<Vec<f64>>,
}

/// The series of one engine's run: those kept by an earlier attempt, and the file new
/// ones are appended to.
pub struct SeriesLog {
    path: PathBuf,
    file: std::fs::File,
    /// Joint angles of the first seconds, by episode.
    pub first_q: SeriesByEpisode,
    /// Accumulated foot slip, by episode.
    pub foot_slip_m: SeriesByEpisode,
    /// Lines of an earlier attempt that could not be read (1-based line, why): their
    /// episodes' series are dropped.
    pub dropped_lines: Vec<(usize, String)>,
}

impl SeriesLog {
    /// Opens `dir`'s series: read back and appended to when `resume`, else started afresh.
    /// A last line cut short by a kill is dropped (its episode runs again), and so is an
    /// unreadable line (counted in [`Self::dropped_lines`]).
    pub fn open(run: &RunDir, resume: bool) -> Result<Self, ResultsError> {
        let dir = run.path();
        std::fs::create_dir_all(dir).map_err(ResultsError::io(dir))?;
        let path = run.crosscheck_series_file();
        let mut dropped_lines = Vec::new();
        let mut first_q = SeriesByEpisode::new();
        let mut foot_slip_m = SeriesByEpisode::new();
        let mut kept = Vec::new();
        if resume && path.exists() {
            // As generous as an episode log: a line per episode.
            let file = crate::files::bounded_read::open(
                &path,
                "series file",
                crate::eval::results::MAX_EPISODE_LOG_BYTES,
            )
            .map_err(ResultsError::io(&path))?;
            for (i, line) in std::io::BufReader::new(file).lines().enumerate() {
                let line = line.map_err(ResultsError::io(&path))?;
                match serde_json::from_str::<Line>(&line) {
                    Ok(l) => {
                        let key = EpisodeKey {
                            task: l.task,
                            sequence_id: l.sequence_id,
                            setting: l.setting,
                        };
                        first_q.insert(key.clone(), l.first_q);
                        foot_slip_m.insert(key, l.foot_slip_m);
                        kept.push(line);
                    }
                    Err(e) => dropped_lines.push((i + 1, e.to_string())),
                }
            }
        }
        // Rewrite what was kept, without a torn last line, then append.
        let mut file = crate::files::no_follow::create(&path).map_err(ResultsError::io(&path))?;
        for line in &kept {
            writeln!(file, "{line}").map_err(ResultsError::io(&path))?;
        }
        Ok(Self {
            path,
            file,
            first_q,
            foot_slip_m,
            dropped_lines,
        })
    }

    /// Keeps the series of a finished episode from its trace: the joint angles of its
    /// first `seconds` (the divergence window) and its feet's accumulated slip.
    pub fn append_trace(
        &mut self,
        key: EpisodeKey,
        trace: &crate::eval::episode::EpisodeTrace,
        seconds: f64,
    ) -> Result<(), ResultsError> {
        let first_q = trace
            .steps
            .iter()
            .take_while(|s| s.time_s <= seconds + 1e-9)
            .map(|s| s.q.clone())
            .collect();
        self.append(key, first_q, trace.foot_slip_m.clone())
    }

    /// Keeps one finished episode's series (written through at once: a kill loses none).
    pub fn append(
        &mut self,
        key: EpisodeKey,
        first_q: Vec<Vec<f64>>,
        foot_slip_m: Vec<Vec<f64>>,
    ) -> Result<(), ResultsError> {
        let EpisodeKey {
            task,
            sequence_id,
            setting,
        } = key.clone();
        let line = Line {
            task,
            sequence_id,
            setting,
            first_q,
            foot_slip_m,
        };
        let text = serde_json::to_string(&line).map_err(|source| ResultsError::Json {
            path: self.path.clone(),
            line: None,
            source,
        })?;
        writeln!(self.file, "{text}").map_err(ResultsError::io(&self.path))?;
        self.first_q.insert(key.clone(), line.first_q);
        self.foot_slip_m.insert(key, line.foot_slip_m);
        Ok(())
    }
}
