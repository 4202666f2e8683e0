//! The benchmark end to end, above the runner and the run directory: [`evaluate`] takes a
//! checked [`EvalSpec`], a connected policy and a [`RunDir`] and leaves a scored run —
//! resumed if asked, records streamed as episodes finish, traces, `summary.json`,
//! `episodes.csv` and `tables.md`; [`merge`] turns the shards of one evaluation into the
//! run they add up to. The commands (`eval`, `serve`, `merge`, `crosscheck`, a sweep's
//! tasks) only parse, call these and print.

mod crosscheck;
mod evaluation;
mod named_check;
mod progress_lines;
mod recording;

pub use crosscheck::{
    compare_engines, Compared, CrosscheckError, CrosscheckObserver, CrosscheckRequest,
    MAX_BOOTSTRAP,
};
pub use evaluation::{same_policy, Evaluation, OpenError, Place};
pub use named_check::{check_named_policy, PolicyCheckError, PolicyCheckRequest};
pub use progress_lines::ProgressLines;
pub use recording::{Recorded, RunRecording};

use crate::eval::episode::EpisodeTrace;
use crate::eval::results::{
    read_shards, MergeError, PolicyIoReport, ResultsError, RunDir, RunHeader, Started, Summary,
};
use crate::eval::runner::{run_eval, EvalPlan};
use crate::eval::sanity::{
    check_policy, walking_sequence, SanityError, SanityOptions, SanityReport,
};
use crate::eval::{task_thresholds, EpisodeRecord, EvalSpec, SanityRecord, Termination};
use crate::policy::Policy;
use crate::sim::motion::{DataError, Dataset};
use crate::sim::robot::RobotModel;
use std::collections::HashSet;

