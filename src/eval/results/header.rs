//! `run.json`: what a run measured.

use super::{
    identity_differences, network_label, PolicyIdentity, ResultsError, HEADER_FILE, RESULTS_VERSION,
};
use crate::eval::{
    reference_steps, EpisodeKey, EvalSpec, PolicyIoRules, SanityRecord, Setting, TerminationRule,
};
use crate::sim::motion::{Reference, Sequence};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// One sequence the run plans to evaluate under every setting, with the control steps of
/// its reference: the length every episode record of it must declare.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct PlannedSequence {
    /// Task.
    pub task: String,
    /// Sequence id.
    pub sequence_id: String,
    /// Control steps of the reference (`T_ref`).
    pub steps_ref: usize,
}

impl PlannedSequence {
    /// The plan of `sequences` at control step `control_dt_s`, in dataset order.
    pub fn plan(sequences: &[Sequence], control_dt_s: f64) -> Vec<Self> {
        sequences
            .iter()
            .map(|seq| Self {
                task: seq.task.clone(),
                sequence_id: seq.sequence_id.clone(),
                steps_ref: reference_steps(Reference::new(seq).duration_s(), control_dt_s),
            })
            .collect()
    }
}

/// What identifies a run; runs may be merged or resumed only if these agree.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunHeader {
    /// [`RESULTS_VERSION`] of the writer.
    pub results_version: u32,
    /// ThorArena version.
    pub version: String,
    /// Policy name.
    pub policy: String,
    /// Profile name.
    pub profile: String,
    /// The profile contradicts the policy's family (`--profile-mismatch-ok`): a TWIST2
    /// network off its `twist2` profile, a BeyondMimic one off a BeyondMimic profile.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub profile_mismatch_ok: bool,
    /// The profile the policy process declared at connect, by name (its numbers are in
    /// the identity's profile fingerprint when the run took it); `None`: in process, or
    /// a process that declared none under a run's `--profile`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub declared_profile: Option<String>,
    /// The profile's control step (the clock of the metrics and regime thresholds), s.
    pub control_dt_s: f64,
    /// The physics step, s (the profile's, or `--physics-dt`).
    pub physics_dt_s: f64,
    /// The physics engine and its model of the robot.
    pub engine: crate::sim::physics::Engine,
    /// Dataset directory as given.
    pub dataset: String,
    /// Dataset content hash.
    pub dataset_sha256: String,
    /// Keypoint set.
    pub keypoints: String,
    /// Termination rule.
    pub termination: TerminationRule,
    /// Settings, in schedule order.
    pub settings: Vec<Setting>,
    /// The dataset's sequences, in dataset order (the schedule runs each under every
    /// setting).
    pub sequences: Vec<PlannedSequence>,
    /// The sequences chosen when not the whole dataset (`--tasks`, `--sequences`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub subset: Option<crate::sim::motion::Subset>,
    /// `(i, n)` when this run is shard i of n.
    pub shard: Option<(usize, usize)>,
    /// Rules of the policy's answers (miss rule, latency mode, budget).
    #[serde(default)]
    pub io: PolicyIoRules,
    /// What the sanity check said about the policy before the run (`None`: a run written
    /// before the check existed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sanity: Option<SanityRecord>,
    /// The instruction sets a network in process ran on (`x86_64,avx,avx2,fma` on every
    /// x86-64 machine that has them: `network_kernels`); `None` for policies
    /// without one. Part of the run's identity: shards and resumed parts must agree.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub network_kernels: Option<String>,
    /// The policy's parameters as it ran (SoftMimic's stiffness command: `Policy::parameters`),
    /// by name with their unit; empty for a policy without any.
    #[serde(default, skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub policy_parameters: std::collections::BTreeMap<String, f64>,
    /// Which policy ran, by content: its network file's SHA-256 and size, the profile's and
    /// the robot's fingerprints. `None`: a run written before runs recorded it, which
    /// reports say ("network not recorded") and which joins no run that has one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub identity: Option<PolicyIdentity>,
    /// The cells whose load lies outside what the policy's family was trained with, per
    /// setting and task, with what lies outside (`eval::outside_training`): judged when
    /// the run starts, so that every table made from it marks them. Empty for a family
    /// with nothing to judge (force-blind, unknown, a built-in). Derived from the policy,
    /// settings and dataset, which the run's identity already holds.
    #[serde(default, skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub outside_training: crate::eval::OutsideTraining,
}

