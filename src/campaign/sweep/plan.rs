//! The expanded plan: cells (one combination of the axes) and tasks (one shard of one
//! cell, i.e. one evaluation, held as an [`EvalRequest`]), numbered
//! 0..N-1 in a fixed order so that a task index means the same work on every node.

use super::spec::{resolve, PolicySpec, SweepSpec};
use super::SweepError;
use crate::eval::{parse_budget, EvalRequest, PolicyIoRules, Setting};
use crate::policy::registry::PolicySource;
use crate::sim::motion::{DataError, Dataset, SequenceSelection};
use crate::sim::robot::RobotModel;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// File name of the plan in a sweep directory.
pub const PLAN_FILE: &str = "plan.json";
/// Version of the plan and task-record format; a sweep directory of another one is
/// refused rather than misread. 2: the robot is recorded and eval arguments are
/// `--flag=value` (a negative value is not read as a flag). 3: the plan is sealed.
/// 4: a task holds its evaluation as a serialized [`EvalRequest`], not `eval` arguments.
/// 5: a policy is one value ([`PolicySource`]): an argument's string, or a launched
/// command's table (command, working directory, connect timeout).
pub const PLAN_FORMAT: u32 = 5;

/// The largest `plan.json` read, bytes (a task is under 1 KiB: this is tens of thousands).
const MAX_PLAN_BYTES: u64 = 64 * crate::files::bounded_read::MIB;

/// A sweep's plan, written to `DIR/plan.json` by `sweep plan`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    /// [`PLAN_FORMAT`].
    pub format: u32,
    /// The ThorArena version that planned it.
    pub thorarena_version: String,
    /// The spec file (absolute).
    pub spec: PathBuf,
    /// Where policy commands run (the spec's directory).
    pub workdir: PathBuf,
    /// The robot every task evaluates.
    pub robot: String,
    /// The cells, in index order.
    pub cells: Vec<Cell>,
    /// The tasks, in index order.
    pub tasks: Vec<Task>,
    /// SHA-256 of the plan as planned, this field empty ([`Plan::seal_of`]): a plan
    /// edited by hand — a policy command changed to run something else — no longer
    /// matches it and is refused before anything of it runs.
    #[serde(default)]
    pub seal: String,
}

/// One combination of the axes: one evaluation configuration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Cell {
    /// Index in [`Plan::cells`].
    pub index: usize,
    /// The policy.
    pub policy: PolicyAxis,
    /// Dataset directory (absolute).
    pub dataset: PathBuf,
    /// Its content hash at planning time (a task refuses a changed dataset).
    pub dataset_sha256: String,
    /// The sequences evaluated (`eval --tasks`, `--sequences`; empty: all).
    #[serde(default, skip_serializing_if = "SequenceSelection::is_all")]
    pub selection: SequenceSelection,
    /// Force setting (in the plan, spelled as `eval --settings` takes it).
    #[serde(with = "crate::eval::spelled_settings::one")]
    pub setting: Setting,
    /// Latency rule.
    pub latency: LatencyRule,
    /// Physics engine (plans written before engines were an axis read as rapier).
    #[serde(default)]
    pub engine: EngineAxis,
    /// Shards (tasks) of this cell.
    pub shards: usize,
    /// Episodes of the cell (one per sequence).
    pub episodes: usize,
    /// Simulated seconds of the cell's references.
    pub simulated_s: f64,
}

/// A policy as planned.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PolicyAxis {
    /// Label in results.
    pub name: String,
    /// Where the policy comes from: an argument (network paths absolute), or the command
    /// a task starts (`{session}`, `{thorarena}` placeholders), in the spec's directory.
    pub policy: PolicySource,
    /// Dynamics profile (name, or absolute .toml path).
    pub profile: String,
    /// Keypoint set.
    pub keypoints: String,
    /// `eval --unchecked`.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub unchecked: bool,
    /// SHA-256 of the network file when it was planned (`None`: no file, or one that could
    /// not be read then — its task says why). A task refuses a file changed since, and a
    /// run of another network never counts for the cell: one policy's curve is one
    /// network's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub network_sha256: Option<String>,
}

/// A physics engine as planned.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EngineAxis {
    /// Label in results.
    pub name: String,
    /// `--engine`.
    pub engine: String,
    /// `--mjcf`, absolute.
    pub mjcf: Option<PathBuf>,
    /// `--physics-dt`, s.
    pub physics_dt_s: Option<f64>,
}

impl Default for EngineAxis {
    fn default() -> Self {
        Self {
            name: "rapier".into(),
            engine: "rapier".into(),
            mjcf: None,
            physics_dt_s: None,
        }
    }
}

