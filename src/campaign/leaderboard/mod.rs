//! The leaderboard (`thorarena leaderboard`): every policy given, on one dataset, with and
//! without force, on each engine asked — one ordinary `eval` run per (policy, engine),
//! resumed where it stopped — summarised in one table; the same policies on the bundled
//! real human walks when asked (`--real-walks`), in a table of their own; and single-clip policies, each on
//! its own clip under pushes of increasing force, in a table of their own. The paper's tables and figures over
//! the same runs are `report`'s (the command writes them beside the table).
//!
//! Each run is exactly what `eval` with the same flags writes (the same `EvalSpec`, the
//! same `pipeline::evaluate`, the sanity check first), so a leaderboard row can be
//! re-derived by one `eval`: every run is opened through the one door,
//! [`Evaluation::open`], a policy in its own process ([`PolicyProcess`], any language)
//! started and connected there for each of its runs, then scored like the others.

use crate::eval::pipeline::{
    BenchmarkError, EvalObserver, Evaluation, OpenError, Place, ProgressLines,
};
use crate::eval::results::Summary;
use crate::eval::{EngineChoice, EvalRequest, Setting};
use crate::policy::launched::PolicyCommand;
use crate::policy::registry::PolicySource;
use crate::policy::SessionOptions;
use std::path::{Path, PathBuf};
use std::time::Instant;

mod board_table;
mod job;
mod outputs;
mod pairs;

pub use board_table::{leaderboard_table, tasks_outside_training, write_leaderboard_page};
pub(crate) use board_table::{markdown_cell, minutes};
pub use job::{run_leaderboard_job, LeaderboardJob, LeaderboardJobError};
pub use outputs::{
    leaderboard_tables, write_leaderboard_outputs, LeaderboardOutputs, OutputsError, PageHeader,
};
pub use pairs::{
    check_pairs, pairs_csv, pairs_table, run_pairs, write_pair_files, CompliancePair, PairMember,
    PairOptions, PairResult,
};

