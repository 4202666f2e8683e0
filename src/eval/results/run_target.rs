//! Where a run is written and what it may find there: a directory given or the default
//! `results/<policy>-<dataset name>`, never over a dataset, and a run already there only
//! continued (`resume`) or replaced (`overwrite`) when asked — checked before a policy
//! process is made to connect, and again in its handshake once its name is known.

use super::{check_run_dir, OutputRefused, ResultsError, RunDir};
use crate::eval::EvalSpec;
use crate::files::names::{check_name, NameError};
use std::path::{Path, PathBuf};

/// Why a run cannot go where it was asked to.
#[derive(Debug, thiserror::Error)]
pub enum RunTargetError {
    /// The directory lies in the dataset, holds a dataset, or is another kind of output.
    #[error(transparent)]
    Refused(#[from] OutputRefused),
    /// The directory's run could not be read, or the directory cannot be written.
    #[error(transparent)]
    Results(#[from] ResultsError),
    /// A policy name that cannot be part of a directory name.
    #[error(transparent)]
    Name(#[from] NameError),
    /// A run is there and nothing says what to do with it.
    #[error("{} already holds a run: pass `option.resume` to continue it, `option.overwrite` to replace it, or choose another `option.out`", .0.display())]
    HoldsRun(PathBuf),
    /// A resumed run was made with another policy.
    #[error("resuming: {} is a run of policy `{previous}`, not `{name}`", .path.display())]
    OtherPolicy {
        /// The run directory.
        path: PathBuf,
        /// The policy that made it.
        previous: String,
        /// The policy now.
        name: String,
    },
}

/// The run directory rules of one evaluation.
#[derive(Debug, Clone)]
pub struct RunTarget<'a> {
    /// The directory asked for; `None`: [`RunTarget::default_out`] of the policy's name.
    pub out: Option<PathBuf>,
    /// Continue a run already there.
    pub resume: bool,
    /// Replace a run already there.
    pub overwrite: bool,
    /// The evaluation (its dataset must not hold the run).
    pub spec: &'a EvalSpec,
}

impl RunTarget<'_> {
    /// `results/<policy>-<dataset name>`.
    pub fn default_out(&self, policy: &str) -> PathBuf {
        PathBuf::from("results").join(format!("{policy}-{}", self.spec.dataset_name()))
    }

    /// Refuses to replace a finished or started run unless `resume` or `overwrite` says
    /// what to do with it, and checks that the directory can be written.
    pub fn check(&self, out: &Path) -> Result<(), RunTargetError> {
        check_run_dir(out, true, Some(&self.spec.dataset))?;
        let run = RunDir::new(out);
        if run.holds_run() && !self.resume && !self.overwrite {
            return Err(RunTargetError::HoldsRun(out.to_path_buf()));
        }
        // The run makes it again when it starts: a policy that fails to load leaves nothing.
        run.check_writable()?;
        Ok(())
    }

    /// The given directory, checked (before any policy is made).
    pub fn check_given(&self) -> Result<(), RunTargetError> {
        match &self.out {
            Some(out) => self.check(out),
            None => Ok(()),
        }
    }

    /// What the run requires of policy `name` (a policy process's, asked in its
    /// handshake): a free default directory, and the policy a resumed run was made with.
    pub fn vet(&self, name: &str) -> Result<(), RunTargetError> {
        let out = match &self.out {
            Some(out) => out.clone(),
            None => {
                let out = self.default_out(name);
                self.check(&out)?;
                out
            }
        };
        let run = RunDir::new(&out);
        if self.resume && run.holds_run() {
            let previous = run.read_header()?.policy;
            if previous != name {
                return Err(RunTargetError::OtherPolicy {
                    path: out,
                    previous,
                    name: name.to_string(),
                });
            }
        }
        Ok(())
    }

    /// The directory of policy `name`'s run: the one given, else its checked default.
    pub fn out_for(&self, name: &str) -> Result<PathBuf, RunTargetError> {
        match &self.out {
            Some(out) => Ok(out.clone()),
            None => {
                check_name("policy name", name)?;
                let out = self.default_out(name);
                self.check(&out)?;
                Ok(out)
            }
        }
    }
}

/// The first `<root>/<stem>-<k>`, counting from `k = from`, that does not exist: a
/// service's runs never replace one another.
pub fn free_numbered_dir(root: &Path, stem: &str, from: usize) -> PathBuf {
    (from..)
        .map(|k| root.join(format!("{stem}-{k}")))
        .find(|dir| !dir.exists())
        .expect("some number is free")
}
