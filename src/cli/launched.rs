//! A policy process the CLI starts itself (a leaderboard's `[[policy]] command = …`):
//! its shell command in its own process group, its output in a log file, connected as a
//! [`RemotePolicy`] and stopped, group and all, when the policy is dropped.

use super::policy_arg::{connect_remote, PolicyIoArgs};
use super::sweep::task::{die_with_parent, policy_command_line, stop_group};
use std::os::unix::process::CommandExt;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::Duration;
use thorarena::evaluation::EvalSpec;
use thorarena::leaderboard::PolicyProcess;
use thorarena::policy::{ActOutcome, Observation, Policy, RemotePolicy, TransportStats, Wiring};

/// Lines of a policy process's log quoted when it fails to connect.
const LOG_LINES_QUOTED: usize = 12;

/// A connected policy process and the process group it runs in.
pub struct LaunchedPolicy {
    remote: RemotePolicy,
    child: Child,
}

impl LaunchedPolicy {
    /// Starts `process` on `session`, its output in `log`, and waits for it to connect
    /// (at most its `connect_timeout_s`) to serve `spec`'s environments. `Err` says why
    /// not, quoting the end of its log.
    pub fn start(
        process: &PolicyProcess,
        session: &str,
        spec: &EvalSpec,
        log: &Path,
    ) -> Result<Self, String> {
        let line = policy_command_line(&process.command, session).map_err(|e| format!("{e:#}"))?;
        let out =
            thorarena::sweep::create_log(log).map_err(|e| format!("{}: {e}", log.display()))?;
        let err = out
            .try_clone()
            .map_err(|e| format!("{}: {e}", log.display()))?;
        // A descendant that leaves the group (`setsid`) is adopted by this process when
        // its parent dies, and stopped with the rest.
        // SAFETY: prctl with PR_SET_CHILD_SUBREAPER takes no pointers.
        unsafe { libc::prctl(libc::PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0) };
        let mut cmd = Command::new("sh");
        cmd.args(["-c", &line])
            .current_dir(&process.workdir)
            .stdin(Stdio::null())
            .stdout(out)
            .stderr(err)
            .process_group(0);
        die_with_parent(&mut cmd);
        let mut child = cmd
            .spawn()
            .map_err(|e| format!("cannot start `{line}`: {e}"))?;
        let io = PolicyIoArgs {
            connect_timeout: process.connect_timeout_s,
            ..PolicyIoArgs::defaults()
        };
        match connect_remote(
            session,
            &spec.robot,
            &spec.profile,
            &io,
            spec.envs,
            &mut |_| Ok(()),
        ) {
            Ok(remote) => Ok(Self { remote, child }),
            Err(e) => {
                // Give a process that failed a moment to finish its last words.
                std::thread::sleep(Duration::from_millis(100));
                stop_group(&mut child);
                let tail = thorarena::sweep::log_tail(log, LOG_LINES_QUOTED);
                Err(format!(
                    "{e:#} (command `{line}`; the end of its output, {}:\n{})",
                    log.display(),
                    tail.join("\n")
                ))
            }
        }
    }
}

impl LaunchedPolicy {
    /// CPU time of the policy's process group so far (the shell and what it started).
    pub fn cpu_time(&self) -> Duration {
        thorarena::perf::process_group_cpu_time(self.child.id())
    }
}

impl Drop for LaunchedPolicy {
    fn drop(&mut self) {
        stop_group(&mut self.child);
        stop_adopted();
    }
}

/// Stops and reaps every process adopted by this one (its parent died): a launched
/// policy's descendants that left its process group. The leaderboard runs no other
/// child of its own meanwhile, so each one adopted is the policy's.
fn stop_adopted() {
    // SAFETY: getpid has no preconditions.
    let me = unsafe { libc::getpid() };
    let deadline = std::time::Instant::now() + Duration::from_secs(1);
    loop {
        let adopted: Vec<libc::pid_t> = std::fs::read_dir("/proc")
            .into_iter()
            .flatten()
            .flatten()
            .filter_map(|e| e.file_name().to_str()?.parse::<libc::pid_t>().ok())
            .filter(|pid| {
                std::fs::read_to_string(format!("/proc/{pid}/stat")).is_ok_and(|stat| {
                    stat.rsplit_once(')')
                        .and_then(|(_, rest)| rest.split_whitespace().nth(1))
                        .and_then(|ppid| ppid.parse::<libc::pid_t>().ok())
                        == Some(me)
                })
            })
            .collect();
        for &pid in &adopted {
            // SAFETY: signalling and reaping a child of this process.
            unsafe {
                libc::kill(pid, libc::SIGKILL);
                libc::waitpid(pid, std::ptr::null_mut(), 0);
            }
        }
        if (adopted.is_empty() && std::time::Instant::now() > deadline)
            || std::time::Instant::now() > deadline + Duration::from_secs(1)
        {
            return;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

impl Policy for LaunchedPolicy {
    fn name(&self) -> &str {
        self.remote.name()
    }
    fn reference_offsets_s(&self) -> Vec<f64> {
        self.remote.reference_offsets_s()
    }
    fn reset(&mut self, env: usize) {
        self.remote.reset(env)
    }
    fn episode_ended(&mut self, env: usize, terminated: bool) {
        self.remote.episode_ended(env, terminated)
    }
    fn act(&mut self, observations: &[Observation], actions: &mut [Vec<f64>]) -> ActOutcome {
        self.remote.act(observations, actions)
    }
    fn last_round_trip(&self) -> Option<Duration> {
        self.remote.last_round_trip()
    }
    fn recover(&mut self) -> bool {
        self.remote.recover()
    }
    fn transport_stats(&self) -> Option<TransportStats> {
        self.remote.transport_stats()
    }
    fn zero_action(&self, obs: &Observation, out: &mut [f64]) {
        self.remote.zero_action(obs, out)
    }
    fn sanity_exempt(&self) -> Option<&'static str> {
        self.remote.sanity_exempt()
    }
    fn wiring(&self) -> Wiring {
        self.remote.wiring()
    }
}
