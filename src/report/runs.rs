//! Reading run directories back for reports, and checking that runs may be compared.
//!
//! Scores are recomputed from `episodes.jsonl` with the run's own regime thresholds
//! (`summary.json`), through the same [`summarize`] the run used: the result is the run's
//! own numbers, and undefined diagnostics stay NaN (JSON wrote them as `null`).

use super::ReportError;
use crate::eval::metrics::{score_episode, Diagnostics, RegimeThresholds, TaskSummary, SIGMA_M};
use crate::eval::results::{
    read_header, read_summary, summarize, Coverage, EpisodeLog, PolicyIoReport, RunHeader,
    SettingResults, EPISODES_FILE,
};
use crate::eval::EpisodeRecord;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// One run directory, read back and scored.
#[derive(Debug, Clone)]
pub struct Run {
    /// The directory as given.
    pub dir: PathBuf,
    /// Name in tables and legends: the policy, made unique among the compared runs.
    pub label: String,
    /// `run.json`.
    pub header: RunHeader,
    /// `episodes.jsonl`.
    pub records: Vec<EpisodeRecord>,
    /// Regime thresholds per task (`summary.json`).
    pub thresholds: BTreeMap<String, RegimeThresholds>,
    /// Per setting: task summaries and the average over tasks.
    pub results: SettingResults,
    /// Latency and faults of the policy, when the run measured them.
    pub policy_io: Option<PolicyIoReport>,
    /// Episodes present and expected per (setting, task): a run stopped early, cut short
    /// or with a failed policy is read as partial and every table says so.
    pub coverage: Coverage,
    /// `episodes.jsonl` ended in a line cut short (a run killed mid-write).
    pub torn_tail: bool,
}

/// One episode's place on the tracking-vs-survival plane.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct EpisodePoint {
    /// Index of the run in the compared list.
    pub run: usize,
    /// Setting name.
    pub setting: String,
    /// Task.
    pub task: String,
    /// Sequence id.
    pub sequence_id: String,
    /// Tracking score `100·exp(−E_i/σ)` (the episode score before survival scales it;
    /// 0 when the episode ended before its first step).
    pub tracking: f64,
    /// Survival `s_i`.
    pub survival: f64,
    /// Episode score `S_i`.
    pub score: f64,
    /// Why it ended early (`torso_tilt`, …), if it did.
    pub termination: Option<String>,
}

impl Run {
    /// Setting names in the run's schedule order (those with results).
    pub fn settings(&self) -> Vec<String> {
        let mut names: Vec<String> = self
            .header
            .settings
            .iter()
            .map(|s| s.name.clone())
            .filter(|s| self.results.contains_key(s))
            .collect();
        // Settings present in the records but not in the header (never written by
        // `eval`, but a hand-edited run should still show them).
        let extra: Vec<String> = self
            .results
            .keys()
            .filter(|k| !names.contains(k))
            .cloned()
            .collect();
        names.extend(extra);
        names
    }

    /// A task's summary under a setting.
    pub fn task(&self, setting: &str, task: &str) -> Option<&TaskSummary> {
        self.results.get(setting)?.0.iter().find(|t| t.task == task)
    }

    /// The average over tasks under a setting.
    pub fn average(&self, setting: &str) -> Option<&Diagnostics> {
        self.results.get(setting).map(|(_, d)| d)
    }

    /// Every episode scored (tracking score, survival, score), in record order.
    pub fn episode_points(&self, run_index: usize) -> Vec<EpisodePoint> {
        self.records
            .iter()
            .map(|r| {
                let th = RegimeThresholds::of_task(&self.thresholds, &r.task);
                let s = score_episode(&r.series, &th);
                EpisodePoint {
                    run: run_index,
                    setting: r.setting.clone(),
                    task: r.task.clone(),
                    sequence_id: r.sequence_id.clone(),
                    tracking: s.error_m.map_or(0.0, |e| 100.0 * (-e / SIGMA_M).exp()),
                    survival: s.survival,
                    score: s.score,
                    termination: r.termination.map(|t| {
                        serde_json::to_value(t)
                            .ok()
                            .and_then(|v| v.as_str().map(str::to_string))
                            .unwrap_or_default()
                    }),
                }
            })
            .collect()
    }
}