/// Why the leaderboard could not be made.
#[derive(Debug, thiserror::Error)]
pub enum LeaderboardError {
    /// A run could not be opened: its request is invalid, or its policy could not be
    /// loaded, or its process started or connected.
    #[error("{policy} on {engine}: {source}")]
    Open {
        /// The policy argument, or the process's name.
        policy: String,
        /// The engine.
        engine: &'static str,
        /// Why.
        source: Box<OpenError>,
    },
    /// A policy argument naming a session (`ipc:`): a policy process joins the leaderboard
    /// as a [`PolicyProcess`], started by the leaderboard for each run.
    #[error("{0} names a session no one starts: give the policy process as a command that joins {{session}} (a policy file's [[policy]] command = …)")]
    NotInProcess(String),
    /// An evaluation failed (its sanity check, its run directory, …).
    #[error("{policy} on {engine}: {source}")]
    Eval {
        /// The policy argument.
        policy: String,
        /// The engine.
        engine: &'static str,
        /// Why.
        source: Box<BenchmarkError>,
    },
    /// A run found in the board's directory was made under another configuration (a
    /// process's command, the settings, the dataset changed since): it is not resumed.
    #[error("{policy} on {engine}: {source}; {advice}")]
    OtherRun {
        /// The policy argument, or the process's name.
        policy: String,
        /// The engine.
        engine: &'static str,
        /// What differs.
        source: Box<crate::eval::results::ResultsError>,
        /// What the user can do, in the command's own options.
        advice: String,
    },
    /// Two rows of the board would write one run directory, or one engine is asked
    /// twice, or a process's name cannot name a run: refused before anything runs.
    #[error("{0}")]
    Names(String),
    /// `--out` holds something a leaderboard must not write over.
    #[error("`option.out` {}: {why}; choose another `option.out`", .out.display())]
    Out {
        /// The directory.
        out: PathBuf,
        /// What it holds.
        why: &'static str,
    },
    /// The board's synthetic dataset could not be opened or made.
    #[error("{}: {why}", .dir.display())]
    Synthetic {
        /// Its directory.
        dir: PathBuf,
        /// Why.
        why: String,
    },
    /// A policy file is unreadable or invalid.
    #[error("{path}: {message}")]
    PolicyFile {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// No policy or no engine.
    #[error("the leaderboard needs at least one policy and one engine")]
    Empty,
    /// A compliant/stiff pair's data could not be prepared.
    #[error("pair {pair}: {message}")]
    PairData {
        /// The pair's name.
        pair: String,
        /// What is wrong.
        message: String,
    },
    /// A run's directory could not be made, or what is there is not entered.
    #[error("{}: {source}", .path.display())]
    RunDir {
        /// The run directory.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
}

/// Makes the directory `run` of a run under `base` (the command's output directory, the
/// user's): each level below `base` made fresh or found a real directory of this user, so
/// a link planted at `runs/NAME-ENGINE` is refused, never written through.
pub(crate) fn make_run_dir(base: &Path, run: &Path) -> Result<(), LeaderboardError> {
    crate::files::no_follow::make_dir_within(base, run).map_err(|source| LeaderboardError::RunDir {
        path: run.to_path_buf(),
        source,
    })
}

/// A single-clip policy and the dataset of its own clip.
#[derive(Debug, Clone, PartialEq)]
pub struct OwnClip {
    /// The policy.
    pub policy: PolicySource,
    /// The dataset holding its clip.
    pub dataset: PathBuf,
}

/// `POLICY@DATASET`, as a command line gives it.
impl std::str::FromStr for OwnClip {
    type Err = String;

    /// `POLICY@DATASET` (split at the last `@`), the policy parsed as `--policy` is.
    fn from_str(text: &str) -> Result<Self, String> {
        let (policy, dataset) = text
            .rsplit_once('@')
            .filter(|(p, d)| !p.is_empty() && !d.is_empty())
            .ok_or_else(|| format!("`{text}`: give POLICY@DATASET"))?;
        Ok(Self {
            policy: PolicySource::parse(policy).map_err(|e| format!("`{text}`: {e}"))?,
            dataset: PathBuf::from(dataset),
        })
    }
}

/// A policy in its own process: a shell command that joins session `{session}` (and
/// `{thorarena}`, this binary), started for each of its runs.
#[derive(Debug, Clone, PartialEq)]
pub struct PolicyProcess {
    /// Its name in the table and run directories.
    pub name: String,
    /// The command, its working directory and connect timeout.
    pub command: PolicyCommand,
    /// Dynamics profile [default: the one the process declares at connect].
    pub profile: Option<String>,
}

/// `[[policy]]` tables, as a sweep spec writes them.
#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct PolicyFile {
    #[serde(rename = "policy", default)]
    policies: Vec<crate::campaign::sweep::PolicySpec>,
}

/// Reads the `[[policy]]` tables of `path` (a sweep spec's format): `policy = …`, a
/// policy argument run in process (a network's path taken against the file's
/// directory), or `command = …` with `{session}`, a [`PolicyProcess`] run in that
/// directory. Returns the policy arguments and the processes, in the file's order.
pub fn load_policy_file(
    path: &Path,
) -> Result<(Vec<PolicySource>, Vec<PolicyProcess>), LeaderboardError> {
    let invalid = |message: String| LeaderboardError::PolicyFile {
        path: path.to_path_buf(),
        message,
    };
    // A policy file is a few kilobytes; 16 MiB bounds what a mistaken path costs.
    let text = crate::files::bounded_read::read_to_string(path, "policy file", 16 << 20)
        .map_err(|e| invalid(e.to_string()))?;
    let file: PolicyFile = toml::from_str(&text).map_err(|e| invalid(e.to_string()))?;
    if file.policies.is_empty() {
        return Err(invalid("no [[policy]] table".into()));
    }
    let workdir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
        .to_path_buf();
    let (mut arguments, mut processes) = (Vec::new(), Vec::new());
    for (i, p) in file.policies.iter().enumerate() {
        let at = |m: &str| invalid(format!("[[policy]] #{}: {m}", i + 1));
        let source = p.source(&workdir).map_err(|m| at(&m))?;
        if p.unchecked {
            return Err(at("a policy file does not say whether a policy is checked: the leaderboard's `option.unchecked` does"));
        }
        match source {
            PolicySource::Named(_) if p.name.is_some() || p.profile.is_some() => {
                return Err(at("an in-process policy runs under its own family's profile and name: drop its `name =` and `profile =` keys"));
            }
            PolicySource::Named(_) => arguments.push(source),
            PolicySource::Launched(command) => processes.push(PolicyProcess {
                name: p.label(),
                command,
                profile: p.resolved_profile(&workdir),
            }),
        }
    }
    Ok((arguments, processes))
}

/// What to put on the leaderboard.
#[derive(Debug, Clone)]
pub struct LeaderboardRequest {
    /// Policies in process, as `eval --policy` takes them.
    pub policies: Vec<PolicySource>,
    /// General policies in their own processes, after [`Self::policies`].
    pub processes: Vec<PolicyProcess>,
    /// Single-clip policies, each on its own clip under [`Self::clip_settings`].
    pub clips: Vec<OwnClip>,
    /// The settings of the single-clip table.
    pub clip_settings: Vec<Setting>,
    /// The engines, each policy running on every one.
    pub engines: Vec<EngineChoice>,
    /// The dataset.
    pub dataset: PathBuf,
    /// Settings, as `eval --settings` spells them.
    pub settings: Vec<Setting>,
    /// Directory of the runs (`<out>/runs/<policy>-<engine>`, `…-own-clip` for a
    /// single-clip policy).
    pub out: PathBuf,
    /// The settings of the real-walks track (every general policy, again, on the bundled
    /// `real-walks`); empty: no such track.
    pub real_walks_settings: Vec<Setting>,
    /// Score policies without their sanity check (recorded in each run).
    pub unchecked: bool,
    /// Policies (as [`Entry`]'s runs name them: the argument, or the process's name) whose
    /// runs start again from the start instead of resuming.
    pub rerun: Vec<String>,
}

/// Which table of the leaderboard a run belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Track {
    /// A general policy on the board's dataset.
    General,
    /// A general policy on the real human walks the binary carries (`real-walks`).
    RealWalks,
    /// A single-clip policy on its own clip.
    OwnClip,
}

