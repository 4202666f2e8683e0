//! [`Evaluation`]: the one door to a scored run. [`Evaluation::open`] takes an
//! [`EvalRequest`] and a [`Place`]: it loads and checks the spec (its advice told to the
//! observer), checks the place before any policy is made, opens the policy through
//! [`open_policy`] (a policy process vetted in its handshake against the place), and names
//! the run directory by the place's rule; [`Evaluation::run`] scores it with
//! [`super::evaluate`]. `eval`, `serve`, the leaderboard and `data check --rollout` open
//! their runs here, so a run found in a directory is judged by one rule
//! ([`same_policy`]) whichever command finds it.

use super::{evaluate, BenchmarkError, EvalObserver, EvalOptions, Evaluated};
use crate::eval::results::{
    free_numbered_dir, identity_differences, PolicyIdentity, RunDir, RunTarget, RunTargetError,
};
use crate::eval::{EvalRequest, EvalSpec, SpecError};
use crate::policy::launched::log_beside;
use crate::policy::registry::{open_policy, OpenPolicyError, PolicyTarget};
use crate::policy::{Policy, SessionOptions};
use std::path::PathBuf;

/// Where a run's results go, and what becomes of a run already there.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Place {
    /// `eval`'s: `out` (`None`: `results/<policy>-<dataset>`, named once the policy is
    /// known). A run found there is refused unless `resume` (continued when it is the
    /// same evaluation of the same policy, refused otherwise) or `overwrite` (replaced).
    Given {
        /// The directory asked for.
        out: Option<PathBuf>,
        /// Continue a run there.
        resume: bool,
        /// Replace a run there.
        overwrite: bool,
    },
    /// A directory the caller made for the run (the leaderboard's runs, `data check`'s
    /// rollouts): a run found there is continued when it ran this policy by content
    /// ([`same_policy`]), and started again from the start, with a note, when it did not
    /// or when `rerun` asks. A launched command's output goes beside it.
    Owned {
        /// The run directory.
        dir: PathBuf,
        /// Start a run there again from the start.
        rerun: bool,
    },
    /// `serve`'s: the first `root/<policy>-<dataset>-<n>` not taken, from `n = from`.
    Numbered {
        /// The directory of the runs.
        root: PathBuf,
        /// The first number tried.
        from: usize,
    },
}