/// Reads one run directory (`run.json`, `episodes.jsonl`, `summary.json`), checking every
/// record against the header, and scores it. The label is the policy name; [`load_runs`]
/// makes labels unique. A run holding fewer episodes than it planned is read (its
/// [`Run::coverage`] says what is missing); a run holding none is an error.
pub fn load_run(dir: &Path) -> Result<Run, ReportError> {
    let header = read_header(dir)?;
    let summary = read_summary(dir)?;
    let log = EpisodeLog::read(&dir.join(EPISODES_FILE), &header)?;
    if log.records.is_empty() {
        return Err(ReportError::BadRun {
            path: dir.to_path_buf(),
            reason: "episodes.jsonl holds no finished episode".into(),
        });
    }
    let results = summarize(&log.records, &summary.thresholds);
    Ok(Run {
        dir: dir.to_path_buf(),
        label: header.policy.clone(),
        coverage: Coverage::of(&header, &log.records),
        torn_tail: log.torn_tail,
        header,
        records: log.records,
        thresholds: summary.thresholds,
        results,
        policy_io: summary.policy_io,
    })
}

/// Reads several runs, labelling each by its policy — or, when two runs share a policy
/// name, by policy and network (when their networks differ) or directory name (then by
/// position, if even those agree).
pub fn load_runs(dirs: &[PathBuf]) -> Result<Vec<Run>, ReportError> {
    let mut runs = dirs
        .iter()
        .map(|d| load_run(d))
        .collect::<Result<Vec<_>, _>>()?;
    label_runs(&mut runs);
    Ok(runs)
}

fn count_same(all: &[Option<String>], one: &Option<String>) -> usize {
    all.iter().filter(|x| *x == one).count()
}

/// Makes every run's label unique (see [`load_runs`]).
pub fn label_runs(runs: &mut [Run]) {
    let count = |labels: &[String], l: &str| labels.iter().filter(|x| *x == l).count();
    let policies: Vec<String> = runs.iter().map(|r| r.header.policy.clone()).collect();
    let mut labels: Vec<String> = runs
        .iter()
        .map(|r| {
            if count(&policies, &r.header.policy) > 1 {
                let same_policy = runs.iter().filter(|o| o.header.policy == r.header.policy);
                let networks: Vec<Option<String>> =
                    same_policy.map(|o| o.header.network_label()).collect();
                let network = r.header.network_label();
                if network.is_some() && count_same(&networks, &network) == 1 {
                    return format!("{} ({})", r.header.policy, network.unwrap_or_default());
                }
                let dir = r.dir.file_name().map_or_else(
                    || r.dir.display().to_string(),
                    |n| n.to_string_lossy().into(),
                );
                format!("{} ({dir})", r.header.policy)
            } else {
                r.header.policy.clone()
            }
        })
        .collect();
    let snapshot = labels.clone();
    for (i, l) in labels.iter_mut().enumerate() {
        if count(&snapshot, l) > 1 {
            *l = format!("{l} #{}", i + 1);
        }
    }
    for (r, l) in runs.iter_mut().zip(labels) {
        r.label = l;
    }
}

/// Why the commands that compare runs refuse to mix engines unless asked, for their
/// messages.
pub const MIXED_ENGINES_WHY: &str = "under force the engines' scores differ by up to 30 FATS points for the same policy (docs/engines.md, \"Force response: rapier against MuJoCo\")";

/// When the runs were simulated by more than one physics engine: the runs grouped by
/// engine (`a, b: rapier; c: mujoco`); `None` when one engine ran them all. Under force the
/// engines' scores differ (docs/engines.md, "Force response: rapier against MuJoCo"), so the
/// commands that compare runs refuse such a set unless asked (`--mixed-engines`).
pub fn mixed_engines(runs: &[Run]) -> Option<String> {
    grouped(
        runs.iter()
            .map(|r| (r.label.as_str(), r.header.engine.name().to_string())),
    )
}

/// Holds `runs` to one physics engine, or — with `mixed_ok` — labels each with its
/// engine; `Err` says which engines ran which runs and why they are not compared.
pub fn one_engine_or_labelled(runs: &mut [Run], mixed_ok: bool) -> Result<(), String> {
    match mixed_engines(runs) {
        Some(groups) if !mixed_ok => Err(format!(
            "these runs were simulated by different physics engines ({groups}); {MIXED_ENGINES_WHY}: compare runs of one engine, or give `option.mixed_engines` to compare them anyway (each label then names its engine)"
        )),
        Some(_) => {
            label_engines(runs);
            Ok(())
        }
        None => Ok(()),
    }
}

/// Appends each run's engine to its label (`twist2 [mujoco]`), for a comparison that
/// mixes engines on purpose.
pub fn label_engines(runs: &mut [Run]) {
    for r in runs {
        r.label = format!("{} [{}]", r.label, r.header.engine.name());
    }
}

