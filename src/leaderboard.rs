//! The leaderboard (`thorarena leaderboard`): every policy given, on one dataset, with and
//! without force, on each engine asked — one ordinary `eval` run per (policy, engine),
//! resumed where it stopped — summarised in one table; and single-clip policies, each on
//! its own clip under pushes of increasing force, in a table of their own. The paper's tables and figures over
//! the same runs are `report`'s (the command writes them beside the table).
//!
//! Each run is exactly what `eval` with the same flags writes (the same `EvalSpec`, the
//! same `benchmark::evaluate`, the sanity check first), so a leaderboard row can be
//! re-derived by one `eval`.

use crate::benchmark::{evaluate, BenchmarkError, EvalObserver, EvalOptions};
use crate::evaluation::{EngineChoice, EvalRequest, EvalSpec, SpecError};
use crate::registry::{self, PolicyChoice, RegistryError};
use crate::results::{RunDir, Summary};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Why the leaderboard could not be made.
#[derive(Debug, thiserror::Error)]
pub enum LeaderboardError {
    /// An evaluation's request is invalid.
    #[error("{policy} on {engine}: {source}")]
    Spec {
        /// The policy argument.
        policy: String,
        /// The engine.
        engine: &'static str,
        /// Why.
        source: Box<SpecError>,
    },
    /// The policy could not be loaded.
    #[error("{policy}: {source}")]
    Policy {
        /// The policy argument.
        policy: String,
        /// Why.
        source: Box<RegistryError>,
    },
    /// A policy that runs in its own process: the leaderboard runs networks in process.
    #[error("{0} is a policy process; the leaderboard runs policies in process (a network file: twist2:, beyondmimic:, wbc-mjlab:, or a built-in)")]
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
    /// No policy or no engine.
    #[error("the leaderboard needs at least one policy and one engine")]
    Empty,
}

/// A single-clip policy and the dataset of its own clip.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct OwnClip {
    /// The policy argument.
    pub policy: String,
    /// The dataset holding its clip.
    pub dataset: PathBuf,
}

impl OwnClip {
    /// `POLICY@DATASET` (split at the last `@`).
    pub fn parse(text: &str) -> Option<Self> {
        let (policy, dataset) = text.rsplit_once('@')?;
        (!policy.is_empty() && !dataset.is_empty()).then(|| Self {
            policy: policy.to_string(),
            dataset: PathBuf::from(dataset),
        })
    }
}

/// What to put on the leaderboard.
#[derive(Debug, Clone)]
pub struct LeaderboardRequest {
    /// Policy arguments as `eval --policy` takes them (in process).
    pub policies: Vec<String>,
    /// Single-clip policies, each on its own clip under [`Self::clip_settings`].
    pub clips: Vec<OwnClip>,
    /// The settings of the single-clip table.
    pub clip_settings: Vec<String>,
    /// The engines, each policy running on every one.
    pub engines: Vec<EngineChoice>,
    /// The dataset.
    pub dataset: PathBuf,
    /// Settings, as `eval --settings` spells them.
    pub settings: Vec<String>,
    /// Directory of the runs (`<out>/runs/<policy>-<engine>`, `…-own-clip` for a
    /// single-clip policy).
    pub out: PathBuf,
    /// Score policies without their sanity check (recorded in each run).
    pub unchecked: bool,
}

/// One (policy, engine) run of the leaderboard.
#[derive(Debug, Clone)]
pub struct Entry {
    /// The policy argument.
    pub policy: String,
    /// Whether it is a single-clip policy on its own clip.
    pub own_clip: bool,
    /// The engine's name.
    pub engine: &'static str,
    /// The run directory.
    pub run: PathBuf,
    /// Its scores.
    pub summary: Summary,
    /// Wall time of this invocation's part of it, s (0 for a run already complete).
    pub wall_s: f64,
}

/// Hears the leaderboard's progress.
pub trait LeaderboardObserver {
    /// Run `index` of `total` is starting: `policy` on `engine` into `run`.
    fn run_starting(&mut self, _index: usize, _total: usize, _policy: &str, _engine: &str) {}
    /// The observer of that run's evaluation.
    fn eval_observer(&mut self) -> &mut dyn EvalObserver;
}

/// The run directory's name of `policy` on `engine`: the family and the network's file
/// stem (`wbc-mjlab-wbc_g1_policy-rapier`), or the built-in's name.
pub fn run_name(policy: &str, engine: EngineChoice) -> String {
    let base = match registry::policy_file_stem(policy) {
        Some((family, stem)) => format!("{family}-{stem}"),
        None => policy.to_string(),
    };
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
    format!("{clean}-{}", engine_name(engine))
}

fn engine_name(engine: EngineChoice) -> &'static str {
    match engine {
        EngineChoice::Rapier => "rapier",
        EngineChoice::Mujoco => "mujoco",
    }
}