impl RunHeader {
    /// The header of evaluating `spec` with the policy named `policy` (its sanity record
    /// is the caller's to set).
    pub fn of(spec: &EvalSpec, policy: &str) -> Self {
        Self {
            results_version: RESULTS_VERSION,
            version: env!("CARGO_PKG_VERSION").into(),
            policy: policy.to_string(),
            profile: spec.profile.name.clone(),
            profile_mismatch_ok: spec.profile_mismatch,
            declared_profile: spec.declared_profile.clone(),
            control_dt_s: spec.profile.control_dt_s,
            physics_dt_s: spec.profile.physics_dt_s,
            engine: spec.engine.clone(),
            dataset: spec.dataset.display().to_string(),
            dataset_sha256: spec.dataset_sha256.clone(),
            keypoints: spec.keypoints.clone(),
            termination: spec.termination,
            settings: spec.settings.clone(),
            sequences: PlannedSequence::plan(&spec.sequences, spec.profile.control_dt_s),
            subset: spec.subset.clone(),
            shard: spec.shard,
            io: spec.io,
            sanity: None,
            network_kernels: None,
            policy_parameters: Default::default(),
            identity: None,
            outside_training: Default::default(),
        }
    }

    /// The engine that simulated the run, its model and step, as every score names it:
    /// `rapier at 5 ms`, `mujoco (generated MJCF) at 5 ms`, `mujoco (g1.xml) at 1 ms`.
    /// Under force the engines' scores differ (docs/engines.md, "Force response: rapier against
    /// MuJoCo"), so a score without its engine is not a result.
    pub fn engine_label(&self) -> String {
        let model = match &self.engine {
            crate::sim::physics::Engine::Rapier => String::new(),
            crate::sim::physics::Engine::Mujoco { mjcf: None, .. } => " (generated MJCF)".into(),
            crate::sim::physics::Engine::Mujoco {
                mjcf: Some(path), ..
            } => format!(
                " ({})",
                path.file_name().map_or_else(
                    || path.display().to_string(),
                    |n| n.to_string_lossy().into()
                )
            ),
        };
        format!(
            "{}{model} at {} ms",
            self.engine.name(),
            self.physics_dt_s * 1e3
        )
    }

    /// The episodes this run (or shard) plans, as (sequence index, setting index), in
    /// schedule order.
    pub fn planned_jobs(&self) -> Vec<(usize, usize)> {
        crate::eval::schedule(self.sequences.len(), self.settings.len(), self.shard)
    }

    /// Of a dataset's `sequences`, those this run planned (all of them unless it ran a
    /// subset), in the plan's order: what its scores' regime thresholds are computed from,
    /// so a merge or a collect scores a partial run as the run itself did.
    pub fn planned_sequences(&self, sequences: &[Sequence]) -> Vec<Sequence> {
        self.sequences
            .iter()
            .filter_map(|p| {
                sequences
                    .iter()
                    .find(|q| q.task == p.task && q.sequence_id == p.sequence_id)
                    .cloned()
            })
            .collect()
    }

    /// The key of job `(sequence index, setting index)` of [`Self::planned_jobs`].
    pub fn job_key(&self, (q, s): (usize, usize)) -> EpisodeKey {
        EpisodeKey {
            task: self.sequences[q].task.clone(),
            sequence_id: self.sequences[q].sequence_id.clone(),
            setting: self.settings[s].name.clone(),
        }
    }

