//! The sweep spec: a TOML file naming the axes of a sweep. Unknown keys are refused (with
//! the key named) so a typo never silently shrinks a sweep.

use super::SweepError;
use crate::eval::Setting;
use crate::policy::launched::PolicyCommand;
use crate::policy::registry::PolicySource;
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// A setting of a spec, parsed on reading (a refusal names the file, line and reason) and
/// kept as its user spelled it, so that a message about it echoes that spelling.
#[derive(Debug, Clone)]
pub struct SpecSetting {
    /// As written in the spec.
    pub spelled: String,
    /// As parsed.
    pub setting: Setting,
}

impl<'de> Deserialize<'de> for SpecSetting {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let spelled = String::deserialize(d)?;
        let setting = Setting::parse(&spelled).map_err(serde::de::Error::custom)?;
        Ok(Self { spelled, setting })
    }
}

/// A sweep spec (`sweeps/*.toml`). Relative paths (datasets, `twist2:FILE`) and policy
/// commands are taken relative to the spec file's directory.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepSpec {
    /// Dataset directories (canonical format).
    pub datasets: Vec<String>,
    /// Force settings, spelled as `eval --settings` takes them: `force`, `no-force`, a
    /// replay coefficient (`0.5`), `push:<N>`, a disturbance. Each is its own cell.
    pub settings: Vec<SpecSetting>,
    /// Only these tasks of each dataset (`eval --tasks`; default: every task).
    #[serde(default)]
    pub tasks: Vec<String>,
    /// Only these sequences, `SEQUENCE_ID` or `TASK/SEQUENCE_ID` (`eval --sequences`;
    /// default: every sequence).
    #[serde(default)]
    pub sequences: Vec<String>,
    /// Shards per cell (tasks per cell).
    #[serde(default = "one")]
    pub shards: usize,
    /// Robot.
    #[serde(default = "default_robot")]
    pub robot: String,
    /// Policies (`[[policy]]` tables).
    #[serde(rename = "policy", default)]
    pub policies: Vec<PolicySpec>,
    /// Latency rules (`[[latency]]` tables); none given means one lock-step rule.
    #[serde(rename = "latency", default)]
    pub latency: Vec<LatencySpec>,
    /// Physics engines (`[[engine]]` tables); none given means rapier at the profile's
    /// step.
    #[serde(rename = "engine", default)]
    pub engines: Vec<EngineSpec>,
}

/// One physics engine of a sweep: `eval`'s `--engine`, `--mjcf` and `--physics-dt`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EngineSpec {
    /// Label in results (default: the engine, with the MJCF's file stem and the step).
    pub name: Option<String>,
    /// `rapier` or `mujoco`.
    pub engine: String,
    /// A user's MJCF for `mujoco` (default: the one generated from the robot model).
    pub mjcf: Option<String>,
    /// Physics step, s (default: the profile's).
    pub physics_dt_s: Option<f64>,
}

impl EngineSpec {
    /// The engine's label in results.
    pub fn label(&self) -> String {
        if let Some(n) = &self.name {
            return n.clone();
        }
        let mut l = self.engine.clone();
        if let Some(m) = &self.mjcf {
            let stem = Path::new(m)
                .file_stem()
                .map_or(m.clone(), |s| s.to_string_lossy().into_owned());
            l += &format!(":{stem}");
        }
        if let Some(dt) = self.physics_dt_s {
            l += &format!("@{}ms", dt * 1e3);
        }
        l
    }
}

/// One policy of a sweep: in process (`policy`) or a process the task launches
/// (`command`, with `{session}` and `{thorarena}` placeholders).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PolicySpec {
    /// Label in results (default: `policy`, or `command`'s first word).
    pub name: Option<String>,
    /// A policy argument as `eval --policy` takes it (`thorarena policies`): a built-in, or a
    /// network in process (`twist2:FILE.onnx`, `beyondmimic:FILE.onnx`, `wbc-mjlab:FILE.onnx`;
    /// relative paths against the spec's directory), parsed as the spec is read.
    #[serde(default, deserialize_with = "policy_argument")]
    pub policy: Option<PolicySource>,
    /// Shell command starting a policy process that joins session `{session}`;
    /// `{thorarena}` is this binary.
    pub command: Option<String>,
    /// Dynamics profile [default: the policy's, `thorarena::policy::registry::PolicySource::default_profile`].
    #[serde(default)]
    pub profile: Option<String>,
    /// Keypoint set.
    #[serde(default = "default_name")]
    pub keypoints: String,
    /// Seconds a launched policy has to connect.
    #[serde(default = "default_connect_timeout")]
    pub connect_timeout_s: f64,
    /// Score the policy without its sanity check (`eval --unchecked`, recorded in each
    /// run); without it every task's `eval` checks a network in process first.
    #[serde(default)]
    pub unchecked: bool,
    /// A policy parameter as an axis: each value becomes a policy of its own
    /// (`parameters = { stiffness = [40, 200, 600] }` on a `softmimic:` network runs
    /// `softmimic:FILE@stiffness=40`, …); several keys give every combination.
    #[serde(default)]
    pub parameters: std::collections::BTreeMap<String, Vec<f64>>,
}