/// What makes two runs' numbers incomparable.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum WarningKind {
    /// Different dataset content (sha256): different motions or forces.
    Dataset,
    /// Different dynamics profile (gains, control rate, delay).
    Profile,
    /// Different physics engine, robot model (MJCF) or physics step.
    Physics,
    /// Different termination rule: survival means something else.
    Termination,
    /// Different keypoint set: the tracking error measures other points.
    Keypoints,
    /// Different policy I/O rules (budget, miss rule, latency mode).
    PolicyIo,
    /// A setting of the same name with another coefficient or push.
    Settings,
    /// Different ThorArena versions (the simulator may have changed).
    Version,
    /// A shard of a run, not the whole run.
    Partial,
}

/// A reason the runs of a report must not be compared as they stand.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ComparisonWarning {
    /// What differs.
    pub kind: WarningKind,
    /// A sentence naming the runs and their values.
    pub message: String,
}

/// Groups labelled values: `a, b: x; c: y`; `None` when all values agree.
fn grouped<'a>(items: impl IntoIterator<Item = (&'a str, String)>) -> Option<String> {
    let mut groups: Vec<(String, Vec<&str>)> = Vec::new();
    for (label, v) in items {
        match groups.iter_mut().find(|(g, _)| *g == v) {
            Some((_, labels)) => labels.push(label),
            None => groups.push((v, vec![label])),
        }
    }
    (groups.len() > 1).then(|| {
        groups
            .iter()
            .map(|(v, labels)| format!("{}: {v}", labels.join(", ")))
            .collect::<Vec<_>>()
            .join("; ")
    })
}

/// The first 12 hex digits of a SHA-256: enough to tell contents apart in a sentence.
fn short_hash(hash: &str) -> &str {
    &hash[..hash.len().min(12)]
}

/// Differences that do not change what was measured, said for information: the same
/// dataset content read from different paths.
pub fn comparison_notes(runs: &[Run]) -> Vec<String> {
    let mut notes = Vec::new();
    if profiles_by_design(runs) {
        if let Some(groups) = grouped(runs.iter().map(|r| (r.label.as_str(), profile_of(r)))) {
            notes.push(format!(
                "each policy runs under the dynamics profile it was trained with (checked when it ran), so the profiles differ by design — {groups}"
            ));
        }
    }
    let mut by_hash: Vec<(&str, Vec<(&str, &str)>)> = Vec::new();
    for r in runs {
        let h = r.header.dataset_sha256.as_str();
        match by_hash.iter_mut().find(|(k, _)| *k == h) {
            Some((_, v)) => v.push((r.label.as_str(), r.header.dataset.as_str())),
            None => by_hash.push((h, vec![(r.label.as_str(), r.header.dataset.as_str())])),
        }
    }
    for (hash, runs) in by_hash {
        if let Some(paths) = grouped(runs.iter().map(|(l, p)| (*l, p.to_string()))) {
            notes.push(format!(
                "the same dataset (sha256 {}) was read from different paths — {paths}",
                short_hash(hash)
            ));
        }
    }
    notes
}

/// Every way the runs differ in what they measured (dataset, profile, termination rule,
/// keypoints, policy I/O rules, settings, version) and every partial run. Empty when the
/// runs are comparable.
pub fn comparison_warnings(runs: &[Run]) -> Vec<ComparisonWarning> {
    let mut out = configuration_warnings(runs);
    out.extend(setting_warnings(runs));
    for r in runs {
        out.extend(partial_warnings(r));
    }
    out
}

/// Header fields that differ between the runs, one warning per kind.
fn configuration_warnings(runs: &[Run]) -> Vec<ComparisonWarning> {
    let mut out = Vec::new();
    let mut flag = |kind, what: &str, value: &dyn Fn(&Run) -> String| {
        if let Some(groups) = grouped(runs.iter().map(|r| (r.label.as_str(), value(r)))) {
            out.push(ComparisonWarning {
                kind,
                message: format!("{what} differ — {groups}"),
            });
        }
    };
    // Datasets and MJCFs are the same when their content is (a path differs between a
    // cache copy and a checkout, or between machines: `comparison_notes` says so).
    flag(WarningKind::Dataset, "Datasets", &|r| {
        format!("sha256 {}", short_hash(&r.header.dataset_sha256))
    });
    if !profiles_by_design(runs) {
        flag(WarningKind::Profile, "Dynamics profiles", &profile_of);
    }
    flag(
        WarningKind::Physics,
        "Physics engines or steps",
        &physics_of,
    );
    flag(WarningKind::Termination, "Termination rules", &|r| {
        let t = r.header.termination;
        format!(
            "torso height error > {} m or tilt error > {} rad",
            crate::files::log_text::short_number(t.max_torso_height_error_m),
            crate::files::log_text::short_number(t.max_torso_tilt_error_rad)
        )
    });
    flag(WarningKind::Keypoints, "Keypoint sets", &|r| {
        format!("`{}`", r.header.keypoints)
    });
    flag(WarningKind::PolicyIo, "Policy I/O rules", &|r| {
        let io = r.header.io;
        format!(
            "budget {}, miss rule {:?}, latency mode {:?}, max |action| {}",
            io.budget_s
                .map_or("none".into(), |b| format!("{:.3} ms", b * 1e3)),
            io.miss_rule,
            io.latency_mode,
            io.max_abs_action
        )
    });
    flag(WarningKind::Version, "ThorArena versions", &|r| {
        r.header.version.clone()
    });
    out
}

