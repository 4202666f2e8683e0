//! `thorarena data check` as one job: the dataset checked (`sim::motion::check`), and with
//! a tracker named, every sequence rolled out by it without force — an ordinary `eval` run
//! into the output directory, resumed when the command runs again — so the check can say
//! which sequences a good tracker cannot hold with no force on it.

use crate::eval::pipeline::{
    BenchmarkError, EvalObserver, Evaluation, OpenError, Place, ProgressLines,
};
use crate::eval::results::{check_dir, OutputRefused, ResultsError, RunDir};
use crate::eval::{EngineChoice, EvalRequest, Setting};
use crate::policy::registry::{self, PolicySource, RegistryError};
use crate::policy::SessionOptions;
use crate::sim::motion::check::held::{SequenceHeld, TrackerHeld};
use crate::sim::motion::check::{
    check_dataset, CheckError, CheckGateError, CheckOptions, CheckWriteError, DatasetCheck,
};
use crate::sim::motion::{DataError, Dataset};
use std::path::PathBuf;

/// The setting the tracker's rollouts run under.
pub const ROLLOUT_SETTING: &str = "no-force";

/// A data check as asked for.
#[derive(Debug, Clone)]
pub struct DataCheckJob {
    /// Dataset directory.
    pub dataset: PathBuf,
    /// Robot name or directory.
    pub robot: String,
    /// How the motions are checked.
    pub options: CheckOptions,
    /// Where `check.md`, `check.json` and the tracker's run go (none: nothing written).
    pub out: Option<PathBuf>,
    /// A tracker (in process) whose rollouts without force join the check; needs `out`.
    pub tracker: Option<PolicySource>,
    /// Engine of the tracker's rollouts.
    pub engine: EngineChoice,
    /// The gate the caller applies afterwards (`DatasetCheck::gate`), checked here
    /// before anything runs or is written.
    pub max_outside: Option<f64>,
}