/// A latency rule as planned.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LatencyRule {
    /// Label in results.
    pub name: String,
    /// `--budget`.
    pub budget: String,
    /// `--latency-mode`.
    pub mode: String,
    /// `--miss-rule`.
    pub miss_rule: String,
}

/// One shard of one cell.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Task {
    /// Index in [`Plan::tasks`] (the array index on a cluster).
    pub index: usize,
    /// Its cell.
    pub cell: usize,
    /// Shard `(i, n)`, 0-based.
    pub shard: (usize, usize),
    /// Episodes this task runs.
    pub episodes: usize,
    /// The evaluation the task runs, as `eval` would build it from its flags — without
    /// workers (the node's) or a run directory (the task's); a launched policy is its
    /// command until [`Task::request_for`] names the session an attempt serves it.
    pub request: EvalRequest,
}

impl Task {
    /// The task's evaluation as its `eval` process runs it: a launched policy is the
    /// policy process on `session`, which the attempt starts beside it.
    pub fn request_for(&self, session: &str) -> EvalRequest {
        let mut request = self.request.clone();
        if request.policy.command().is_some() {
            request.policy = PolicySource::on_session(session);
        }
        request
    }
}

/// What planning needs to know of a dataset.
#[derive(Debug, Clone)]
pub struct DatasetInfo {
    /// Absolute directory.
    pub dir: PathBuf,
    /// Content hash.
    pub sha256: String,
    /// Its sequences, in dataset order.
    pub sequences: Vec<SequenceInfo>,
}

impl DatasetInfo {
    /// Reads what planning needs of the dataset at `dir` (absolute) for `robot`.
    pub fn read(dir: PathBuf, robot: &RobotModel) -> Result<Self, DataError> {
        let ds = Dataset::open(&dir, robot)?;
        let sequences = ds.load_all()?;
        Ok(Self {
            sha256: ds.content_hash(),
            sequences: sequences
                .iter()
                .map(|s| SequenceInfo {
                    task: s.task.clone(),
                    sequence_id: s.sequence_id.clone(),
                    duration_s: s.duration_s(),
                    forces_recorded: s.forces_recorded,
                })
                .collect(),
            dir,
        })
    }
}

/// What planning needs to know of one sequence.
#[derive(Debug, Clone)]
pub struct SequenceInfo {
    /// Task.
    pub task: String,
    /// Sequence id.
    pub sequence_id: String,
    /// Duration, s.
    pub duration_s: f64,
    /// Whether it has force logs (a replay setting on a dataset with none is refused, as
    /// `eval` refuses it).
    pub forces_recorded: bool,
}