/// Runs every (policy, engine) of `request`, resuming runs already started, engine by
/// engine in the order given.
pub fn run_leaderboard(
    request: &LeaderboardRequest,
    observer: &mut dyn LeaderboardObserver,
) -> Result<Vec<Entry>, LeaderboardError> {
    if (request.policies.is_empty() && request.clips.is_empty()) || request.engines.is_empty() {
        return Err(LeaderboardError::Empty);
    }
    let general = request.policies.iter().map(|p| OwnClip {
        policy: p.clone(),
        dataset: request.dataset.clone(),
    });
    let runs: Vec<(OwnClip, bool)> = general
        .map(|g| (g, false))
        .chain(request.clips.iter().map(|c| (c.clone(), true)))
        .collect();
    let total = runs.len() * request.engines.len();
    let mut entries = Vec::new();
    for &engine in &request.engines {
        for (what, own_clip) in &runs {
            let engine_name = engine_name(engine);
            let name = run_name(&what.policy, engine);
            let run = request.out.join("runs").join(if *own_clip {
                format!("{name}-own-clip")
            } else {
                name
            });
            observer.run_starting(entries.len(), total, &what.policy, engine_name);
            let started = Instant::now();
            let settings = if *own_clip {
                &request.clip_settings
            } else {
                &request.settings
            };
            let summary = run_one(
                request,
                what,
                settings,
                engine,
                &run,
                observer.eval_observer(),
            )?;
            entries.push(Entry {
                policy: what.policy.clone(),
                own_clip: *own_clip,
                engine: engine_name,
                run,
                summary,
                wall_s: started.elapsed().as_secs_f64(),
            });
        }
    }
    Ok(entries)
}

fn run_one(
    request: &LeaderboardRequest,
    what: &OwnClip,
    settings: &[String],
    engine: EngineChoice,
    run: &Path,
    observer: &mut dyn EvalObserver,
) -> Result<Summary, LeaderboardError> {
    let policy = what.policy.as_str();
    let engine_name = engine_name(engine);
    let spec = EvalSpec::load(&EvalRequest {
        policy: policy.to_string(),
        dataset: Some(what.dataset.clone()),
        settings: settings.to_vec(),
        engine,
        unchecked: request.unchecked,
        ..EvalRequest::default()
    })
    .map_err(|source| LeaderboardError::Spec {
        policy: policy.to_string(),
        engine: engine_name,
        source: Box::new(source),
    })?;
    let choice = registry::policy(policy, &spec.robot, &spec.profile).map_err(|source| {
        LeaderboardError::Policy {
            policy: policy.to_string(),
            source: Box::new(source),
        }
    })?;
    let PolicyChoice::InProcess(mut p) = choice else {
        return Err(LeaderboardError::NotInProcess(policy.to_string()));
    };
    let dir = RunDir::new(run);
    let options = EvalOptions {
        resume: dir.header_file().exists(),
        trace_first_s: None,
    };
    let evaluated = evaluate(&spec, p.as_mut(), &dir, options, observer).map_err(|source| {
        LeaderboardError::Eval {
            policy: policy.to_string(),
            engine: engine_name,
            source: Box::new(source),
        }
    })?;
    Ok(evaluated.summary)
}

/// The leaderboard as one Markdown table: per (policy, engine), FATS with its 95 %
/// interval, survival and keypoint error under each setting of the runs (the first
/// entry's, in its order), and the wall time. Give it the general entries, or the
/// own-clip ones.
pub fn leaderboard_table(entries: &[&Entry]) -> String {
    let settings: Vec<String> = entries
        .first()
        .map(|e| {
            e.summary
                .header
                .settings
                .iter()
                .map(|s| s.name.clone())
                .collect()
        })
        .unwrap_or_default();
    let mut out = String::from("| policy | engine |");
    let mut rule = String::from("|---|---|");
    for s in &settings {
        out.push_str(&format!(
            " FATS {s} (95 % CI) | survival {s} | keypoint error {s} (mm) |"
        ));
        rule.push_str("---:|---:|---:|");
    }
    out.push_str(" wall time |\n");
    rule.push_str("---:|\n");
    out.push_str(&rule);
    for e in entries {
        out.push_str(&format!("| {} | {} |", policy_label(&e.policy), e.engine));
        for s in &settings {
            match e.summary.settings.get(s.as_str()) {
                Some(r) => {
                    let ci = r
                        .fats_ci95
                        .map(|[lo, hi]| format!(" ({lo:.1}–{hi:.1})"))
                        .unwrap_or_default();
                    out.push_str(&format!(
                        " {:.1}{ci} | {:.3} | {:.1} |",
                        r.average.fats, r.average.survival, r.average.kp_mm
                    ));
                }
                None => out.push_str(" – | – | – |"),
            }
        }
        out.push_str(&format!(" {} |\n", minutes(e.wall_s)));
    }
    out
}

/// A policy argument as a table names it: `family (file stem)` for a network
/// (`twist2 (twist2_1017_25k)`), the argument itself otherwise.
pub fn policy_label(policy: &str) -> String {
    match registry::policy_file_stem(policy) {
        Some((family, stem)) => format!("{family} ({stem})"),
        None => policy.to_string(),
    }
}

fn minutes(s: f64) -> String {
    if s < 60.0 {
        format!("{s:.0} s")
    } else {
        format!("{} min {:02.0} s", (s / 60.0).floor(), s % 60.0)
    }
}
