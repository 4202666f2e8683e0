//! A policy process started for a run (a leaderboard's `[[policy]] command = …`, `bench
//! eval --policy-command`, a request whose policy is a command): its shell command in its
//! own process group, its output in a log file, connected as a [`RemotePolicy`] and
//! stopped, group and descendants that left it, when the policy is dropped.

use super::{adopt_orphans, stop_adopted, stop_group, PolicyCommand};
use crate::policy::{
    ActOutcome, Observation, Policy, RemotePolicy, SessionOptions, TransportStats, Wiring,
};
use crate::sim::profile::Profile;
use crate::sim::robot::RobotModel;
use std::path::Path;
use std::process::Child;
use std::time::Duration;

/// Lines of a policy process's log quoted when it fails to connect.
const LOG_LINES_QUOTED: usize = 12;

/// A connected policy process and the process group it runs in.
pub struct LaunchedPolicy {
    remote: RemotePolicy,
    child: Child,
}

/// Where a launched policy serves: the robot, the profile and the environment slots of
/// its run, and how the session runs (its connect timeout is the command's own).
pub struct LaunchTarget<'a> {
    /// The robot simulated.
    pub robot: &'a RobotModel,
    /// The dynamics profile.
    pub profile: &'a Profile,
    /// How the run takes the profile the process declares.
    pub process_profile: crate::policy::declared_profile::ProcessProfile,
    /// How the session is served.
    pub session: &'a SessionOptions,
    /// Environment slots per batch.
    pub envs: usize,
}

impl LaunchedPolicy {
    /// Starts `command` on `session`, its output in `log`, and waits for it to connect
    /// (at most its `connect_timeout_s`) to serve `target`; `note` hears the session's
    /// progress. `Err` says why not, quoting the end of its log.
    pub fn start(
        command: &PolicyCommand,
        session: &str,
        target: &LaunchTarget,
        log: &Path,
        note: &mut dyn FnMut(&str),
    ) -> Result<Self, String> {
        let connect_timeout = crate::policy::check_wait_s(command.connect_timeout_s(), true)
            .map_err(|why| format!("connect_timeout_s = {why}"))?;
        let line = command.line(session).map_err(|e| e.to_string())?;
        let out = crate::files::log_text::create_log(log)
            .map_err(|e| format!("{}: {e}", log.display()))?;
        // A descendant that leaves the group (`setsid`) is adopted by this process when
        // its parent dies, and stopped with the rest.
        adopt_orphans();
        let mut child = command.spawn(session, out, log)?;
        let options = SessionOptions {
            connect_timeout,
            ..target.session.clone()
        };
        match RemotePolicy::serve(
            session,
            target.robot,
            target.profile,
            target.process_profile,
            &options,
            target.envs,
            &mut |_| Ok(()),
            note,
            &mut || launch_gone(&mut child),
        ) {
            Ok(remote) => Ok(Self { remote, child }),
            Err(e) => {
                // Give a process that failed a moment to finish its last words.
                std::thread::sleep(Duration::from_millis(100));
                let exited = match child.try_wait() {
                    Ok(Some(status)) => format!("; it exited ({status}) without connecting"),
                    _ => String::new(),
                };
                stop_group(&mut child);
                let tail = crate::files::log_text::log_tail(log, LOG_LINES_QUOTED);
                Err(format!(
                    "serving session `{session}`: {e}{exited} (command `{line}`; the end of its output, {}:\n{})",
                    log.display(),
                    tail.join("\n")
                ))
            }
        }
    }

    /// The process group the policy runs in (the shell's id; it and what it started), to
    /// measure its CPU time by.
    pub fn process_group(&self) -> u32 {
        self.child.id()
    }
}

/// The command started for the policy can no longer connect: its shell exited with a
/// failure, or exited and left nothing of its process group running (a command that
/// starts its policy in the background and exits 0 is waited for as before).
fn launch_gone(child: &mut std::process::Child) -> bool {
    match child.try_wait() {
        Ok(Some(status)) if !status.success() => true,
        Ok(Some(_)) => {
            // SAFETY: signal 0 to a process group this run created only asks whether it
            // has members.
            let rc = unsafe { libc::kill(-(child.id() as libc::pid_t), 0) };
            rc == -1 && std::io::Error::last_os_error().raw_os_error() == Some(libc::ESRCH)
        }
        _ => false,
    }
}

impl Drop for LaunchedPolicy {
    fn drop(&mut self) {
        stop_group(&mut self.child);
        stop_adopted();
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
    fn profile_declaration(&self) -> Option<&crate::policy::declared_profile::ProfileDeclaration> {
        self.remote.profile_declaration()
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