    /// What differs between this header and `other`: fields by name (`version`,
    /// `policy`, `settings`, …), the policy's identity with both hashes, this header's
    /// first — what a refused resume or merge reports.
    pub fn differences(&self, other: &Self) -> Vec<String> {
        let mut d = Vec::new();
        let mut check = |name: &str, same: bool| {
            if !same {
                d.push(name.to_string());
            }
        };
        check(
            "results_version",
            self.results_version == other.results_version,
        );
        check("version", self.version == other.version);
        check("policy", self.policy == other.policy);
        check("profile", self.profile == other.profile);
        check("control_dt_s", self.control_dt_s == other.control_dt_s);
        check("physics_dt_s", self.physics_dt_s == other.physics_dt_s);
        check("engine", self.engine == other.engine);
        check("dataset", self.dataset == other.dataset);
        check(
            "dataset_sha256",
            self.dataset_sha256 == other.dataset_sha256,
        );
        check("keypoints", self.keypoints == other.keypoints);
        check("termination", self.termination == other.termination);
        check("settings", self.settings == other.settings);
        check(
            "profile_mismatch_ok",
            self.profile_mismatch_ok == other.profile_mismatch_ok,
        );
        check("sequences", self.sequences == other.sequences);
        check("subset", self.subset == other.subset);
        check("sanity", self.sanity == other.sanity);
        check("shard", self.shard == other.shard);
        check("io", self.io == other.io);
        check(
            "network_kernels",
            self.network_kernels == other.network_kernels,
        );
        check(
            "policy_parameters",
            self.policy_parameters == other.policy_parameters,
        );
        d.extend(identity_differences(
            self.identity.as_ref(),
            other.identity.as_ref(),
        ));
        d
    }

    /// How tables name this run's network beside its policy ([`network_label`]).
    pub fn network_label(&self) -> Option<String> {
        network_label(self.identity.as_ref())
    }

    /// The policy as a table's title names it: `` `softmimic` (network 3f2a9c0b1d4e) ``,
    /// `` `balance` `` for a policy without a network file.
    pub fn policy_text(&self) -> String {
        match self.network_label() {
            Some(network) => format!("`{}` ({network})", self.policy),
            None => format!("`{}`", self.policy),
        }
    }

    /// Index of a setting by name.
    pub fn setting_index(&self, name: &str) -> Option<usize> {
        self.settings.iter().position(|s| s.name == name)
    }

    /// Index of a planned sequence.
    pub fn sequence_index(&self, task: &str, sequence_id: &str) -> Option<usize> {
        self.sequences
            .iter()
            .position(|s| s.task == task && s.sequence_id == sequence_id)
    }
}

/// Parses a results file whose top level carries `results_version`, refusing another
/// version before reading the rest (whose meaning may have changed).
pub(super) fn parse_versioned<T: serde::de::DeserializeOwned>(
    path: &Path,
    text: &str,
) -> Result<T, ResultsError> {
    let json = |source| ResultsError::Json {
        path: path.to_path_buf(),
        line: None,
        source,
    };
    let value: serde_json::Value = serde_json::from_str(text).map_err(json)?;
    let found = value
        .get("results_version")
        .and_then(serde_json::Value::as_u64)
        .unwrap_or(0);
    if found != u64::from(RESULTS_VERSION) {
        return Err(ResultsError::Version {
            path: path.to_path_buf(),
            found,
        });
    }
    serde_json::from_value(value).map_err(json)
}

/// The largest `run.json` read, bytes (it lists the run's sequences: 64 MiB is hundreds of
/// thousands).
pub const MAX_HEADER_BYTES: u64 = 64 * crate::files::bounded_read::MIB;

/// Reads `<run>/run.json` (a regular file of at most [`MAX_HEADER_BYTES`]).
pub fn read_header(run: &Path) -> Result<RunHeader, ResultsError> {
    let path = run.join(HEADER_FILE);
    let text = crate::files::bounded_read::read_to_string(&path, "run.json", MAX_HEADER_BYTES)
        .map_err(ResultsError::io(&path))?;
    parse_versioned(&path, &text)
}

/// Writes `<run>/run.json`.
pub fn write_header(run: &Path, header: &RunHeader) -> Result<(), ResultsError> {
    let path = run.join(HEADER_FILE);
    let text = serde_json::to_string_pretty(header).expect("a header serializes") + "\n";
    crate::files::atomic_file::write(&path, text).map_err(ResultsError::io(&path))
}