/// Why an evaluation or a merge could not finish.
#[derive(Debug, thiserror::Error)]
pub enum BenchmarkError {
    /// The run directory could not be read or written.
    #[error(transparent)]
    Results(#[from] ResultsError),
    /// A run resumed under another configuration than the one it was started with.
    #[error("`option.resume`: {0}; use another `option.out`, or `option.overwrite`")]
    ResumedOther(ResultsError),
    /// The dataset of a run could not be read.
    #[error(transparent)]
    Data(#[from] DataError),
    /// Where the run would be written.
    #[error(transparent)]
    Output(#[from] crate::eval::results::OutputRefused),
    /// The dataset changed since its runs ran: they would be scored against other
    /// references.
    #[error("dataset {dataset} changed since the shards ran (content hash differs)")]
    DatasetChanged {
        /// The dataset directory.
        dataset: String,
    },
    /// Where the dataset's forces point could not be measured (for the cells outside the
    /// forces the policy's family was trained with).
    #[error("measuring where the dataset's forces point (to mark the cells outside the policy's training): {0}")]
    ForceSpans(#[from] crate::sim::motion::check::CheckError),
    /// The sanity check could not run.
    #[error("the sanity check could not run: {0}")]
    Sanity(#[from] SanityError),
    /// The profile a policy process declared cannot be the run's.
    #[error("the policy process's profile: {0}")]
    DeclaredProfile(#[from] crate::eval::SpecError),
    /// The policy failed its sanity check: it is refused, its report says why.
    #[error("{policy} failed its sanity check before the run ({}), so its scores would not say how it tracks under force:\n{}\nCheck the policy, its profile and its file (`thorarena policy check`), or give `request.unchecked` to score it anyway (recorded in run.json)", report.failed().join(", "), report.checks.iter().map(|c| format!("  {} {}: {}", if c.passed { "pass" } else { "FAIL" }, c.name, c.detail)).collect::<Vec<_>>().join("\n"))]
    SanityFailed {
        /// The policy's name.
        policy: String,
        /// The check's report.
        report: Box<SanityReport>,
    },
    /// The policy failed mid-run: its finished episodes are written, the rest are not a
    /// result.
    #[error("the policy failed: {cut_short} episodes ended `policy_failed`, {not_run} did not run (finished ones are in {0}; `thorarena eval --resume --out {0}` with a working policy runs both again)", .out.display())]
    PolicyFailed {
        /// Episodes the failure cut short.
        cut_short: usize,
        /// Episodes that never ran.
        not_run: usize,
        /// The run directory.
        out: std::path::PathBuf,
    },
}

/// How [`evaluate`] treats the run directory and what it records beyond the run.
#[derive(Debug, Clone, Copy, Default)]
pub struct EvalOptions {
    /// Keep the finished episodes of a previous run of the same configuration in the
    /// directory and run the rest.
    pub resume: bool,
    /// Hand every episode's first this many seconds to [`EvalObserver::episode`] as a
    /// trace (`crosscheck` compares the engines there); nothing of it is written.
    pub trace_first_s: Option<f64>,
}

/// What a run is about to do, once its directory is started.
#[derive(Debug)]
pub struct Starting<'a> {
    /// The run's header (written).
    pub header: &'a RunHeader,
    /// What the start kept of a previous attempt.
    pub started: &'a Started,
    /// Episodes to run now.
    pub to_run: usize,
}

impl Starting<'_> {
    /// What a run says as it starts: a resume that found nothing to resume or dropped a
    /// torn last line, what `policy` is evaluated on with how many slots and workers, and
    /// how its sanity check went. `resume_asked`: the caller asked to resume; `slots`:
    /// the run's environment slots and workers.
    pub fn news(
        &self,
        policy: &str,
        slots: (usize, usize),
        run: &RunDir,
        resume_asked: bool,
    ) -> Vec<String> {
        let mut news = Vec::new();
        if resume_asked && !self.started.resumed {
            news.push(format!(
                "`option.resume`: nothing to resume in {}, starting afresh",
                run.path().display()
            ));
        }
        if let [first, ..] = self.started.trace_missing.as_slice() {
            news.push(format!(
                "`option.resume`: {} finished episode{} run again, {} trace missing from {} (first: {}/{} {})",
                self.started.trace_missing.len(),
                if self.started.trace_missing.len() == 1 { "" } else { "s" },
                if self.started.trace_missing.len() == 1 { "its" } else { "their" },
                run.traces_dir().display(),
                first.task,
                first.sequence_id,
                first.setting
            ));
        }
        if self.started.torn_tail_dropped {
            news.push(format!(
                "`option.resume`: {} ended in a line cut short; it is dropped",
                run.episodes_file().display()
            ));
        }
        let header = self.header;
        let part = header
            .subset
            .as_ref()
            .map(|sub| format!(" (part of it: {})", sub.describe(header.sequences.len())))
            .unwrap_or_default();
        news.push(format!(
            "evaluating `{policy}` on {}{part}: {} episodes to run ({} already done), {} environment slots on {} workers",
            header.dataset,
            self.to_run,
            self.started.kept.len(),
            slots.0,
            slots.1
        ));
        if let Some(sanity) = &header.sanity {
            news.push(format!("sanity check: {}", sanity.label()));
        }
        news
    }
}

/// Hears an evaluation's progress (the library prints nothing; a command shows it).
pub trait EvalObserver {
    /// The run directory is started and `to_run` episodes are about to run.
    fn starting(&mut self, _starting: &Starting) {}
    /// An episode finished and its record is written; `trace` is its rollout when one was
    /// recorded (a `--trace` sequence, or [`EvalOptions::trace_first_s`]).
    fn episode(&mut self, _record: &EpisodeRecord, _trace: Option<&EpisodeTrace>) {}
    /// What opening the run says: the spec's advice, a policy process's news (serving,
    /// connected, a command started and its log).
    fn note(&mut self, _text: &str) {}
}

/// An observer that hears nothing.
impl EvalObserver for () {}

/// A finished evaluation.
#[derive(Debug)]
pub struct Evaluated {
    /// Its header.
    pub header: RunHeader,
    /// Its scores, as written to `summary.json`.
    pub summary: Summary,
    /// `tables.md`, as written.
    pub tables: String,
    /// Episodes the policy cut short by failing (records ending `policy_failed`).
    pub cut_short: usize,
    /// Episodes that never ran because the policy failed and did not come back.
    pub not_run: usize,
}

impl Evaluated {
    /// A run whose policy failed is not a result, even when every episode has a record;
    /// `--resume` with a working policy runs the missing ones.
    pub fn policy_failed(&self) -> bool {
        self.cut_short > 0 || self.not_run > 0
    }

    /// `Err` when the policy failed ([`Evaluated::policy_failed`]): the exit status of a
    /// command must say so too (sweeps and scripts go by it).
    pub fn check_policy(&self, out: &std::path::Path) -> Result<(), BenchmarkError> {
        if !self.policy_failed() {
            return Ok(());
        }
        Err(BenchmarkError::PolicyFailed {
            cut_short: self.cut_short,
            not_run: self.not_run,
            out: out.to_path_buf(),
        })
    }
}

impl Evaluated {
    /// What a written run says after its tables: the files written, and where the traces
    /// are and how to look at one.
    pub fn written_news(&self, spec: &EvalSpec, run: &RunDir) -> Vec<String> {
        let files: Vec<&str> = crate::eval::results::RUN_FILES
            .iter()
            .filter(|f| **f != crate::eval::results::TRACES_DIR)
            .copied()
            .collect();
        let mut news = vec![format!(
            "wrote {}/{{{}}}",
            run.path().display(),
            files.join(", ")
        )];
        if !spec.trace.is_empty() {
            news.push(format!(
                "traces of {} in {}/<task>-<sequence>-<setting>.json: look at one with `thorarena view FILE`",
                spec.trace.join(", "),
                run.traces_dir().display()
            ));
        }
        news
    }
}

/// The sanity check of `policy` before it is scored (`crate::eval::sanity`), on the walk of
/// the sequences `spec` evaluates (for a single-clip policy: its clip), the run's engine
/// and keypoints: passed, exempt, or not run under `--unchecked`; a failure refuses the run.
fn sanity(spec: &EvalSpec, policy: &mut dyn Policy) -> Result<SanityRecord, BenchmarkError> {
    if let Some(why) = policy.sanity_exempt() {
        return Ok(SanityRecord::Exempt { why: why.into() });
    }
    if spec.unchecked {
        return Ok(SanityRecord::Unchecked);
    }
    let options = SanityOptions {
        engine: spec.engine.clone(),
        keypoints: spec.keypoints.clone(),
        ..SanityOptions::default()
    };
    let Some(walk) = walking_sequence(&spec.sequences, options.track_s) else {
        return Ok(SanityRecord::Exempt {
            why: "no sequence to track".into(),
        });
    };
    let report = check_policy(
        policy,
        &spec.robot,
        &spec.profile,
        &spec.sequences[walk],
        &options,
    )?;
    if !report.passed() {
        return Err(BenchmarkError::SanityFailed {
            policy: policy.name().to_string(),
            report: Box::new(report),
        });
    }
    Ok(SanityRecord::Passed {
        tracking_reference: report.tracking_reference,
    })
}

/// Runs the evaluation `spec` for one connected policy into `run`: starts the directory
/// (resuming with [`EvalOptions::resume`]), runs every planned episode not already
/// finished, appends each record as it finishes, writes the traces asked for, and writes
/// the scores and tables.
pub fn evaluate(
    spec: &EvalSpec,
    policy: &mut dyn Policy,
    run: &RunDir,
    options: EvalOptions,
    observer: &mut dyn EvalObserver,
) -> Result<Evaluated, BenchmarkError> {
    let _writer = run.lock()?;
    // A policy process's declared profile decides the run's (or marks a mismatch).
    let adopted = spec.adopting(policy.profile_declaration())?;
    let spec = &adopted;
    let mut header = RunHeader::of(spec, policy.name());
    header.network_kernels = policy.network_kernels().map(|k| k.isa.clone());
    header.policy_parameters = policy
        .parameters()
        .into_iter()
        .map(|(name, value)| (name.to_string(), value))
        .collect();
    header.identity = Some(crate::eval::results::PolicyIdentity::of(
        policy,
        &spec.profile,
        &spec.robot,
    ));
    if let Some(family) = spec
        .policy
        .as_ref()
        .and_then(|p| p.named())
        .map(|n| n.family())
    {
        header.outside_training = crate::eval::outside_training(
            &family.trained_forces,
            &spec.settings,
            header.policy_parameters.get("stiffness_n_per_m").copied(),
            &spec.sequences,
            &spec.robot,
        )?;
    }
    header.sanity = Some(sanity(spec, policy)?);
    let (mut recording, started) = RunRecording::start(run, spec, header, options.resume)?;
    let header = recording.header();
    let finished: HashSet<_> = started.kept.iter().map(EpisodeRecord::key).collect();
    let jobs: Vec<(usize, usize)> = header
        .planned_jobs()
        .into_iter()
        .filter(|&job| !finished.contains(&header.job_key(job)))
        .collect();
    observer.starting(&Starting {
        header,
        started: &started,
        to_run: jobs.len(),
    });
    let plan = EvalPlan::of(spec, options.trace_first_s);
    let outcome = run_eval(&plan, &spec.sequences, &jobs, policy, &mut |r, trace| {
        recording.record(r, trace.map(|t| t.steps.as_slice()));
        observer.episode(r, trace);
    });
    // Faults are in every record, kept or new; latency percentiles only of this attempt
    // (the run keeps no samples), which the report says when a resume kept episodes.
    let io = PolicyIoReport {
        latency: outcome.latency,
        transport: outcome.transport,
        // Summed over every record, kept or new, by `finish`.
        deadline_misses: 0,
        invalid_actions: 0,
        resumed_episodes: recording.resumed_episodes(),
    };
    let recorded = recording.finish(Some(io), "")?;
    let cut_short = recorded
        .records
        .iter()
        .filter(|r| r.termination == Some(Termination::PolicyFailed))
        .count();
    Ok(Evaluated {
        header: recorded.header,
        summary: recorded.summary,
        tables: recorded.tables,
        cut_short,
        not_run: outcome.not_run,
    })
}

/// A run merged from shards.
#[derive(Debug)]
pub struct Merged {
    /// Its scores.
    pub summary: Summary,
    /// `tables.md`, as written.
    pub tables: String,
}

/// `thorarena merge`: the run directories `runs`, shards of one evaluation, merged into
/// `out` ([`merge`]) — which may replace a run there with `overwrite`, never a shard.
pub fn merge_dirs(
    runs: &[std::path::PathBuf],
    out: &std::path::Path,
    overwrite: bool,
    robot: &RobotModel,
) -> Result<Merged, BenchmarkError> {
    crate::eval::results::check_dir(out, overwrite, runs)?;
    let shards: Vec<RunDir> = runs.iter().map(RunDir::new).collect();
    merge(&shards, &RunDir::new(out), robot)
}

/// Merges `shards`, runs of one evaluation, into `out`: the same records, scores and
/// tables a single run of the whole plan writes. The dataset must be the one they ran
/// (by content), and every planned episode must be in some shard.
pub fn merge(
    shards: &[RunDir],
    out: &RunDir,
    robot: &RobotModel,
) -> Result<Merged, BenchmarkError> {
    let _writer = out.lock()?;
    let read = read_shards(shards)?;
    let header = read.header.clone();
    let ds = Dataset::open(std::path::Path::new(&header.dataset), robot)?;
    if ds.content_hash() != header.dataset_sha256 {
        return Err(BenchmarkError::DatasetChanged {
            dataset: header.dataset.clone(),
        });
    }
    let sequences = header.planned_sequences(&ds.load_all()?);
    let missing = read.missing();
    if !missing.is_empty() {
        return Err(ResultsError::from(MergeError::Missing { missing }).into());
    }
    let mut records = read.into_records();
    let thresholds = task_thresholds(&sequences, header.control_dt_s);
    let summary = out.rewrite(&header, &mut records, thresholds)?;
    let tables = crate::report::write_run_tables(out.path(), &summary)?;
    Ok(Merged { summary, tables })
}