impl Track {
    /// What its run directories' names end with.
    fn dir_suffix(self) -> &'static str {
        match self {
            Self::General => "",
            Self::RealWalks => "-real-walks",
            Self::OwnClip => "-own-clip",
        }
    }
}

/// One (policy, engine) run of the leaderboard.
#[derive(Debug, Clone)]
pub struct Entry {
    /// How the table names the policy (`twist2 (twist2_1017_25k)`, a process's name).
    pub policy: String,
    /// The table it belongs to.
    pub track: Track,
    /// The engine's name.
    pub engine: &'static str,
    /// The run directory.
    pub run: PathBuf,
    /// Its scores.
    pub summary: Summary,
    /// Wall time of this invocation's part of it, s (0 for a run already complete).
    pub wall_s: f64,
    /// The forces its family was trained with (a policy process's are unknown).
    pub trained_forces: crate::policy::registry::TrainedForces,
}

/// Hears the leaderboard's progress.
pub trait LeaderboardObserver {
    /// Run `index` of `total` is starting: `policy` on `engine` into `run`.
    fn run_starting(&mut self, _index: usize, _total: usize, _policy: &str, _engine: &str) {}
    /// The observer of that run's evaluation.
    fn eval_observer(&mut self) -> &mut dyn EvalObserver;
    /// What the runs' policy processes say (starting, their log, connection news).
    fn note(&mut self, _text: &str) {}
}

/// A leaderboard's progress as lines: one per run, then the run's own
/// ([`ProgressLines`]).
impl LeaderboardObserver for ProgressLines<'_> {
    fn run_starting(&mut self, index: usize, total: usize, policy: &str, engine: &str) {
        EvalObserver::note(
            self,
            &format!("[{}/{total}] {policy} on {engine}", index + 1),
        );
    }

    fn eval_observer(&mut self) -> &mut dyn EvalObserver {
        self
    }

    fn note(&mut self, text: &str) {
        EvalObserver::note(self, text);
    }
}