/// A run's profile as the comparison names it.
fn profile_of(r: &Run) -> String {
    format!(
        "`{}` (control step {} s)",
        r.header.profile, r.header.control_dt_s
    )
}

/// Whether the runs' profiles differ only as their policies do: every run's profile was
/// checked against its policy's family when it ran (none overrode the check), and no
/// policy ran under two profiles. A leaderboard is such a comparison — each policy on
/// the profile it was trained with — and its profiles are a note, not a warning.
fn profiles_by_design(runs: &[Run]) -> bool {
    let mut profile_of_policy: Vec<(&str, &str)> = Vec::new();
    for r in runs {
        if r.header.profile_mismatch_ok {
            return false;
        }
        let (policy, profile) = (r.header.policy.as_str(), r.header.profile.as_str());
        match profile_of_policy.iter().find(|(p, _)| *p == policy) {
            Some((_, other)) if *other != profile => return false,
            Some(_) => {}
            None => profile_of_policy.push((policy, profile)),
        }
    }
    true
}

/// The engine, its model and step of a run, as the physics warning compares them.
fn physics_of(r: &Run) -> String {
    let model = match &r.header.engine {
        crate::sim::physics::Engine::Rapier => String::new(),
        crate::sim::physics::Engine::Mujoco {
            mjcf: Some(mjcf),
            mjcf_sha256,
        } => match mjcf_sha256 {
            Some(hash) => format!(" on an MJCF with sha256 {}", short_hash(hash)),
            None => format!(" on {}", mjcf.display()),
        },
        crate::sim::physics::Engine::Mujoco { mjcf: None, .. } => " on the generated MJCF".into(),
    };
    format!(
        "{}{model} at {} ms",
        r.header.engine.name(),
        r.header.physics_dt_s * 1e3
    )
}

/// Setting names that mean different coefficients or pushes in different runs.
fn setting_warnings(runs: &[Run]) -> Vec<ComparisonWarning> {
    let mut out = Vec::new();
    // A setting name must mean the same coefficient and push in every run that has it.
    let mut names: Vec<&str> = runs
        .iter()
        .flat_map(|r| r.header.settings.iter().map(|s| s.name.as_str()))
        .collect();
    names.sort();
    names.dedup();
    for name in names {
        let having = runs.iter().filter_map(|r| {
            let s = r.header.settings.iter().find(|s| s.name == name)?;
            let value = format!("coefficient {}, push {} N", s.coefficient, s.push_n);
            Some((r.label.as_str(), value))
        });
        if let Some(groups) = grouped(having) {
            out.push(ComparisonWarning {
                kind: WarningKind::Settings,
                message: format!("Setting `{name}` differs — {groups}"),
            });
        }
    }
    out
}

/// What a run lacks: episodes missing or cut short, a subset of its dataset, a shard.
fn partial_warnings(r: &Run) -> Vec<ComparisonWarning> {
    let mut out = Vec::new();
    if let Some(sentence) = r.coverage.sentence() {
        let cells: Vec<String> = r
            .coverage
            .cells
            .iter()
            .filter(|c| c.present != c.expected || c.policy_failed > 0)
            .map(|c| {
                format!(
                    "{}/{}: {} of {} present, {} cut short by a policy failure",
                    c.setting, c.task, c.present, c.expected, c.policy_failed
                )
            })
            .collect();
        let torn = if r.torn_tail {
            " (episodes.jsonl ends in a line cut short)"
        } else {
            ""
        };
        out.push(ComparisonWarning {
            kind: WarningKind::Partial,
            message: format!(
                "{} ({}) is a {sentence}{torn} — {}",
                r.label,
                r.dir.display(),
                cells.join("; ")
            ),
        });
    }
    if let Some(subset) = &r.header.subset {
        out.push(ComparisonWarning {
            kind: WarningKind::Partial,
            message: format!(
                "{} ({}) ran part of its dataset: {}",
                r.label,
                r.dir.display(),
                subset.describe(r.header.sequences.len())
            ),
        });
    }
    if let Some((i, n)) = r.header.shard {
        out.push(ComparisonWarning {
            kind: WarningKind::Partial,
            message: format!(
                "{} is shard {i}/{n} of a run ({}): partial results; `thorarena merge` the shards first",
                r.label,
                r.dir.display()
            ),
        });
    }
    out
}