/// One latency rule: `eval`'s `--budget`, `--latency-mode` and `--miss-rule`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LatencySpec {
    /// Label in results (default: `budget`/`mode`/`miss_rule`).
    pub name: Option<String>,
    /// `none` (lock-step) or a duration such as `5ms`.
    #[serde(default = "default_budget")]
    pub budget: String,
    /// `ignore` or `measured`.
    #[serde(default = "default_mode")]
    pub mode: String,
    /// `hold`, `zero` or `fail`.
    #[serde(default = "default_miss_rule")]
    pub miss_rule: String,
}

/// A `policy = "…"` key: the argument parsed where the spec is read, refused with the
/// registry's message (a sweep spec names a command with `command = …`, not here).
fn policy_argument<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> Result<Option<PolicySource>, D::Error> {
    let spec = String::deserialize(d)?;
    PolicySource::parse(&spec)
        .map(Some)
        .map_err(serde::de::Error::custom)
}

fn one() -> usize {
    1
}
fn default_robot() -> String {
    "g1_29dof".into()
}
fn default_name() -> String {
    "default".into()
}
fn default_connect_timeout() -> f64 {
    60.0
}
fn default_budget() -> String {
    "none".into()
}
fn default_mode() -> String {
    "ignore".into()
}
fn default_miss_rule() -> String {
    "hold".into()
}