/// Who plays a leaderboard run: a policy argument (in process), or a policy process.
#[derive(Debug, Clone)]
enum Player {
    Argument(PolicySource),
    Process(PolicyProcess),
}

impl Player {
    /// The policy argument, or the process's name, as messages name it.
    fn name(&self) -> String {
        match self {
            Self::Argument(a) => a.to_string(),
            Self::Process(p) => p.name.clone(),
        }
    }

    /// How a table names it.
    fn table_label(&self) -> String {
        match self {
            Self::Argument(a) => a.table_label(),
            Self::Process(p) => p.name.clone(),
        }
    }

    /// The base of its run directories' names: the family and the network's file stem
    /// (`wbc-mjlab-wbc_g1_policy`), a built-in's name, a process's name.
    fn dir_label(&self) -> String {
        match self {
            Self::Argument(a) => a.dir_label(),
            Self::Process(p) => p.name.clone(),
        }
    }
}

/// The run directory's name of a player whose directory label is `base` on `engine`
/// (`wbc-mjlab-wbc_g1_policy-rapier`).
fn run_name(base: &str, engine: EngineChoice) -> String {
    let clean: String = base
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "-_.".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect();
    format!("{clean}-{}", engine.name())
}

/// Refuses, before the first run, what would otherwise fail late or overwrite a run: an
/// engine asked twice, a process's name that cannot name a run directory, and two rows
/// that would share one run directory (two policies of one name, or whose names clean
/// to the same directory name).
fn check_names(
    runs: &[(Player, PathBuf, Track)],
    engines: &[EngineChoice],
) -> Result<(), LeaderboardError> {
    for (i, e) in engines.iter().enumerate() {
        if engines[..i].contains(e) {
            return Err(LeaderboardError::Names(format!(
                "`option.engines` names {} twice",
                e.name()
            )));
        }
    }
    let mut seen: std::collections::BTreeMap<String, String> = Default::default();
    for (player, _, track) in runs {
        if let Player::Process(p) = player {
            crate::files::names::check_name("policy name", &p.name)
                .map_err(|e| LeaderboardError::Names(e.to_string()))?;
        }
        let dir = format!(
            "{}{}",
            run_name(&player.dir_label(), EngineChoice::Rapier),
            track.dir_suffix()
        );
        if let Some(other) = seen.insert(dir.clone(), player.name()) {
            return Err(LeaderboardError::Names(format!(
                "`{other}` and `{}` would share the run directory runs/{dir}: give each policy a name of its own",
                player.name()
            )));
        }
    }
    Ok(())
}

/// A leaderboard writes `runs/`, `leaderboard.md` and its reports into `out`: a new
/// directory or an earlier leaderboard's (whose runs it resumes), never a run, a dataset
/// or a directory holding another command's report.
fn check_out(out: &Path) -> Result<(), LeaderboardError> {
    let refuse = |why| {
        Err(LeaderboardError::Out {
            out: out.to_path_buf(),
            why,
        })
    };
    if crate::eval::results::RunDir::new(out).holds_run() {
        return refuse("it holds a run");
    }
    if out.join(crate::sim::motion::MANIFEST).is_file() {
        return refuse("it holds a dataset");
    }
    let earlier_board = out.join("leaderboard.md").is_file() || out.join("runs").is_dir();
    if !earlier_board && out.join("report.html").exists() {
        return refuse("it holds a report.html no leaderboard wrote");
    }
    Ok(())
}

