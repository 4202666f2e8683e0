//! [`EvalRequest`]: one evaluation as asked for, in plain values — what `eval`'s flags
//! say, what a sweep task stores in its plan, and what a request file holds
//! (`eval --request`). [`super::EvalSpec::load`] checks it.

use super::{PolicyIoRules, Setting, TerminationRule};
use crate::policy::registry::PolicySource;
use crate::sim::motion::SequenceSelection;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Which engine simulates the run, before its model is checked.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EngineChoice {
    /// rapier, built in.
    #[default]
    Rapier,
    /// MuJoCo (a build with the `mujoco` feature).
    Mujoco,
}

impl EngineChoice {
    /// The engine's name, as `--engine` takes it and tables print it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Rapier => "rapier",
            Self::Mujoco => "mujoco",
        }
    }
}

/// An evaluation as asked for, in plain values; every field is checked by
/// [`super::EvalSpec::load`]. `eval` builds one from its flags; a sweep task stores one in the
/// plan (serialized: JSON, every field named, an unknown one refused) and hands it to its
/// `eval` process as a file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct EvalRequest {
    /// Where the policy comes from (`balance`, `twist2:FILE`, `ipc:SESSION`, a command to
    /// start, …; a file spells an argument as its string): its family picks the profile
    /// when none is named.
    pub policy: PolicySource,
    /// Dataset directory (`None`: the bundled sample).
    pub dataset: Option<PathBuf>,
    /// Robot name or directory.
    pub robot: String,
    /// Profile name or `.toml` path (`None`: the policy family's).
    pub profile: Option<String>,
    /// Run under a profile the policy family was not trained with.
    pub profile_mismatch_ok: bool,
    /// Score the policy without its sanity check (recorded in `run.json`).
    pub unchecked: bool,
    /// Settings (empty: [`super::DEFAULT_SETTINGS`], or `no-force` alone on a dataset
    /// without force logs); a file spells each as `eval --settings` takes it.
    #[serde(with = "super::setting::spelled")]
    pub settings: Vec<Setting>,
    /// Run replay settings on a dataset without force logs.
    pub replay_without_force_logs: bool,
    /// Tasks and sequences to evaluate.
    pub selection: SequenceSelection,
    /// Worker threads (`None`: every core).
    pub workers: Option<usize>,
    /// Environment slots (`None`: one per worker).
    pub envs: Option<usize>,
    /// Slot groups in the pipeline (1: lock-step; 2: the workers step one half of the
    /// slots while the policy answers for the other half). See [`super::MAX_PIPELINE_DEPTH`].
    pub pipeline_depth: usize,
    /// Keypoint set of the tracking error.
    pub keypoints: String,
    /// When an episode has failed.
    pub termination: TerminationRule,
    /// Sequences (`TASK/SEQUENCE_ID`) whose rollouts are written as traces.
    pub trace: Vec<String>,
    /// The engine.
    pub engine: EngineChoice,
    /// A user's MJCF for MuJoCo (`None`: generated from the robot model).
    pub mjcf: Option<PathBuf>,
    /// A physics step, s, instead of the profile's.
    pub physics_dt_s: Option<f64>,
    /// The rules of the policy's answers.
    pub io: PolicyIoRules,
    /// `(i, n)`: only shard i of n of the schedule.
    pub shard: Option<(usize, usize)>,
}

impl Default for EvalRequest {
    fn default() -> Self {
        Self {
            policy: PolicySource::builtin("balance").expect("`balance` is a built-in"),
            dataset: None,
            robot: "g1_29dof".into(),
            profile: None,
            profile_mismatch_ok: false,
            unchecked: false,
            settings: Vec::new(),
            replay_without_force_logs: false,
            selection: SequenceSelection::default(),
            workers: None,
            envs: None,
            pipeline_depth: 1,
            keypoints: "default".into(),
            termination: TerminationRule::default(),
            trace: Vec::new(),
            engine: EngineChoice::Rapier,
            mjcf: None,
            physics_dt_s: None,
            io: PolicyIoRules::default(),
            shard: None,
        }
    }
}

/// The largest request file read, bytes (16 MiB): a request is a few kilobytes, even
/// with thousands of sequences named.
pub const MAX_REQUEST_FILE_BYTES: u64 = 16 << 20;

/// Why a request file cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum RequestFileError {
    /// The file cannot be read.
    #[error("reading {}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// It is not a request (a field unknown, missing a value, or of the wrong type).
    #[error("{} is not an evaluation request: {source}", path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: serde_json::Error,
    },
}

impl EvalRequest {
    /// The request in file `path` (JSON; a field left out takes its default).
    pub fn read(path: &Path) -> Result<Self, RequestFileError> {
        let text = crate::files::bounded_read::read_to_string(
            path,
            "request file",
            MAX_REQUEST_FILE_BYTES,
        )
        .map_err(|source| RequestFileError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        serde_json::from_str(&text).map_err(|source| RequestFileError::Parse {
            path: path.to_path_buf(),
            source,
        })
    }

    /// Writes the request to `path` (its directory made if missing), atomically.
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir)?;
        }
        let json = serde_json::to_string_pretty(self).expect("an EvalRequest serialises");
        crate::files::atomic_file::write(path, json)
    }
}

/// A shard `I/N` as a user writes it (`0/4`: the first of four), checked: `0 <= I < N`.
pub fn parse_shard(s: &str) -> Result<(usize, usize), String> {
    let (i, n) = s.split_once('/').ok_or("expected I/N, e.g. 0/4")?;
    let (i, n): (usize, usize) = (
        i.parse().map_err(|_| "I is not a number")?,
        n.parse().map_err(|_| "N is not a number")?,
    );
    check_shard(i, n)?;
    Ok((i, n))
}

/// The one rule of a shard `I/N`, for `--shard` and a request file's `shard` alike.
pub fn check_shard(i: usize, n: usize) -> Result<(), String> {
    if n == 0 || i >= n {
        return Err(format!("shard {i}/{n}: need 0 <= I < N"));
    }
    Ok(())
}
