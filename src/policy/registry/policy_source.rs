//! [`PolicySource`]: where a run gets its policy, as one typed value — a family of the
//! registry named by an argument (a built-in, a network file with its parameters, a
//! session a policy process joins) or a command the run starts as its policy process.
//! It is parsed once, at the edges (a command line's value parser, a request file, a
//! sweep spec, a leaderboard's policy file), and everything after reads the value:
//! [`super::open_policy`] makes it a policy, a run's header names it, a sweep plans it.
//!
//! In a file it is spelled as today: an argument is its string (`"balance"`,
//! `"softmimic:F.onnx@stiffness=200"`, `"ipc:NAME"`), a launched command the table of
//! its fields (`{"command": …, "workdir": …, "connect_timeout_s": …}`).

use super::families::{policy_family, PolicyFamily, Target, POLICY_FAMILIES};
use super::{NamedPolicy, PolicyChoice, RegistryError};
use crate::policy::launched::PolicyCommand;
use crate::sim::profile::Profile;
use crate::sim::robot::RobotModel;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Where a run's policy comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum PolicySource {
    /// A family of the registry, named by an argument (`balance`, `twist2:FILE.onnx`,
    /// `softmimic:FILE.onnx@stiffness=200`, `ipc:NAME`).
    Named(NamedPolicy),
    /// A command the run starts as its policy process, on a session the run serves it
    /// (a sweep's or a leaderboard's `command = …`, `bench eval --policy-command`).
    Launched(PolicyCommand),
}

impl PolicySource {
    /// The policy argument `spec` (`--policy`'s spelling); refused naming what it
    /// probably meant. Call it at an edge only: what is parsed is passed on as the value.
    pub fn parse(spec: &str) -> Result<Self, RegistryError> {
        NamedPolicy::parse(spec).map(Self::Named)
    }

    /// The built-in family `name` (`hold`, `replay`, `balance`), or `None` when `name`
    /// is no built-in.
    pub fn builtin(name: &str) -> Option<Self> {
        let family = POLICY_FAMILIES
            .iter()
            .find(|f| f.name == name && f.target == Target::Nothing)?;
        Some(Self::Named(NamedPolicy::of_family(family, "")))
    }

    /// Session `name` as a command line gives it (`serve --session`): held to the wire's
    /// rule (1 to 64 characters from `[A-Za-z0-9_.-]`) before anything is served.
    pub fn session_name(name: &str) -> Result<String, thorarena_ipc::IpcError> {
        thorarena_ipc::check_session_name(name).map(|()| name.to_string())
    }

    /// The policy process that joins session `name` (`ipc:NAME`), which the run serves.
    pub fn on_session(name: &str) -> Self {
        let family = policy_family("ipc:").expect("the registry has the `ipc` family");
        Self::Named(NamedPolicy::of_family(family, name))
    }

    /// The argument, when it is one.
    pub fn named(&self) -> Option<&NamedPolicy> {
        match self {
            Self::Named(arg) => Some(arg),
            Self::Launched(_) => None,
        }
    }

    /// The command the run starts, when it is one.
    pub fn command(&self) -> Option<&PolicyCommand> {
        match self {
            Self::Named(_) => None,
            Self::Launched(command) => Some(command),
        }
    }