/// Why a data check could not be made, or did not pass.
#[derive(Debug, thiserror::Error)]
pub enum DataCheckError {
    /// The robot is unknown.
    #[error(transparent)]
    Robot(#[from] RegistryError),
    /// The output directory is refused.
    #[error(transparent)]
    Output(#[from] OutputRefused),
    /// The dataset could not be read.
    #[error(transparent)]
    Data(#[from] DataError),
    /// The motions could not be checked.
    #[error(transparent)]
    Check(#[from] CheckError),
    /// The gate is no share.
    #[error(transparent)]
    Gate(#[from] CheckGateError),
    /// The check's files could not be written.
    #[error(transparent)]
    Write(#[from] CheckWriteError),
    /// The tracker's run would have nowhere to go.
    #[error("`option.rollout` runs an evaluation, kept for `view` and reruns: give `option.out`")]
    RolloutNeedsOut,
    /// The tracker is a policy process: the check's rollouts step it in process.
    #[error("{0} names a policy process; `option.rollout` steps a tracker in process (a built-in or a network file, e.g. twist2:FILE)")]
    RolloutNotInProcess(String),
    /// The tracker's run directory could not be made.
    #[error("making the tracker's run directory {}: {source}", path.display())]
    RolloutDir {
        /// The directory.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The tracker's run could not be opened.
    #[error("the tracker's rollouts: {0}")]
    RolloutOpen(#[from] Box<OpenError>),
    /// The tracker's run failed.
    #[error("the tracker's rollouts: {0}")]
    Rollout(#[from] Box<BenchmarkError>),
    /// A run of the tracker in the output directory that cannot be continued.
    #[error("the tracker's rollouts: {source}; remove {} to run it again from the start, or choose another `option.out`", path.display())]
    RolloutOther {
        /// The run directory.
        path: PathBuf,
        /// Why it cannot be continued.
        source: Box<ResultsError>,
    },
    /// The tracker's run could not be read back.
    #[error("reading the tracker's run: {0}")]
    RolloutRead(#[from] ResultsError),
    /// A sequence the tracker's run does not hold.
    #[error("the tracker's run {run} has no `{ROLLOUT_SETTING}` episode of {task}/{sequence}")]
    RolloutMissing {
        /// The run directory.
        run: String,
        /// Task.
        task: String,
        /// Sequence id.
        sequence: String,
    },
}

/// What a data check says while it runs.
pub trait DataCheckObserver {
    /// `done` of `total` sequences checked.
    fn checked(&mut self, done: usize, total: usize);
    /// The observer of the tracker's run.
    fn rollouts(&mut self) -> &mut dyn EvalObserver;
}

/// Progress as lines: the sequences checked at each tenth, then the tracker's run's.
impl DataCheckObserver for ProgressLines<'_> {
    fn checked(&mut self, done: usize, total: usize) {
        if done == total || done.is_multiple_of((total / 10).max(1)) {
            self.note(&format!("checked {done}/{total} sequences"));
        }
    }

    fn rollouts(&mut self) -> &mut dyn EvalObserver {
        self
    }
}

/// Runs `job`: the check, the tracker's rollouts when asked, and the files when `out` is
/// given. The gate (`DatasetCheck::gate`) is the caller's, after it has shown the check;
/// every option, the gate's share included, is checked before anything runs.
pub fn run_data_check(
    job: &DataCheckJob,
    observer: &mut dyn DataCheckObserver,
) -> Result<DatasetCheck, DataCheckError> {
    if let Some(max) = job.max_outside {
        CheckGateError::check_share(max)?;
    }
    if job.tracker.is_some() && job.out.is_none() {
        return Err(DataCheckError::RolloutNeedsOut);
    }
    if let Some(out) = &job.out {
        check_dir(out, false, std::slice::from_ref(&job.dataset))?;
    }
    let robot = registry::robot(&job.robot)?;
    let ds = Dataset::open(&job.dataset, &robot)?;
    let mut check = check_dataset(&ds, &ds.load_all()?, &robot, &job.options, |d, t| {
        observer.checked(d, t)
    })?;
    if let (Some(tracker), Some(out)) = (&job.tracker, &job.out) {
        let run = out.join(format!("rollout-{}", tracker.dir_label()));
        crate::files::no_follow::make_dir_within(out, &run).map_err(|source| {
            DataCheckError::RolloutDir {
                path: run.clone(),
                source,
            }
        })?;
        check.tracker = Some(rollouts(job, tracker, &run, &check, observer)?);
    }
    if let Some(out) = &job.out {
        check.write(out)?;
    }
    Ok(check)
}

/// The tracker's run of every sequence without force into `run`, read back per sequence in
/// the check's order.
fn rollouts(
    job: &DataCheckJob,
    tracker: &PolicySource,
    run: &std::path::Path,
    check: &DatasetCheck,
    observer: &mut dyn DataCheckObserver,
) -> Result<TrackerHeld, DataCheckError> {
    if !tracker.in_process() {
        return Err(DataCheckError::RolloutNotInProcess(tracker.to_string()));
    }
    let request = EvalRequest {
        policy: tracker.clone(),
        dataset: Some(job.dataset.clone()),
        settings: vec![Setting::no_force()],
        engine: job.engine,
        ..EvalRequest::default()
    };
    let place = Place::Owned {
        dir: run.to_path_buf(),
        rerun: false,
    };
    let mut evaluation = Evaluation::open(
        &request,
        place,
        &SessionOptions::LAUNCHED,
        observer.rollouts(),
    )
    .map_err(Box::new)?;
    evaluation.run(observer.rollouts()).map_err(|e| match e {
        BenchmarkError::ResumedOther(source) => DataCheckError::RolloutOther {
            path: run.to_path_buf(),
            source: Box::new(source),
        },
        e => DataCheckError::Rollout(Box::new(e)),
    })?;
    let dir = RunDir::new(run);
    let log = dir.read_log(&dir.read_header()?)?;
    let sequences = check
        .sequences
        .iter()
        .map(|q| {
            let id = q.sequence_id.clone().unwrap_or_default();
            let record = log
                .records
                .iter()
                .rev()
                .find(|r| r.task == q.task && r.sequence_id == id && r.setting == ROLLOUT_SETTING)
                .ok_or_else(|| DataCheckError::RolloutMissing {
                    run: run.display().to_string(),
                    task: q.task.clone(),
                    sequence: id.clone(),
                })?;
            Ok(SequenceHeld {
                task: q.task.clone(),
                sequence_id: id,
                survival: record.series.survival(),
                ended_by: record.termination.map(|t| {
                    serde_json::to_value(t)
                        .ok()
                        .and_then(|v| v.as_str().map(str::to_string))
                        .unwrap_or_else(|| format!("{t:?}"))
                }),
            })
        })
        .collect::<Result<Vec<_>, DataCheckError>>()?;
    Ok(TrackerHeld {
        policy: tracker.to_string(),
        engine: job.engine.name().to_string(),
        run: run.display().to_string(),
        sequences,
    })
}