/// Runs every (policy, engine) of `request`, resuming runs already started, engine by
/// engine in the order given.
pub fn run_leaderboard(
    request: &LeaderboardRequest,
    observer: &mut dyn LeaderboardObserver,
) -> Result<Vec<Entry>, LeaderboardError> {
    if (request.policies.is_empty() && request.processes.is_empty() && request.clips.is_empty())
        || request.engines.is_empty()
    {
        return Err(LeaderboardError::Empty);
    }
    let general = request
        .policies
        .iter()
        .map(|p| Player::Argument(p.clone()))
        .chain(request.processes.iter().cloned().map(Player::Process))
        .map(|player| (player, request.dataset.clone(), Track::General));
    let general: Vec<_> = general.collect();
    let real = general
        .iter()
        .filter(|_| !request.real_walks_settings.is_empty())
        .map(|(player, _, _)| (player.clone(), real_walks_dir(), Track::RealWalks))
        .collect::<Vec<_>>();
    let own = request.clips.iter().map(|c| {
        let player = Player::Argument(c.policy.clone());
        (player, c.dataset.clone(), Track::OwnClip)
    });
    let runs: Vec<(Player, PathBuf, Track)> = general.into_iter().chain(real).chain(own).collect();
    check_names(&runs, &request.engines)?;
    check_rerun(&runs, &request.rerun)?;
    check_out(&request.out)?;
    let total = runs.len() * request.engines.len();
    let mut entries = Vec::new();
    for &engine in &request.engines {
        for (player, dataset, track) in &runs {
            let engine_name = engine.name();
            let name = run_name(&player.dir_label(), engine);
            let run = request
                .out
                .join("runs")
                .join(format!("{name}{}", track.dir_suffix()));
            observer.run_starting(entries.len(), total, &player.name(), engine_name);
            make_run_dir(&request.out, &run)?;
            let started = Instant::now();
            let settings = match track {
                Track::General => &request.settings,
                Track::RealWalks => &request.real_walks_settings,
                Track::OwnClip => &request.clip_settings,
            };
            let rerun = request.rerun.contains(&player.name());
            // The gate is the general track's: a policy that passed its sanity check on
            // the board's dataset is not checked again on people's walks, where a
            // command follower's heading check judges the walk, not the wiring
            // (recorded `unchecked` in those runs).
            let summary = board_run(
                request.unchecked || *track == Track::RealWalks,
                player,
                dataset,
                settings,
                engine,
                &run,
                Resume::Board { rerun },
                observer,
            )?;
            entries.push(Entry {
                policy: player.table_label(),
                track: *track,
                engine: engine_name,
                run,
                summary,
                wall_s: started.elapsed().as_secs_f64(),
                trained_forces: match player {
                    Player::Argument(a) => a.family().trained_forces,
                    Player::Process(_) => crate::policy::registry::TrainedForces::Unknown,
                },
            });
        }
    }
    Ok(entries)
}

/// How a run already in its directory is treated, and what a refusal to resume it
/// advises.
#[derive(Debug, Clone, Copy)]
enum Resume {
    /// A leaderboard's run: resumed unless `rerun` (`option.rerun` names its policy).
    Board {
        /// Start it again from the start.
        rerun: bool,
    },
    /// A run of the pairs: resumed, or removed by hand.
    Alone,
}

/// The bundled real human walks (`--dataset real-walks`).
fn real_walks_dir() -> PathBuf {
    crate::sim::motion::bundled_dataset("real-walks").expect("real-walks is a bundled dataset")
}

/// Refuses an `option.rerun` that names no policy of the board, before anything runs.
fn check_rerun(
    runs: &[(Player, PathBuf, Track)],
    rerun: &[String],
) -> Result<(), LeaderboardError> {
    for name in rerun {
        if !runs.iter().any(|(p, _, _)| p.name() == *name) {
            let names: Vec<String> = runs.iter().map(|(p, _, _)| p.name()).collect();
            return Err(LeaderboardError::Names(format!(
                "`option.rerun` names `{}`, no policy of this board (its policies: {})",
                name.escape_debug(),
                names.join(", ")
            )));
        }
    }
    Ok(())
}

