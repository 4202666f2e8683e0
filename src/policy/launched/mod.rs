//! A policy the run starts itself: a shell command ([`PolicyCommand`]) that joins the
//! session the run serves for it. The command runs in its own process group, its output
//! in a log file, and it is stopped — group and the descendants that left it — when the
//! run is over ([`LaunchedPolicy`], or [`stop_group`] for a sweep task's sibling process).
//! A sweep task, the leaderboard and `bench eval` start their policy processes here.

mod launched_policy;
mod process_group;

pub use launched_policy::{LaunchTarget, LaunchedPolicy};
pub use process_group::{
    adopt_orphans, die_with_parent, shell_in_own_group, shell_quote, stop_adopted, stop_group,
    CommandLineError,
};

use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::process::Child;

/// The placeholder of a command that the session the run serves replaces.
pub const SESSION_PLACEHOLDER: &str = "{session}";

/// Where the output of a command started for run `run` goes: `<run>.policy.log` beside
/// the run's directory (never inside it, which holds the run's files only).
pub fn log_beside(run: &Path) -> PathBuf {
    let name = run
        .file_name()
        .map_or("run".into(), |n| n.to_string_lossy());
    run.with_file_name(format!("{name}.policy.log"))
}

/// A policy process as the command that starts it: a shell line with `{session}` (the
/// session the run serves it, one per run) and `{thorarena}` (this binary), run in
/// `workdir`, which has `connect_timeout_s` to connect. Made only through
/// [`PolicyCommand::new`] (a request file's too), so every one holds its placeholder and a
/// usable wait.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "CommandFields")]
pub struct PolicyCommand {
    /// The shell line as given.
    command: String,
    /// Where it runs.
    workdir: PathBuf,
    /// Seconds it has to connect.
    connect_timeout_s: f64,
}

/// [`PolicyCommand`]'s fields as a file spells them, before they are checked.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CommandFields {
    command: String,
    workdir: PathBuf,
    connect_timeout_s: f64,
}

impl TryFrom<CommandFields> for PolicyCommand {
    type Error = String;

    fn try_from(f: CommandFields) -> Result<Self, String> {
        Self::new(&f.command, &f.workdir, f.connect_timeout_s)
    }
}

impl PolicyCommand {
    /// `command` run in `workdir`, given `connect_timeout_s` to connect; refused when it
    /// lacks `{session}` (it could not join the run's session) or the wait is not one
    /// [`crate::policy::check_wait_s`] takes.
    pub fn new(command: &str, workdir: &Path, connect_timeout_s: f64) -> Result<Self, String> {
        if !command.contains(SESSION_PLACEHOLDER) {
            return Err(format!(
                "`command` must contain {SESSION_PLACEHOLDER}, the session each run serves"
            ));
        }
        crate::policy::check_wait_s(connect_timeout_s, false)
            .map_err(|why| format!("`connect_timeout_s` = {why}"))?;
        Ok(Self {
            command: command.to_string(),
            workdir: workdir.to_path_buf(),
            connect_timeout_s,
        })
    }

    /// The shell line as given, placeholders in it.
    pub fn command(&self) -> &str {
        &self.command
    }

    /// Where it runs.
    pub fn workdir(&self) -> &Path {
        &self.workdir
    }

    /// Seconds it has to connect.
    pub fn connect_timeout_s(&self) -> f64 {
        self.connect_timeout_s
    }

    /// Its first word (`python3`): how results name it when nothing else does.
    pub fn first_word(&self) -> &str {
        self.command.split_whitespace().next().unwrap_or("command")
    }

    /// The shell line for `session`, its placeholders filled in as single shell words.
    pub fn line(&self, session: &str) -> Result<String, CommandLineError> {
        process_group::policy_command_line(&self.command, session)
    }

    /// Starts it on `session` in its own process group, in its working directory, dying
    /// with this process, its output in `log` (at `log_path`) up to
    /// [`crate::files::capped_log::PROCESS_LOG_MAX_BYTES`]; `Err` says why it could not
    /// start.
    pub fn spawn(
        &self,
        session: &str,
        log: std::fs::File,
        log_path: &Path,
    ) -> Result<Child, String> {
        let line = self.line(session).map_err(|e| e.to_string())?;
        if !self.workdir.is_dir() {
            return Err(format!(
                "cannot start the policy command `{line}`: its working directory {} is not a directory",
                self.workdir.display()
            ));
        }
        shell_in_own_group(&line, &self.workdir, log, log_path)
            .and_then(|mut cmd| cmd.spawn())
            .map_err(|e| format!("cannot start the policy command `{line}`: {e}"))
    }
}

impl std::fmt::Display for PolicyCommand {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "`{}`", self.command)
    }
}
