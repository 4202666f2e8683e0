//! The policy of one timed run of `bench eval`: built in process, or a policy process
//! started afresh for the run (a run's process is never reused, so each pipeline depth
//! times a cold start alike), whose CPU time then counts in the cores the run kept busy.

use super::{process_group_cpu_time, PerfError};
use crate::campaign::leaderboard::{LaunchedPolicy, PolicyProcess};
use crate::eval::EvalSpec;
use crate::policy::registry::{PolicyArg, PolicyChoice};
use crate::policy::Policy;
use std::path::Path;
use std::time::Duration;

/// The policy of one run.
pub(super) enum TimedPolicy {
    /// Built in process: its time is the bench's own.
    InProcess(Box<dyn Policy>),
    /// A process started for the run, connected over shared memory.
    Process(Box<LaunchedPolicy>),
}

/// How the policy of a run is had: built from `policy` in process, or `command` started.
pub(super) struct PolicySource<'a> {
    /// The policy in process (`hold`, `twist2:FILE.onnx`, …), when there is no command.
    pub policy: &'a str,
    /// A shell command joining session `{session}` (`{thorarena}`: this binary).
    pub command: Option<&'a str>,
    /// The dynamics profile asked for, handed to the process.
    pub profile: Option<&'a str>,
    /// Seconds the process has to connect.
    pub connect_timeout_s: f64,
    /// Where the process runs.
    pub workdir: &'a Path,
}

impl TimedPolicy {
    /// The policy for `spec`'s run at pipeline depth `depth` and its label in the output
    /// (the policy's name, or the command in backticks); `note` hears a process's session
    /// as it connects.
    pub(super) fn start(
        source: &PolicySource,
        spec: &EvalSpec,
        depth: usize,
        note: &mut dyn FnMut(&str),
    ) -> Result<(String, Self), PerfError> {
        let Some(command) = source.command else {
            let arg = PolicyArg::parse(source.policy)?;
            let PolicyChoice::InProcess(policy) = arg.load(&spec.robot, &spec.profile)? else {
                return Err(PerfError::Precondition(format!(
                    "bench eval times a policy in process or one it starts (`option.policy_command`): not `{}`",
                    source.policy
                )));
            };
            return Ok((source.policy.to_string(), Self::InProcess(policy)));
        };
        let process = PolicyProcess {
            name: "bench".into(),
            command: command.to_string(),
            profile: source.profile.map(str::to_string),
            connect_timeout_s: source.connect_timeout_s,
            workdir: source.workdir.to_path_buf(),
        };
        let session = format!("bench-eval-{}-{depth}", std::process::id());
        let log = std::env::temp_dir().join(format!("thorarena-{session}.log"));
        let launched = LaunchedPolicy::start(&process, &session, spec, &log, note)
            .map_err(PerfError::PolicyProcess)?;
        Ok((format!("`{command}`"), Self::Process(Box::new(launched))))
    }

    /// The policy to run.
    pub(super) fn policy(&mut self) -> &mut dyn Policy {
        match self {
            Self::InProcess(p) => p.as_mut(),
            Self::Process(p) => p.as_mut(),
        }
    }

    /// CPU time so far of the policy's own processes, the shell and what it started
    /// (`None` in process: that time is the bench's).
    pub(super) fn cpu_time(&self) -> Option<Duration> {
        match self {
            Self::InProcess(_) => None,
            Self::Process(p) => Some(process_group_cpu_time(p.process_group())),
        }
    }
}