impl SweepSpec {
    /// Reads and checks a spec file: TOML, no unknown keys, no empty axis.
    pub fn load(path: &Path) -> Result<Self, SweepError> {
        // A spec is a few kilobytes; 16 MiB bounds what a mistaken path costs.
        let text = crate::files::bounded_read::read_to_string(path, "sweep spec", 16 << 20)
            .map_err(|source| SweepError::Io {
                path: path.to_path_buf(),
                source,
            })?;
        let mut spec: Self = toml::from_str(&text).map_err(|e| SweepError::Toml {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
        let mut policies = Vec::new();
        for (i, p) in spec.policies.iter().enumerate() {
            policies.extend(p.expanded().map_err(|m| SweepError::Invalid {
                path: path.to_path_buf(),
                message: format!("[[policy]] #{}: {m}", i + 1),
            })?);
        }
        spec.policies = policies;
        spec.check(path)?;
        Ok(spec)
    }

    fn check(&self, path: &Path) -> Result<(), SweepError> {
        let invalid = |message: String| SweepError::Invalid {
            path: path.to_path_buf(),
            message,
        };
        for (key, empty) in [
            ("datasets", self.datasets.is_empty()),
            ("settings", self.settings.is_empty()),
            ("[[policy]]", self.policies.is_empty()),
        ] {
            if empty {
                return Err(invalid(format!(
                    "the axis `{key}` is empty: give at least one"
                )));
            }
        }
        if self.shards == 0 {
            return Err(invalid("`shards` must be at least 1".into()));
        }
        for (i, p) in self.policies.iter().enumerate() {
            p.check()
                .map_err(|m| invalid(format!("[[policy]] #{}: {m}", i + 1)))?;
        }
        for (key, values) in [
            ("datasets", &self.datasets),
            (
                "settings",
                &self.settings.iter().map(|s| s.spelled.clone()).collect(),
            ),
            (
                "[[policy]] name",
                &self.policies.iter().map(PolicySpec::label).collect(),
            ),
            (
                "[[latency]] name",
                &self.latency.iter().map(LatencySpec::label).collect(),
            ),
        ] {
            let mut seen = std::collections::HashSet::new();
            if let Some(dup) = values.iter().find(|v| !seen.insert(v.as_str())) {
                return Err(invalid(format!("`{key}` lists `{dup}` twice")));
            }
        }
        Ok(())
    }

    /// The engines, rapier at the profile's step when none is given.
    pub fn engine_axis(&self) -> Vec<EngineSpec> {
        if self.engines.is_empty() {
            vec![EngineSpec {
                name: None,
                engine: "rapier".into(),
                mjcf: None,
                physics_dt_s: None,
            }]
        } else {
            self.engines.clone()
        }
    }

    /// The latency rules, the default lock-step one when none is given.
    pub fn latency_rules(&self) -> Vec<LatencySpec> {
        if self.latency.is_empty() {
            vec![LatencySpec {
                name: None,
                budget: default_budget(),
                mode: default_mode(),
                miss_rule: default_miss_rule(),
            }]
        } else {
            self.latency.clone()
        }
    }
}

impl LatencySpec {
    /// Whether the rule times the policy (a budget, or measured latency): only a policy
    /// process is timed, so an in-process policy runs under the other rules alone.
    pub fn times_the_policy(&self) -> bool {
        self.budget != "none" || self.mode == "measured"
    }
}

impl PolicySpec {
    /// One policy per combination of [`Self::parameters`]' values, each naming its values
    /// in its policy argument (`FILE@stiffness=40`); itself when it has none. A parameter
    /// the family does not declare is refused here, before anything is planned.
    pub fn expanded(&self) -> Result<Vec<PolicySpec>, String> {
        if self.parameters.is_empty() {
            return Ok(vec![self.clone()]);
        }
        let Some(policy) = &self.policy else {
            return Err("`parameters` vary a policy in process (`policy = …`); a `command` takes its own arguments".into());
        };
        if policy.parameters().is_some() {
            return Err(format!(
                "`{policy}` names its parameters already: give them in `parameters` or in the argument, not both"
            ));
        }
        if self.name.is_some() {
            return Err("`name` would label every value of `parameters` alike: drop it (each gets its own label)".into());
        }
        let mut combos: Vec<Vec<(String, f64)>> = vec![Vec::new()];
        for (key, values) in &self.parameters {
            if values.is_empty() {
                return Err(format!(
                    "the axis `parameters.{key}` is empty: give at least one value"
                ));
            }
            combos = combos
                .into_iter()
                .flat_map(|c| {
                    values.iter().map(move |v| {
                        let mut c = c.clone();
                        c.push((key.clone(), *v));
                        c
                    })
                })
                .collect();
        }
        combos
            .into_iter()
            .map(|combo| {
                let params: Vec<String> = combo.iter().map(|(k, v)| format!("{k}={v}")).collect();
                Ok(PolicySpec {
                    policy: Some(policy.with_parameters(&params.join(","))?),
                    parameters: Default::default(),
                    ..self.clone()
                })
            })
            .collect()
    }

    /// Whether the table says what to run: `policy` (not a session no one starts) or
    /// `command` with `{session}`, one of them, and a usable connect timeout. Sweeps and
    /// the leaderboard's policy files hold it to the same rules.
    pub fn check(&self) -> Result<(), String> {
        self.source(Path::new(".")).map(|_| ())
    }

    /// Where the policy comes from: `policy` with a network file's path taken against
    /// `workdir` (the spec's directory), or `command` run there; `Err` when the table does
    /// not say what to run ([`Self::check`]).
    pub fn source(&self, workdir: &Path) -> Result<PolicySource, String> {
        let source = match (&self.policy, &self.command) {
            (Some(_), Some(_)) => Err("give `policy` or `command`, not both".into()),
            (None, None) => Err(
                "give `policy` (a built-in or a network file, e.g. twist2:FILE) or `command`"
                    .into(),
            ),
            // A session served by a process nobody starts: every run would wait on the
            // same name (and a sweep's planning, which tries each policy, with them).
            (Some(p), None) if p.session().is_some() => Err(format!(
                "`policy = \"{p}\"` names a policy process no one starts: give `command` (with {{session}}) that starts it for each run"
            )),
            (Some(p), None) => Ok(p.with_file_in(workdir)),
            (None, Some(c)) => {
                PolicyCommand::new(c, workdir, self.connect_timeout_s).map(PolicySource::from)
            }
        }?;
        crate::policy::check_wait_s(self.connect_timeout_s, false)
            .map_err(|why| format!("`connect_timeout_s` = {why}"))?;
        Ok(source)
    }

    /// `profile` with a profile file's path taken against `workdir`; a bundled
    /// profile's name as it is.
    pub fn resolved_profile(&self, workdir: &Path) -> Option<String> {
        self.profile.as_ref().map(|f| {
            if f.ends_with(".toml") {
                resolve(workdir, f).display().to_string()
            } else {
                f.clone()
            }
        })
    }

    /// The policy's label in results.
    pub fn label(&self) -> String {
        if let Some(n) = &self.name {
            return n.clone();
        }
        match (&self.policy, &self.command) {
            (Some(p), _) => p.label(),
            (None, Some(c)) => c.split_whitespace().next().unwrap_or("command").to_string(),
            (None, None) => "policy".into(),
        }
    }
}

impl LatencySpec {
    /// The rule's label in results.
    pub fn label(&self) -> String {
        self.name
            .clone()
            .unwrap_or_else(|| format!("{}/{}/{}", self.budget, self.mode, self.miss_rule))
    }
}

/// `p` relative to `base` unless absolute.
pub(super) fn resolve(base: &Path, p: &str) -> PathBuf {
    let p = Path::new(p);
    if p.is_absolute() {
        p.to_path_buf()
    } else {
        base.join(p)
    }
}