impl Plan {
    /// Expands `spec` (read from `spec_path`, absolute) over `datasets` (the spec's
    /// datasets, resolved and opened, in the spec's order).
    ///
    /// Cells are numbered policy-major: policy, engine, dataset, latency rule, setting
    /// (innermost); each cell's shards are consecutive tasks.
    pub fn expand(
        spec: &SweepSpec,
        spec_path: &Path,
        datasets: &[DatasetInfo],
    ) -> Result<Self, SweepError> {
        let workdir = spec_path.parent().unwrap_or(Path::new("/")).to_path_buf();
        let invalid = |message: String| SweepError::Invalid {
            path: spec_path.to_path_buf(),
            message,
        };
        let selection = SequenceSelection {
            tasks: spec.tasks.clone(),
            sequences: spec.sequences.clone(),
        };
        let durations = selected_durations(spec, datasets, &selection).map_err(invalid)?;
        check_shards(spec, &durations).map_err(invalid)?;
        super::axes::refuse_equivalent(spec, spec_path, datasets)?;
        // Every rule's budget parses, whichever policies it ends up applied to.
        for l in spec.latency_rules() {
            parse_budget(&l.budget)
                .map_err(|e| invalid(format!("latency rule `{}`: budget: {e}", l.label())))?;
        }
        let mut cells = Vec::new();
        let mut tasks = Vec::new();
        for p in &spec.policies {
            let policy = policy_axis(p, &workdir).map_err(invalid)?;
            // An in-process policy has no round trip to time: it runs under the rules that
            // do not time it, so no latency curve is drawn over an axis that never varied.
            let in_process = policy.policy.in_process();
            let rules: Vec<_> = spec
                .latency_rules()
                .into_iter()
                .filter(|l| !(in_process && l.times_the_policy()))
                .collect();
            if rules.is_empty() {
                return Err(invalid(format!(
                    "policy `{}` runs in process, where no budget or measured latency applies, and every `[[latency]]` rule sets one: add a lock-step rule (`[[latency]]` with `name = \"lock-step\"`) or run the policy as a process (`command = …`)",
                    policy.name
                )));
            }
            for e in spec.engine_axis() {
                let engine = EngineAxis {
                    name: e.label(),
                    engine: e.engine.clone(),
                    mjcf: e.mjcf.as_deref().map(|m| resolve(&workdir, m)),
                    physics_dt_s: e.physics_dt_s,
                };
                for (ds, durations_s) in datasets.iter().zip(&durations) {
                    for l in &rules {
                        let latency = LatencyRule {
                            name: l.label(),
                            budget: l.budget.clone(),
                            mode: l.mode.clone(),
                            miss_rule: l.miss_rule.clone(),
                        };
                        for setting in &spec.settings {
                            let cell = Cell {
                                index: cells.len(),
                                policy: policy.clone(),
                                dataset: ds.dir.clone(),
                                dataset_sha256: ds.sha256.clone(),
                                selection: selection.clone(),
                                setting: setting.setting.clone(),
                                latency: latency.clone(),
                                engine: engine.clone(),
                                shards: spec.shards,
                                episodes: durations_s.len(),
                                simulated_s: durations_s.iter().sum(),
                            };
                            push_shards(&mut tasks, &spec.robot, &cell).map_err(|m| {
                                invalid(format!(
                                    "cell {} (policy `{}`): {m}",
                                    cell.index, policy.name
                                ))
                            })?;
                            cells.push(cell);
                        }
                    }
                }
            }
        }
        let mut plan = Self {
            format: PLAN_FORMAT,
            thorarena_version: env!("CARGO_PKG_VERSION").into(),
            spec: spec_path.to_path_buf(),
            workdir,
            robot: spec.robot.clone(),
            cells,
            tasks,
            seal: String::new(),
        };
        plan.check()
            .map_err(|m| invalid(format!("the expanded plan is inconsistent: {m}")))?;
        plan.seal = plan.seal_of();
        Ok(plan)
    }

    /// SHA-256 (hex) of this plan's JSON with an empty [`Plan::seal`].
    pub fn seal_of(&self) -> String {
        let unsealed = Self {
            seal: String::new(),
            ..self.clone()
        };
        let json = serde_json::to_vec(&unsealed).expect("a plan serializes");
        crate::sim::motion::sha256_hex(&json)
    }

    /// Writes this plan into sweep directory `dir` (its `tasks/` and `plan.json`, whole or
    /// not at all), or finds it there already: `Ok(false)` then. A directory holding
    /// another plan is refused, saying what differs: tasks may be running under its
    /// numbering.
    pub fn place(&self, dir: &Path) -> Result<bool, SweepError> {
        let path = dir.join(PLAN_FILE);
        if path.exists() {
            let existing = Self::load(dir)?;
            return match diff_plans(&existing, self) {
                None => Ok(false),
                Some(change) => Err(SweepError::Invalid {
                    path: dir.to_path_buf(),
                    message: format!(
                        "holds another plan ({change}); tasks may be running under its numbering, so it is not replaced: plan into a new directory"
                    ),
                }),
            };
        }
        let tasks = dir.join("tasks");
        crate::files::no_follow::make_dir_within(dir, &tasks).map_err(|source| SweepError::Io {
            path: tasks,
            source,
        })?;
        let json = serde_json::to_string(self).expect("a plan serializes");
        super::write_atomic(&path, json.as_bytes())?;
        Ok(true)
    }

    /// Reads `DIR/plan.json`, refusing another format version.
    pub fn load(dir: &Path) -> Result<Self, SweepError> {
        let path = dir.join(PLAN_FILE);
        let text = crate::files::bounded_read::read_to_string(&path, "sweep plan", MAX_PLAN_BYTES)
            .map_err(|source| SweepError::Io {
                path: path.clone(),
                source,
            })?;
        let format = serde_json::from_str::<serde_json::Value>(&text)
            .ok()
            .and_then(|v| v.get("format").and_then(|f| f.as_u64()));
        if format != Some(u64::from(PLAN_FORMAT)) {
            return Err(SweepError::BadRecord {
                path,
                message: format!(
                    "sweep format {} (this ThorArena {} reads format {PLAN_FORMAT}): plan the sweep again in a new directory",
                    format.map_or("unknown".into(), |f| f.to_string()),
                    env!("CARGO_PKG_VERSION")
                ),
            });
        }
        let plan: Self = serde_json::from_str(&text).map_err(|e| SweepError::BadRecord {
            path: path.clone(),
            message: e.to_string(),
        })?;
        plan.check().map_err(|m| SweepError::BadRecord {
            path: path.clone(),
            message: format!(
                "{m}: the plan does not hold what it claims (edited or damaged); plan the sweep again in a new directory"
            ),
        })?;
        if plan.seal != plan.seal_of() {
            return Err(SweepError::BadRecord {
                path,
                message: "it was changed after `sweep plan` wrote it (its seal does not match its content), so none of it runs: plan the sweep again (edit the spec, not the plan)".into(),
            });
        }
        Ok(plan)
    }