/// One run of the board: `player` on `dataset` under `settings` on `engine` into `run`,
/// opened through the one door ([`Evaluation`], the place [`Place::Owned`]: a run there
/// of the same policy is continued, another started again) and scored; a run that cannot
/// be continued is refused with what to do (`resume`'s advice).
#[allow(clippy::too_many_arguments)]
fn board_run(
    unchecked: bool,
    player: &Player,
    dataset: &Path,
    settings: &[Setting],
    engine: EngineChoice,
    run: &Path,
    resume: Resume,
    observer: &mut dyn LeaderboardObserver,
) -> Result<Summary, LeaderboardError> {
    let name = player.name();
    let engine_name = engine.name();
    let (source, profile) = match player {
        Player::Argument(a) if a.in_process() => (a.clone(), None),
        Player::Argument(a) => return Err(LeaderboardError::NotInProcess(a.to_string())),
        Player::Process(p) => (PolicySource::from(p.command.clone()), p.profile.clone()),
    };
    let request = EvalRequest {
        policy: source,
        dataset: Some(dataset.to_path_buf()),
        profile,
        settings: settings.to_vec(),
        engine,
        unchecked,
        ..EvalRequest::default()
    };
    let place = Place::Owned {
        dir: run.to_path_buf(),
        rerun: matches!(resume, Resume::Board { rerun: true }),
    };
    let mut evaluation = Evaluation::open(
        &request,
        place,
        &SessionOptions::LAUNCHED,
        observer.eval_observer(),
    )
    .map_err(|source| LeaderboardError::Open {
        policy: name.clone(),
        engine: engine_name,
        source: Box::new(source),
    })?;
    let evaluated = evaluation
        .run(observer.eval_observer())
        .map_err(|source| match source {
            BenchmarkError::ResumedOther(other) => LeaderboardError::OtherRun {
                advice: match resume {
                    Resume::Board { .. } => format!(
                        "give `option.rerun` {name} to run it again from the start (its episodes are replaced), or choose another `option.out`"
                    ),
                    Resume::Alone => format!(
                        "remove {} to run it again from the start, or choose another `option.out`",
                        run.display()
                    ),
                },
                policy: name.clone(),
                engine: engine_name,
                source: Box::new(other),
            },
            source => LeaderboardError::Eval {
                policy: name.clone(),
                engine: engine_name,
                source: Box::new(source),
            },
        })?;
    Ok(evaluated.summary)
}

/// Per task, where the dataset's recorded hand forces point (`data check`'s
/// [`HandForceSpan`]): what a FATS cell is judged against for a policy trained with a
/// force curriculum.
pub type TaskForceSpans = crate::eval::TaskForceSpans;

/// The board's synthetic dataset in `out`/synthetic: generated with `per_task` sequences
/// per task (`note` hears that it is), or reused when it holds exactly that many.
pub fn synthetic_dataset(
    out: &Path,
    per_task: usize,
    note: &mut dyn FnMut(&str),
) -> Result<PathBuf, LeaderboardError> {
    use crate::sim::motion::synth::{write_synthetic, SynthOptions, TASKS};
    let dir = out.join("synthetic");
    let failed = |why: String| LeaderboardError::Synthetic {
        dir: dir.clone(),
        why,
    };
    let robot = crate::policy::registry::robot("g1_29dof").map_err(|e| failed(e.to_string()))?;
    let want = per_task * TASKS.len();
    // The board's own directory: a link planted at `synthetic` is not entered.
    crate::files::no_follow::make_dir_within(out, &dir).map_err(|e| failed(e.to_string()))?;
    if dir.join(crate::sim::motion::MANIFEST).exists() {
        let have = crate::sim::motion::Dataset::open(&dir, &robot)
            .map_err(|e| failed(e.to_string()))?
            .len();
        if have != want {
            return Err(failed(format!(
                "holds {have} sequences, not {want} (`option.per_task` {per_task}): remove it, or give that `option.per_task`"
            )));
        }
        return Ok(dir);
    }
    note(&format!(
        "generating the synthetic dataset into {} ({want} sequences)",
        dir.display()
    ));
    let opts = SynthOptions {
        per_task,
        ..SynthOptions::default()
    };
    write_synthetic(&dir, &robot, &opts, false, |_, _| {}).map_err(|e| failed(e.to_string()))?;
    Ok(dir)
}
