//! `crosscheck`'s evaluation: the same episodes on rapier and on MuJoCo, each an ordinary
//! run directory (`<out>/rapier`, `<out>/mujoco`), with each episode's joint angles of its
//! first seconds and its feet's slip kept beside the run as episodes finish (a resume keeps
//! them); then the two compared per episode, per setting and per push force, with
//! bootstrap confidence intervals, into `crosscheck.json` and `crosscheck.csv`.

use super::{evaluate, BenchmarkError, EvalObserver, EvalOptions, Evaluated, Starting};
use crate::eval::episode::EpisodeTrace;
use crate::eval::results::crosscheck::{compare_runs, write_crosscheck, Crosscheck, SeriesLog};
use crate::eval::results::{
    ResultsError, RunDir, RunTarget, RunTargetError, CROSSCHECK_SERIES_FILE,
};
use crate::eval::{EngineChoice, EpisodeRecord, EvalRequest, EvalSpec, SpecError};
use crate::files::names::{check_name, NameError};
use crate::policy::registry::{open_in_process, OpenPolicyError, PolicySource, RegistryError};
use std::path::PathBuf;

/// The most bootstrap resamples a comparison takes (10⁶ already pins a 95 % interval's
/// ends to a fraction of a per cent of its width).
pub const MAX_BOOTSTRAP: usize = 1_000_000;

/// What a crosscheck compares and where it writes.
#[derive(Debug, Clone)]
pub struct CrosscheckRequest {
    /// The rapier run (its engine is rapier).
    pub rapier: EvalRequest,
    /// The MuJoCo run: the same evaluation, with MuJoCo's model and physics step.
    pub mujoco: EvalRequest,
    /// The directory of both runs and the comparison (default:
    /// `results/crosscheck-<policy family>-<dataset name>`).
    pub out: Option<PathBuf>,
    /// Continue runs already there.
    pub resume: bool,
    /// Replace runs already there.
    pub overwrite: bool,
    /// Bootstrap resamples of the confidence intervals.
    pub bootstrap: usize,
    /// Seconds from each episode's start over which the joint angles are compared.
    pub divergence_s: f64,
}

impl CrosscheckRequest {
    /// The two runs of `request`: rapier on the robot model (an `mjcf` is MuJoCo's), and
    /// MuJoCo with its own physics step when `mujoco_physics_dt_s` gives one.
    pub fn engine_requests(
        request: &EvalRequest,
        mujoco_physics_dt_s: Option<f64>,
    ) -> [EvalRequest; 2] {
        let rapier = EvalRequest {
            engine: EngineChoice::Rapier,
            mjcf: None,
            ..request.clone()
        };
        let mujoco = EvalRequest {
            engine: EngineChoice::Mujoco,
            physics_dt_s: mujoco_physics_dt_s.or(request.physics_dt_s),
            ..request.clone()
        };
        [rapier, mujoco]
    }
}

