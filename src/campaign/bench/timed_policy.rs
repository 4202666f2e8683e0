//! The policy of one timed run of `bench eval`: built in process, or a policy process
//! started afresh for the run (a run's process is never reused, so each pipeline depth
//! times a cold start alike), whose CPU time then counts in the cores the run kept busy.

use super::{process_group_cpu_time, PerfError};
use crate::eval::EvalSpec;
use crate::policy::launched::LaunchedPolicy;
use crate::policy::registry::{self, OpenPolicyError, PolicySource, PolicyTarget};
use crate::policy::{Policy, SessionOptions};
use std::time::Duration;

/// The policy of one run.
pub(super) enum TimedPolicy {
    /// Built in process: its time is the bench's own.
    InProcess(Box<dyn Policy>),
    /// A process started for the run, connected over shared memory.
    Process(Box<LaunchedPolicy>),
}

impl TimedPolicy {
    /// The policy `source` names for `spec`'s run at pipeline depth `depth` and its label
    /// in the output (the policy's name, or the command in backticks); `note` hears a
    /// process's session as it connects.
    pub(super) fn start(
        source: &PolicySource,
        spec: &EvalSpec,
        depth: usize,
        note: &mut dyn FnMut(&str),
    ) -> Result<(String, Self), PerfError> {
        let Some(command) = source.command() else {
            let policy = match registry::open_in_process(source, &spec.robot, &spec.profile) {
                Ok(policy) => policy,
                Err(OpenPolicyError::Registry(e)) => return Err(e.into()),
                Err(_) => {
                    return Err(PerfError::Precondition(format!(
                        "bench eval times a policy in process or one it starts (`option.policy_command`): not `{source}`"
                    )))
                }
            };
            return Ok((source.to_string(), Self::InProcess(policy)));
        };
        let log = std::env::temp_dir().join(format!(
            "thorarena-bench-eval-{}-{depth}.log",
            std::process::id()
        ));
        let target = PolicyTarget {
            robot: &spec.robot,
            profile: &spec.profile,
            process_profile: spec.process_profile,
            session: &SessionOptions::LAUNCHED,
            envs: spec.envs,
            launch_log: Some(&log),
        };
        let launched = registry::launch(command, &target, note)
            .map_err(|e| PerfError::PolicyProcess(e.to_string()))?;
        Ok((command.to_string(), Self::Process(Box::new(launched))))
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