    /// Simulated seconds of all tasks.
    pub fn simulated_s(&self) -> f64 {
        self.cells.iter().map(|c| c.simulated_s).sum()
    }

    /// Episodes of all tasks.
    pub fn episodes(&self) -> usize {
        self.tasks.iter().map(|t| t.episodes).sum()
    }

    /// A task's directory.
    pub fn task_dir(dir: &Path, index: usize) -> PathBuf {
        dir.join("tasks").join(format!("{index:06}"))
    }

    /// A cell's directory (merged shards).
    pub fn cell_dir(dir: &Path, index: usize) -> PathBuf {
        dir.join("cells").join(format!("{index:06}"))
    }
}

/// Each dataset's durations of the sequences `selection` picks, s. A setting that replays
/// recorded forces is refused on a dataset none of whose picked sequences has force logs:
/// it would run as no-force under another name.
fn selected_durations(
    spec: &SweepSpec,
    datasets: &[DatasetInfo],
    selection: &SequenceSelection,
) -> Result<Vec<Vec<f64>>, String> {
    let mut durations: Vec<Vec<f64>> = Vec::new();
    for (spelled, ds) in spec.datasets.iter().zip(datasets) {
        let picked = selection
            .pick(ds.sequences.iter().collect(), |q| (&q.task, &q.sequence_id))
            .map_err(|e| format!("`tasks`/`sequences` in dataset `{spelled}`: {e}"))?;
        if picked.iter().all(|q| !q.forces_recorded) {
            let replaying = spec
                .settings
                .iter()
                .find(|s| s.setting.coefficient != 0.0)
                .map(|s| &s.spelled);
            if let Some(setting) = replaying {
                return Err(format!(
                    "setting `{setting}` replays recorded hand forces, but no sequence of dataset `{spelled}` has force logs (imported without force logs): it would run as no-force under another name; use no-force or push:<N>"
                ));
            }
        }
        durations.push(picked.iter().map(|q| q.duration_s).collect());
    }
    Ok(durations)
}

/// Every shard must get an episode of every dataset (`durations`: one per episode).
/// Checked before anything is allocated per task: a shard without an episode is no work,
/// and `shards = 10⁹` would exhaust memory planning empty tasks.
fn check_shards(spec: &SweepSpec, durations: &[Vec<f64>]) -> Result<(), String> {
    for (spelled, d) in spec.datasets.iter().zip(durations) {
        if spec.shards > d.len() {
            return Err(format!(
                "`shards` = {} but dataset `{spelled}` has {} episodes per cell: at most {} shards",
                spec.shards,
                d.len(),
                d.len()
            ));
        }
    }
    Ok(())
}

/// The policy `p` as planned: paths made absolute against `workdir`, a command run
/// there, the profile defaulting to the policy's own (`PolicySource::default_profile`).
fn policy_axis(p: &PolicySpec, workdir: &Path) -> Result<PolicyAxis, String> {
    let policy = p.source(workdir)?;
    Ok(PolicyAxis {
        name: p.label(),
        // The resolved path: a published network's own profile is found by content.
        profile: p
            .resolved_profile(workdir)
            .unwrap_or_else(|| policy.default_profile().to_string()),
        network_sha256: planned_network(&policy),
        policy,
        keypoints: p.keypoints.clone(),
        unchecked: p.unchecked,
    })
}

/// The SHA-256 of the network file `policy` names, if it names one that can be read.
pub(super) fn planned_network(policy: &PolicySource) -> Option<String> {
    let (_, network) = crate::policy::network_file::NetworkFile::read(policy.file()?).ok()?;
    Some(network.sha256)
}

/// Appends the tasks of `cell`, one per shard, numbered on from those in `tasks`; `Err`
/// says which of the cell's values no evaluation takes.
fn push_shards(tasks: &mut Vec<Task>, robot: &str, cell: &Cell) -> Result<(), String> {
    for i in 0..cell.shards {
        let shard = (i, cell.shards);
        tasks.push(Task {
            index: tasks.len(),
            cell: cell.index,
            shard,
            episodes: shard_episodes(cell.episodes, shard),
            request: task_request(robot, cell, shard)?,
        });
    }
    Ok(())
}

