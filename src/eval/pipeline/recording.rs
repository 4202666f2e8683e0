//! A run being written, from its header to its tables: the one tail every way of running
//! episodes shares. [`RunRecording::start`] writes `run.json` (resuming if asked),
//! [`RunRecording::record`] appends each episode as it finishes — with its trace when the
//! run traces its sequence — and [`RunRecording::finish`] scores every record into
//! `summary.json`, `episodes.csv` and `tables.md`. [`super::evaluate`] drives it with the
//! runner's episodes; a deployment over DDS (`crate::dds::session`) with the one episode
//! its bridge ran in real time. The caller holds the run's writer lock throughout.

use super::BenchmarkError;
use crate::eval::episode::TraceStep;
use crate::eval::results::{
    PolicyIoReport, RecordAppender, ResultsError, RunDir, RunHeader, Started, Summary,
};
use crate::eval::{task_thresholds, EpisodeRecord, EvalSpec};

/// A run started and being written.
pub struct RunRecording<'a> {
    run: &'a RunDir,
    spec: &'a EvalSpec,
    header: RunHeader,
    appender: RecordAppender,
    /// The finished episodes a resume kept, then this attempt's.
    records: Vec<EpisodeRecord>,
    resumed_episodes: usize,
    /// The first write that failed: episodes keep running, the run fails at the end.
    write_error: Option<ResultsError>,
}

/// A finished recording.
#[derive(Debug)]
pub struct Recorded {
    /// The run's header.
    pub header: RunHeader,
    /// Its scores, as written to `summary.json`.
    pub summary: Summary,
    /// `tables.md`, as written.
    pub tables: String,
    /// Every record, kept and new, in schedule order.
    pub records: Vec<EpisodeRecord>,
}

impl<'a> RunRecording<'a> {
    /// Starts `run` for `spec` under `header`: afresh, or with `resume` keeping the
    /// finished episodes of a previous run of the same configuration (another one is
    /// refused, naming what differs). Returns what the start kept.
    pub fn start(
        run: &'a RunDir,
        spec: &'a EvalSpec,
        header: RunHeader,
        resume: bool,
    ) -> Result<(Self, Started), BenchmarkError> {
        let traced = |r: &EpisodeRecord| spec.traces(&r.task, &r.sequence_id);
        let started = run.start(&header, resume, &traced).map_err(|e| match e {
            e @ ResultsError::OtherConfiguration { .. } => BenchmarkError::ResumedOther(e),
            e => e.into(),
        })?;
        let appender = run.appender()?;
        let recording = Self {
            run,
            spec,
            header,
            appender,
            records: started.kept.clone(),
            resumed_episodes: started.kept.len(),
            write_error: None,
        };
        Ok((recording, started))
    }

    /// The run's header, as written.
    pub fn header(&self) -> &RunHeader {
        &self.header
    }

    /// Appends `record` to `episodes.jsonl` and writes `trace` when the run traces its
    /// sequence; a failed write is kept and returned by [`Self::finish`], so the episodes
    /// in flight are not lost to it.
    pub fn record(&mut self, record: &EpisodeRecord, trace: Option<&[TraceStep]>) {
        if let Err(e) = self.appender.append(record) {
            self.write_error.get_or_insert(e);
        }
        if let Some(steps) = trace.filter(|_| self.spec.traces(&record.task, &record.sequence_id)) {
            if let Err(e) = self.run.write_trace(&record.key(), steps) {
                self.write_error.get_or_insert(e);
            }
        }
        self.records.push(record.clone());
    }

    /// How many finished episodes a resume kept.
    pub fn resumed_episodes(&self) -> usize {
        self.resumed_episodes
    }

    /// Flushes the records and scores them (the regime thresholds from the run's
    /// sequences), with the policy's I/O when it has one to report — its fault counts
    /// summed here over every record, kept or new —; `tables.md` gains `more_tables` after
    /// the run's own.
    pub fn finish(
        mut self,
        io: Option<PolicyIoReport>,
        more_tables: &str,
    ) -> Result<Recorded, BenchmarkError> {
        self.appender.flush()?;
        if let Some(e) = self.write_error {
            return Err(e.into());
        }
        let io = io.map(|io| PolicyIoReport {
            deadline_misses: self.records.iter().map(|r| r.faults.deadline_misses).sum(),
            invalid_actions: self.records.iter().map(|r| r.faults.invalid_actions).sum(),
            ..io
        });
        let thresholds = task_thresholds(&self.spec.sequences, self.header.control_dt_s);
        let summary = self
            .run
            .finish(&self.header, &mut self.records, thresholds, io)?;
        let mut tables = crate::report::run_tables(&summary);
        tables.push_str(more_tables);
        let path = self.run.path().join(crate::eval::results::TABLES_FILE);
        crate::files::atomic_file::write(&path, &tables)
            .map_err(|source| ResultsError::Io { path, source })?;
        Ok(Recorded {
            header: self.header,
            summary,
            tables,
            records: self.records,
        })
    }
}
