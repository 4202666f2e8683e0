//! The processes a run starts beside an evaluation — a policy's shell command (a sweep
//! task, a leaderboard, `bench eval`), a sweep task's evaluation itself — are tied to the
//! process that started them: each dies with its parent, a policy runs in its own process
//! group so the whole group can be stopped, and what escaped the group is adopted and
//! stopped too.

use std::os::unix::process::CommandExt;
use std::process::{Child, Command};
use std::time::{Duration, Instant};

/// `s` as one word of a POSIX shell: bare when it is only safe characters, else in
/// single quotes (inside which nothing is special but `'` itself).
pub fn shell_quote(s: &str) -> String {
    if !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || "/._-+=:,".contains(c))
    {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', "'\\''"))
    }
}

/// Why a policy command cannot be written as a shell line.
#[derive(Debug, thiserror::Error)]
pub enum CommandLineError {
    /// This binary's path could not be found.
    #[error("finding this binary's path for `{{thorarena}}`: {0}")]
    CurrentExe(std::io::Error),
    /// This binary's path is not UTF-8.
    #[error("{0}: not UTF-8, which `{{thorarena}}` cannot name")]
    NotUtf8(String),
}

/// A policy command with its placeholders filled in as single shell words: the binary's
/// path and the session are data, whatever characters they hold (`$(…)` in a directory
/// name is not run).
pub fn policy_command_line(command: &str, session: &str) -> Result<String, CommandLineError> {
    let exe = std::env::current_exe().map_err(CommandLineError::CurrentExe)?;
    let exe = exe
        .to_str()
        .ok_or_else(|| CommandLineError::NotUtf8(exe.display().to_string()))?;
    Ok(command
        .replace("{session}", &shell_quote(session))
        .replace("{thorarena}", &shell_quote(exe)))
}

/// A child that is killed when the thread that started it dies (a `sweep run` killed
/// with SIGKILL leaves no evaluation writing behind it).
pub fn die_with_parent(cmd: &mut Command) {
    // SAFETY: prctl is async-signal-safe and touches only the calling (child) process.
    unsafe {
        cmd.pre_exec(|| {
            if libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
}

/// `sh -c line` in `workdir`, in its own process group, dying with this process, its
/// output in `log` (at `log_path`), capped ([`crate::files::capped_log`]), with nothing on
/// its standard input.
pub fn shell_in_own_group(
    line: &str,
    workdir: &std::path::Path,
    log: std::fs::File,
    log_path: &std::path::Path,
) -> std::io::Result<Command> {
    use crate::files::capped_log::{capped_output, PROCESS_LOG_MAX_BYTES};
    let (stdout, stderr) = capped_output(log, log_path, PROCESS_LOG_MAX_BYTES)?;
    let mut cmd = Command::new("sh");
    cmd.args(["-c", line])
        .current_dir(workdir)
        .stdin(std::process::Stdio::null())
        .stdout(stdout)
        .stderr(stderr)
        .process_group(0);
    die_with_parent(&mut cmd);
    Ok(cmd)
}

/// Ends a launched policy's whole process group: SIGTERM, then SIGKILL after 2 s.
pub fn stop_group(child: &mut Child) {
    let pgid = child.id() as libc::pid_t;
    // SAFETY: signalling a process group we created.
    unsafe { libc::kill(-pgid, libc::SIGTERM) };
    let deadline = Instant::now() + Duration::from_secs(2);
    while Instant::now() < deadline {
        if matches!(child.try_wait(), Ok(Some(_))) {
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    // SAFETY: as above; the group may already be gone.
    unsafe { libc::kill(-pgid, libc::SIGKILL) };
    let _ = child.wait();
}

/// Makes this process adopt the descendants of its children whose parents die (a
/// policy's `setsid` grandchild), so [`stop_adopted`] can stop them.
pub fn adopt_orphans() {
    // SAFETY: prctl with PR_SET_CHILD_SUBREAPER takes no pointers.
    unsafe { libc::prctl(libc::PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0) };
}

/// Stops and reaps every process adopted by this one (its parent died): a launched
/// policy's descendants that left its process group. The caller runs no other child of
/// its own meanwhile, so each one adopted is the policy's.
pub fn stop_adopted() {
    // SAFETY: getpid has no preconditions.
    let me = unsafe { libc::getpid() };
    let deadline = Instant::now() + Duration::from_secs(1);
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
        if (adopted.is_empty() && Instant::now() > deadline)
            || Instant::now() > deadline + Duration::from_secs(1)
        {
            return;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}