/// Episodes of shard `(i, n)` of `episodes` (one setting): the jobs `j` with
/// `j % n == i`, as [`crate::eval::schedule`] deals them, counted without listing them.
pub(super) fn shard_episodes(episodes: usize, (i, n): (usize, usize)) -> usize {
    if n == 0 || i >= episodes {
        0
    } else {
        (episodes - 1 - i) / n + 1
    }
}

/// The evaluation of one shard of `cell`: the cell's values in an [`EvalRequest`], each
/// one `eval` would otherwise take as a flag; `Err` names a latency rule or engine that
/// is none of the spellings `eval` takes.
pub(super) fn task_request(
    robot: &str,
    cell: &Cell,
    shard: (usize, usize),
) -> Result<EvalRequest, String> {
    let latency = &cell.latency;
    let budget = parse_budget(&latency.budget)
        .map_err(|e| format!("latency rule `{}`: budget: {e}", latency.name))?;
    fn spelled<T: serde::de::DeserializeOwned>(value: &str) -> Option<T> {
        serde_json::from_value(serde_json::Value::String(value.to_string())).ok()
    }
    let not_taken = |what: &str, value: &str| {
        format!(
            "latency rule `{}`: {what} `{value}` is none of those an evaluation takes",
            latency.name
        )
    };
    let engine = spelled(&cell.engine.engine).ok_or_else(|| {
        format!(
            "engine `{}`: `{}` is not rapier or mujoco",
            cell.engine.name, cell.engine.engine
        )
    })?;
    Ok(EvalRequest {
        policy: cell.policy.policy.clone(),
        dataset: Some(cell.dataset.clone()),
        robot: robot.to_string(),
        profile: Some(cell.policy.profile.clone()),
        unchecked: cell.policy.unchecked,
        settings: vec![cell.setting.clone()],
        selection: cell.selection.clone(),
        keypoints: cell.policy.keypoints.clone(),
        engine,
        mjcf: cell.engine.mjcf.clone(),
        physics_dt_s: cell.engine.physics_dt_s,
        io: PolicyIoRules {
            miss_rule: spelled(&latency.miss_rule)
                .ok_or_else(|| not_taken("miss rule", &latency.miss_rule))?,
            latency_mode: spelled(&latency.mode)
                .ok_or_else(|| not_taken("latency mode", &latency.mode))?,
            budget_s: budget.0.map(|b| b.as_secs_f64()),
            ..PolicyIoRules::default()
        },
        shard: (shard.1 > 1).then_some(shard),
        ..EvalRequest::default()
    })
}

/// The first difference between an existing plan and a new one, for a refusal that says
/// what changed; `None` when they plan the same work.
pub fn diff_plans(old: &Plan, new: &Plan) -> Option<String> {
    if old.cells.len() != new.cells.len() || old.tasks.len() != new.tasks.len() {
        return Some(format!(
            "{} cells / {} tasks planned, the spec now gives {} cells / {} tasks",
            old.cells.len(),
            old.tasks.len(),
            new.cells.len(),
            new.tasks.len()
        ));
    }
    for (a, b) in old.cells.iter().zip(&new.cells) {
        if a != b {
            let what = if a.policy != b.policy {
                format!("policy `{}` → `{}`", a.policy.name, b.policy.name)
            } else if a.dataset != b.dataset || a.dataset_sha256 != b.dataset_sha256 {
                format!(
                    "dataset {} ({}) → {} ({})",
                    a.dataset.display(),
                    &a.dataset_sha256[..a.dataset_sha256.len().min(12)],
                    b.dataset.display(),
                    &b.dataset_sha256[..b.dataset_sha256.len().min(12)]
                )
            } else if a.setting != b.setting {
                format!(
                    "setting `{}` → `{}`",
                    a.setting.spelling(),
                    b.setting.spelling()
                )
            } else if a.latency != b.latency {
                format!("latency `{}` → `{}`", a.latency.name, b.latency.name)
            } else if a.engine != b.engine {
                format!("engine `{}` → `{}`", a.engine.name, b.engine.name)
            } else {
                "shards or episodes".to_string()
            };
            return Some(format!("cell {}: {what}", a.index));
        }
    }
    if old.tasks != new.tasks {
        return Some("the tasks' evaluations differ".into());
    }
    None
}