/// Why a crosscheck could not run.
#[derive(Debug, thiserror::Error)]
pub enum CrosscheckError {
    /// A policy process: both engines need the same policy, run twice in process.
    #[error("crosscheck runs the policy twice in process: use a built-in, twist2:, beyondmimic: or wbc-mjlab: policy")]
    PolicyProcess,
    /// A divergence window that is not a positive number of seconds.
    #[error("`option.divergence_seconds` must be a positive number of seconds")]
    DivergenceWindow,
    /// Checked before the two evaluations run: an interval needs resamples, and each
    /// resample holds one mean per episode in memory.
    #[error("`option.bootstrap` {0}: the confidence intervals need between 1 and {MAX_BOOTSTRAP} resamples")]
    Bootstrap(usize),
    /// The policy argument names no policy.
    #[error(transparent)]
    Registry(#[from] RegistryError),
    /// The rapier run's evaluation is not one.
    #[error(transparent)]
    Spec(#[from] SpecError),
    /// The MuJoCo run's evaluation is not one (MuJoCo missing, a bad model or step).
    #[error("the MuJoCo run{}", .physics_dt_s.map(|dt| format!(" (`option.mujoco_physics_dt` {dt})")).unwrap_or_default())]
    MujocoSpec {
        /// MuJoCo's own physics step, when one was given.
        physics_dt_s: Option<f64>,
        /// Why.
        #[source]
        source: SpecError,
    },
    /// The default directory's name is not usable.
    #[error(transparent)]
    Name(#[from] NameError),
    /// A run directory that cannot be used.
    #[error(transparent)]
    Target(#[from] RunTargetError),
    /// The series or the comparison files could not be read or written.
    #[error(transparent)]
    Results(#[from] ResultsError),
    /// An engine's evaluation failed.
    #[error(transparent)]
    Benchmark(#[from] BenchmarkError),
}

/// Hears a crosscheck (the library prints nothing).
pub trait CrosscheckObserver {
    /// Advice on the evaluations, and warnings.
    fn note(&mut self, text: &str);
    /// One engine's evaluation is about to run into `run`.
    fn engine_starting(&mut self, spec: &EvalSpec, run: &RunDir, policy: &str);
    /// Hears the running engine's progress.
    fn eval_observer(&mut self) -> &mut dyn EvalObserver;
    /// One engine's evaluation is written.
    fn engine_done(&mut self, spec: &EvalSpec, run: &RunDir, done: &Evaluated);
}

/// A finished crosscheck.
#[derive(Debug)]
pub struct Compared {
    /// The comparison.
    pub check: Crosscheck,
    /// `crosscheck.json` and `crosscheck.csv`.
    pub files: [PathBuf; 2],
}

/// Runs `request` on both engines (resuming each with [`CrosscheckRequest::resume`]) and
/// compares them.
pub fn compare_engines(
    request: &CrosscheckRequest,
    observer: &mut dyn CrosscheckObserver,
) -> Result<Compared, CrosscheckError> {
    let policy = &request.rapier.policy;
    if !policy.in_process() {
        return Err(CrosscheckError::PolicyProcess);
    }
    if !(request.divergence_s.is_finite() && request.divergence_s > 0.0) {
        return Err(CrosscheckError::DivergenceWindow);
    }
    if !(1..=MAX_BOOTSTRAP).contains(&request.bootstrap) {
        return Err(CrosscheckError::Bootstrap(request.bootstrap));
    }
    // Both evaluations first: a missing MuJoCo fails before anything runs.
    let rapier = EvalSpec::load(&request.rapier)?;
    let mujoco = EvalSpec::load(&request.mujoco).map_err(|source| CrosscheckError::MujocoSpec {
        physics_dt_s: (request.mujoco.physics_dt_s != request.rapier.physics_dt_s)
            .then_some(request.mujoco.physics_dt_s)
            .flatten(),
        source,
    })?;
    for advice in rapier.advice.iter().chain(&mujoco.advice) {
        observer.note(&advice.to_string());
    }
    let out = match &request.out {
        Some(out) => out.clone(),
        None => {
            let name = format!(
                "crosscheck-{}-{}",
                policy.family().name,
                rapier.dataset_name()
            );
            check_name("crosscheck directory", &name)?;
            PathBuf::from("results").join(name)
        }
    };
    let runs = [
        RunDir::new(out.join("rapier")),
        RunDir::new(out.join("mujoco")),
    ];
    for (run, spec) in runs.iter().zip([&rapier, &mujoco]) {
        RunTarget {
            out: None,
            resume: request.resume,
            overwrite: request.overwrite,
            spec,
        }
        .check(run.path())?;
    }
    let mut series = Vec::new();
    for (spec, run) in [&rapier, &mujoco].into_iter().zip(&runs) {
        series.push(run_engine(request, policy, spec, run, observer)?);
    }
    let check = compare_runs(
        [&runs[0], &runs[1]],
        [&series[0], &series[1]],
        request.bootstrap,
    )?;
    if check.without_series > 0 {
        observer.note(&format!(
            "warning: {} of {} episodes have no joint divergence or foot slip: their series are not in {CROSSCHECK_SERIES_FILE} (a run resumed from an older crosscheck?); `option.overwrite` runs them again",
            check.without_series,
            check.pairs.len(),
        ));
    }
    let files = write_crosscheck(
        &out,
        [runs[0].path(), runs[1].path()],
        &check,
        request.bootstrap,
        request.divergence_s,
    )?;
    Ok(Compared { check, files })
}

/// One engine's evaluation into `run`, its series kept as episodes finish.
fn run_engine(
    request: &CrosscheckRequest,
    policy: &PolicySource,
    spec: &EvalSpec,
    run: &RunDir,
    observer: &mut dyn CrosscheckObserver,
) -> Result<SeriesLog, CrosscheckError> {
    let mut log = SeriesLog::open(run, request.resume)?;
    for (line, why) in &log.dropped_lines {
        observer.note(&format!(
            "`option.resume`: {} line {line} is unreadable ({why}); its episode's series is dropped",
            run.crosscheck_series_file().display()
        ));
    }
    // Checked in process by `compare_engines`: each engine gets its own copy.
    let mut policy = match open_in_process(policy, &spec.robot, &spec.profile) {
        Ok(policy) => policy,
        Err(OpenPolicyError::Registry(e)) => return Err(e.into()),
        Err(_) => return Err(CrosscheckError::PolicyProcess),
    };
    observer.engine_starting(spec, run, policy.name());
    let mut keeping = KeepingSeries {
        inner: observer.eval_observer(),
        log: &mut log,
        seconds: request.divergence_s,
        error: None,
    };
    let options = EvalOptions {
        resume: request.resume,
        trace_first_s: Some(request.divergence_s),
    };
    let done = evaluate(spec, policy.as_mut(), run, options, &mut keeping);
    let error = keeping.error.take();
    let done = done?;
    if let Some(e) = error {
        return Err(e.into());
    }
    observer.engine_done(spec, run, &done);
    done.check_policy(run.path())?;
    Ok(log)
}

/// Passes a run's progress on, keeping each episode's series from its trace.
struct KeepingSeries<'a> {
    inner: &'a mut dyn EvalObserver,
    log: &'a mut SeriesLog,
    seconds: f64,
    /// The first series that could not be written (the run goes on; the crosscheck fails).
    error: Option<ResultsError>,
}

impl EvalObserver for KeepingSeries<'_> {
    fn starting(&mut self, starting: &Starting) {
        self.inner.starting(starting);
    }

    fn episode(&mut self, record: &EpisodeRecord, trace: Option<&EpisodeTrace>) {
        if let Some(trace) = trace {
            if let Err(e) = self.log.append_trace(record.key(), trace, self.seconds) {
                self.error.get_or_insert(e);
            }
        }
        self.inner.episode(record, trace);
    }
}