/// Why a run could not be opened.
#[derive(Debug, thiserror::Error)]
pub enum OpenError {
    /// The evaluation asked for is not one that can run.
    #[error(transparent)]
    Spec(#[from] SpecError),
    /// The place refuses the run.
    #[error(transparent)]
    Place(#[from] RunTargetError),
    /// The policy could not be made, served or started.
    #[error(transparent)]
    Policy(#[from] OpenPolicyError),
}

/// An evaluation ready to score: its checked spec, its policy (connected when it is a
/// process), its run directory, and whether a run there is continued.
pub struct Evaluation {
    /// The evaluation, checked.
    pub spec: EvalSpec,
    /// The policy.
    pub policy: Box<dyn Policy>,
    /// Where its results go.
    pub run: RunDir,
    /// Continue the run found there.
    pub resume: bool,
}

impl Evaluation {
    /// Opens `request`'s run at `place`; a policy process is served with `session`, and
    /// the spec's advice and the session's news go to `observer`'s notes.
    pub fn open(
        request: &EvalRequest,
        place: Place,
        session: &SessionOptions,
        observer: &mut dyn EvalObserver,
    ) -> Result<Self, OpenError> {
        let spec = EvalSpec::load(request)?;
        for advice in &spec.advice {
            observer.note(&advice.to_string());
        }
        Self::of_spec(spec, request, place, session, observer)
    }

    /// [`Self::open`] of a spec already loaded from `request` (`serve` loads its spec once
    /// for every policy that connects).
    pub fn of_spec(
        spec: EvalSpec,
        request: &EvalRequest,
        place: Place,
        session: &SessionOptions,
        observer: &mut dyn EvalObserver,
    ) -> Result<Self, OpenError> {
        let given = match &place {
            Place::Given {
                out,
                resume,
                overwrite,
            } => Some(RunTarget {
                out: out.clone(),
                resume: *resume,
                overwrite: *overwrite,
                spec: &spec,
            }),
            Place::Owned { .. } | Place::Numbered { .. } => None,
        };
        // An unusable directory is found before a policy process is made to connect.
        if let Some(target) = &given {
            target.check_given()?;
        }
        let launch_log = match &place {
            Place::Given { out, .. } => out.as_deref().map(log_beside),
            Place::Owned { dir, .. } => Some(log_beside(dir)),
            Place::Numbered { .. } => None,
        };
        let target = PolicyTarget {
            robot: &spec.robot,
            profile: &spec.profile,
            process_profile: spec.process_profile,
            session,
            envs: spec.envs,
            launch_log: launch_log.as_deref(),
        };
        let mut vet = |name: &str| match &given {
            Some(target) => target
                .vet(name)
                .map_err(|e| crate::eval::flag_names::as_flags(&e.to_string())),
            None => Ok(()),
        };
        let policy = open_policy(&request.policy, &target, &mut vet, &mut |note| {
            observer.note(note)
        })?;
        let (out, resume) = match (place, given) {
            (Place::Given { resume, .. }, Some(target)) => (target.out_for(policy.name())?, resume),
            (Place::Owned { dir, rerun }, _) => {
                let run = RunDir::new(&dir);
                let resume = continues(&run, rerun, policy.as_ref(), &spec, observer);
                (dir, resume)
            }
            (Place::Numbered { root, from }, _) => {
                let stem = format!("{}-{}", policy.name(), spec.dataset_name());
                (free_numbered_dir(&root, &stem, from), false)
            }
            (Place::Given { .. }, None) => unreachable!("a given place has its target"),
        };
        Ok(Self {
            spec,
            policy,
            run: RunDir::new(out),
            resume,
        })
    }

    /// Scores the run, `observer` hearing its start and every episode.
    pub fn run(&mut self, observer: &mut dyn EvalObserver) -> Result<Evaluated, BenchmarkError> {
        let options = EvalOptions {
            resume: self.resume,
            trace_first_s: None,
        };
        evaluate(
            &self.spec,
            self.policy.as_mut(),
            &self.run,
            options,
            observer,
        )
    }
}

/// The differences between the policy that made the run in `run` and `policy` under
/// `spec`, by content (network, profile, robot: [`PolicyIdentity`]); empty when they are
/// the same, `None` when `run` holds no readable header. A run that never recorded its
/// policy's identity differs from every policy.
pub fn same_policy(run: &RunDir, policy: &dyn Policy, spec: &EvalSpec) -> Option<Vec<String>> {
    let previous = run.read_header().ok()?;
    let now = PolicyIdentity::of(policy, &spec.profile, &spec.robot);
    Some(identity_differences(previous.identity.as_ref(), Some(&now)))
}

/// Whether an owned place's run is continued: it exists, `rerun` does not ask for it
/// again, and it ran the same policy ([`same_policy`]); the observer hears why one is run
/// again. A run whose header cannot be read is left to the resume to refuse.
fn continues(
    run: &RunDir,
    rerun: bool,
    policy: &dyn Policy,
    spec: &EvalSpec,
    observer: &mut dyn EvalObserver,
) -> bool {
    if rerun {
        if run.header_file().exists() {
            observer.note(&format!(
                "  {}: running it again from the start, as `option.rerun` asks",
                run.path().display()
            ));
        }
        return false;
    }
    let Some(differences) = same_policy(run, policy, spec) else {
        return run.header_file().exists();
    };
    if differences.is_empty() {
        return true;
    }
    observer.note(&format!(
        "  {} ran another policy than this one ({}, the run's first): running it again from the start",
        run.path().display(),
        differences.join("; ")
    ));
    false
}