    /// Its family's entry; a launched command is a policy process (`ipc`) whose session
    /// the run names.
    pub fn family(&self) -> &'static PolicyFamily {
        match self {
            Self::Named(arg) => arg.family(),
            Self::Launched(_) => policy_family("ipc:").expect("the registry has `ipc`"),
        }
    }

    /// Whether it runs inside this process (a built-in or a network), where no budget or
    /// measured latency applies.
    pub fn in_process(&self) -> bool {
        self.family().build.is_some()
    }

    /// The network file of a network's argument.
    pub fn file(&self) -> Option<&Path> {
        self.named()?.file()
    }

    /// The session of `ipc:SESSION`.
    pub fn session(&self) -> Option<&str> {
        self.named()?.session()
    }

    /// The parameters after the file, as given (`stiffness=200`).
    pub fn parameters(&self) -> Option<&str> {
        self.named()?.parameters()
    }

    /// The value it gives parameter `name`, if any.
    pub fn parameter(&self, name: &str) -> Option<f64> {
        self.named()?.parameter(name)
    }

    /// The network file's stem.
    pub fn file_stem(&self) -> Option<String> {
        self.named()?.file_stem()
    }

    /// The same source with a network file taken against `dir`.
    pub fn with_file_in(&self, dir: &Path) -> Self {
        match self {
            Self::Named(arg) => Self::Named(arg.with_file_in(dir)),
            Self::Launched(_) => self.clone(),
        }
    }

    /// The same network with `parameters` after its file, held to its family's
    /// declaration; refused for anything that takes none.
    pub fn with_parameters(&self, parameters: &str) -> Result<Self, String> {
        match self {
            Self::Named(arg) => arg.with_parameters(parameters).map(Self::Named),
            Self::Launched(c) => Err(format!(
                "{c} takes no parameters: a command gives its own arguments"
            )),
        }
    }

    /// A sweep's label: `family:stem[@parameters]` for a network, the argument itself for
    /// the others, a command's first word.
    pub fn label(&self) -> String {
        match self {
            Self::Named(arg) => arg.label(),
            Self::Launched(c) => c.first_word().to_string(),
        }
    }

    /// How a table names it (`twist2 (twist2_1017_25k)`).
    pub fn table_label(&self) -> String {
        match self {
            Self::Named(arg) => arg.table_label(),
            Self::Launched(c) => c.first_word().to_string(),
        }
    }

    /// The base of a run directory's name (`wbc-mjlab-wbc_g1_policy`).
    pub fn dir_label(&self) -> String {
        match self {
            Self::Named(arg) => arg.dir_label(),
            Self::Launched(c) => c.first_word().to_string(),
        }
    }

    /// The profile it runs under when none is named (a published network's own, known by
    /// its content, which is read here: call it once per run).
    pub fn default_profile(&self) -> &'static str {
        match self {
            Self::Named(arg) => arg.default_profile(),
            Self::Launched(_) => self.family().profile,
        }
    }

    /// Environment slots per worker when a run names none.
    pub fn slots_per_worker(&self) -> usize {
        self.family().slots_per_worker
    }

    /// Whether `profile` is one its family runs under; `Err` says why not.
    pub fn check_profile(&self, profile: &Profile) -> Result<(), String> {
        (self.family().profile_rule)(profile)
    }

    /// Builds it in process for `robot` under `profile`, or says which session a policy
    /// process joins, or which command the caller starts.
    pub fn load(
        &self,
        robot: &RobotModel,
        profile: &Profile,
    ) -> Result<PolicyChoice<'_>, RegistryError> {
        match self {
            Self::Named(arg) => arg.load(robot, profile),
            Self::Launched(command) => Ok(PolicyChoice::Launched(command)),
        }
    }
}

impl std::fmt::Display for PolicySource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Named(arg) => arg.fmt(f),
            Self::Launched(c) => c.fmt(f),
        }
    }
}

impl From<PolicyCommand> for PolicySource {
    fn from(command: PolicyCommand) -> Self {
        Self::Launched(command)
    }
}

impl Serialize for PolicySource {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Self::Named(arg) => s.serialize_str(arg.as_str()),
            Self::Launched(c) => c.serialize(s),
        }
    }
}

impl<'de> Deserialize<'de> for PolicySource {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        // A string is an argument, refused with the registry's message; a table a
        // command, held to its checks.
        let value = serde_json::Value::deserialize(d)?;
        match value {
            serde_json::Value::String(spec) => Self::parse(&spec).map_err(serde::de::Error::custom),
            table @ serde_json::Value::Object(_) => PolicyCommand::deserialize(table)
                .map(Self::Launched)
                .map_err(|e| serde::de::Error::custom(format!("a policy command: {e}"))),
            other => Err(serde::de::Error::custom(format!(
                "`policy` is {other}: give a policy argument as a string (\"balance\", \"twist2:FILE.onnx\") or a command as a table with `command`, `workdir` and `connect_timeout_s`"
            ))),
        }
    }
}
