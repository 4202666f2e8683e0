//! `leaderboard` end to end: the dataset (the synthetic one generated once into the
//! output directory unless one is given), every general policy and single-clip policy on
//! each engine, the compliance pairs, then the leaderboard's tables, page and reports.

use super::{
    check_pairs, load_policy_file, run_leaderboard, run_pairs, synthetic_dataset,
    write_leaderboard_outputs, CompliancePair, Entry, LeaderboardError, LeaderboardObserver,
    LeaderboardOutputs, LeaderboardRequest, OutputsError, OwnClip, PageHeader, PairOptions,
    TaskForceSpans,
};
use crate::eval::{EngineChoice, EvalRequest, Setting};
use crate::policy::registry::{self, RegistryError};
use crate::report::{Page, ReportError, WebBundle};
use crate::sim::motion::check::{check_dataset, CheckError, CheckOptions, HandForceSpan};
use crate::sim::motion::Dataset;
use std::path::Path;
use std::path::PathBuf;
use std::time::Instant;

/// Everything one `leaderboard` command asks for.
#[derive(Debug, Clone)]
pub struct LeaderboardJob {
    /// General policies, as a run names them (in process).
    pub policies: Vec<crate::policy::registry::PolicySource>,
    /// More general policies, and policy processes, from a TOML file.
    pub policy_file: Option<PathBuf>,
    /// Single-clip policies on their own clips.
    pub clips: Vec<OwnClip>,
    /// Settings of the single-clip table.
    pub clip_settings: Vec<Setting>,
    /// Settings of the real-walks track (empty: none).
    pub real_walks_settings: Vec<Setting>,
    /// Compliant policies with their stiff twins.
    pub pairs: Vec<CompliancePair>,
    /// How the pairs run (its engines, output and checking are the job's).
    pub pair_options: PairOptions,
    /// Engines; empty: rapier, and MuJoCo in a build with it.
    pub engines: Vec<EngineChoice>,
    /// The dataset [default: the synthetic one, `per_task` sequences per task].
    pub dataset: Option<PathBuf>,
    /// Sequences per task of the generated synthetic dataset.
    pub per_task: usize,
    /// Settings of the general table.
    pub settings: Vec<Setting>,
    /// Directory of the runs, the generated dataset and the tables.
    pub out: PathBuf,
    /// Score policies without their sanity check.
    pub unchecked: bool,
    /// The command line, as the page records it.
    pub command: String,
    /// Policies whose runs start again from the start (`LeaderboardRequest::rerun`).
    pub rerun: Vec<String>,
}

/// Why the leaderboard could not be made.
#[derive(Debug, thiserror::Error)]
pub enum LeaderboardJobError {
    /// The report's front end could not be found.
    #[error(transparent)]
    Report(#[from] ReportError),
    /// A run, the dataset or the policy file failed.
    #[error(transparent)]
    Leaderboard(#[from] LeaderboardError),
    /// The tables, page or reports could not be written.
    #[error(transparent)]
    Outputs(#[from] OutputsError),
    /// The robot the dataset's forces are checked on.
    #[error("the robot to check the dataset's forces on: {0}")]
    Robot(#[from] RegistryError),
    /// Where the dataset's forces point could not be measured.
    #[error("measuring where the dataset's forces point (for the cells outside a policy's training): {0}")]
    ForceSpans(#[from] CheckError),
}

/// Per task, where `dataset`'s recorded forces point (`data check`'s spans), when a general
/// entry's family has a force envelope to judge them against; empty otherwise.
fn task_force_spans(
    dataset: &Path,
    entries: &[Entry],
) -> Result<TaskForceSpans, LeaderboardJobError> {
    let judged = entries.iter().any(|e| {
        e.track == super::Track::General
            && e.trained_forces
                .holds_hand_forces(&HandForceSpan::default())
                .is_some()
    });
    if !judged {
        return Ok(TaskForceSpans::new());
    }
    let robot = registry::robot(&EvalRequest::default().robot)?;
    let ds = Dataset::open(dataset, &robot).map_err(CheckError::from)?;
    let seqs = ds.load_all().map_err(CheckError::from)?;
    let check = check_dataset(&ds, &seqs, &robot, &CheckOptions::default(), |_, _| {})?;
    Ok(check
        .tasks
        .iter()
        .map(|t| (t.task.clone(), t.forces.span))
        .collect())
}

/// Runs `job`, resuming the runs a previous attempt left, and writes its outputs.
pub fn run_leaderboard_job(
    job: &LeaderboardJob,
    observer: &mut dyn LeaderboardObserver,
) -> Result<LeaderboardOutputs, LeaderboardJobError> {
    let started = Instant::now();
    // The bundle first: a missing front end fails before hours of runs.
    let bundle = WebBundle::locate()?;
    let dataset = match &job.dataset {
        Some(d) => d.clone(),
        None if job.policies.is_empty() && job.policy_file.is_none() => PathBuf::new(),
        None => synthetic_dataset(&job.out, job.per_task, &mut |n| observer.note(n))?,
    };
    // MuJoCo, the field's reference engine, where the build has it; rapier is then the
    // cross-check a user asks for (`--engines mujoco,rapier`), at 5-10× MuJoCo's time.
    let engines = if !job.engines.is_empty() {
        job.engines.clone()
    } else if cfg!(feature = "mujoco") {
        vec![EngineChoice::Mujoco]
    } else {
        vec![EngineChoice::Rapier]
    };
    let pair_options = PairOptions {
        engines: engines.clone(),
        out: job.out.clone(),
        unchecked: job.unchecked,
        ..job.pair_options.clone()
    };
    // The pairs before any run: a bad pair option fails now, not after the board's runs.
    let sweeps = check_pairs(&job.pairs, &pair_options)?;
    let (mut policies, processes) = match &job.policy_file {
        Some(file) => load_policy_file(file)?,
        None => Default::default(),
    };
    policies.splice(0..0, job.policies.iter().cloned());
    let request = LeaderboardRequest {
        policies,
        processes,
        clips: job.clips.clone(),
        clip_settings: job.clip_settings.clone(),
        engines: engines.clone(),
        dataset: dataset.clone(),
        settings: job.settings.clone(),
        real_walks_settings: job.real_walks_settings.clone(),
        out: job.out.clone(),
        unchecked: job.unchecked,
        rerun: job.rerun.clone(),
    };
    let nothing_general =
        request.policies.is_empty() && request.processes.is_empty() && request.clips.is_empty();
    let entries = if nothing_general {
        if let Some(name) = job.rerun.first() {
            return Err(LeaderboardError::Names(format!(
                "`option.rerun` names `{}`, but the board runs no general policy (a pair's runs are removed by hand)",
                name.escape_debug()
            ))
            .into());
        }
        Vec::new()
    } else {
        run_leaderboard(&request, observer)?
    };
    let pairs = run_pairs(&job.pairs, sweeps, &pair_options, observer)?;
    let header = PageHeader {
        dataset: &dataset,
        settings: &job.settings,
        command: &job.command,
        wall_s: started.elapsed().as_secs_f64(),
    };
    let spans = task_force_spans(&dataset, &entries)?;
    let script = bundle.script(Page::Report)?;
    Ok(write_leaderboard_outputs(
        &job.out, &entries, &pairs, &spans, &header, &script,
    )?)
}
