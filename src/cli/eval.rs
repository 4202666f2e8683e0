//! `thorarena eval`: the benchmark — every sequence of a dataset with and without force,
//! scored with FATS and the diagnostics; results streamed to a run directory that can be
//! resumed after a crash, or sharded across machines and merged.

use super::policy_arg::make_policy_vetted;
pub use super::run_args::RunArgs;
use super::run_args::REQUEST_CONFLICTS;
use anyhow::{bail, Context};
use std::path::{Path, PathBuf};
use thorarena::evaluation::{EvalRequest, EvalSpec};
use thorarena::results::RunDir;

/// Arguments of `eval`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Built-in policy: `balance` (reference PD + tilt feedback), `replay` (reference
    /// joints, open loop) or `hold` (default pose); `twist2:<file.onnx>` for the TWIST2
    /// network in process (with `--profile twist2`); `beyondmimic:<file.onnx>` for a
    /// BeyondMimic-style tracking network (mjlab, whole_body_tracking, holosoma; e.g. with
    /// `--profile holosoma-wbt`); `wbc-mjlab:<file.onnx>` for wbc-mjlab's general tracker;
    /// or `ipc:<session>` to serve a session
    /// and evaluate whichever policy process connects to it (Python, C++, Rust clients).
    #[arg(long, default_value = "balance")]
    pub policy: String,
    /// Run the evaluation a request file describes (JSON, every field of
    /// `thorarena::evaluation::EvalRequest`; a sweep task writes one per attempt) instead
    /// of one given by flags. Only --out, --resume, --overwrite, --workers and the
    /// session options (--connect-timeout, --on-policy-failure, --spin-us) go with it.
    #[arg(long, conflicts_with_all = REQUEST_CONFLICTS)]
    pub request: Option<PathBuf>,
    /// Run directory (default: results/<policy>-<dataset name>).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Everything else of the run.
    #[command(flatten)]
    pub run: RunArgs,
}

/// The checked evaluation `args` ask for with `policy`; its advice is printed.
pub(super) fn load_spec(args: &RunArgs, policy: &str) -> anyhow::Result<EvalSpec> {
    load_request(&args.request(policy))
}

/// The checked evaluation of `request`; its advice is printed.
fn load_request(request: &EvalRequest) -> anyhow::Result<EvalSpec> {
    let spec = EvalSpec::load(request)?;
    for advice in &spec.advice {
        eprintln!("{}", super::flags::as_flags(&advice.to_string()));
    }
    Ok(spec)
}

/// The request in file `path`, with `--workers` when given.
fn read_request(path: &Path, workers: Option<usize>) -> anyhow::Result<EvalRequest> {
    let mut request = EvalRequest::read(path).context("--request")?;
    if workers.is_some() {
        request.workers = workers;
    }
    Ok(request)
}

pub(super) fn run(args: &Args) -> anyhow::Result<()> {
    let request = match &args.request {
        Some(path) => read_request(path, args.run.workers)?,
        None => args.run.request(&args.policy),
    };
    let spec = load_request(&request)?;
    let out_rules = OutRules::of(&args.run, &spec);
    // An unusable --out is found before a policy process is made to connect.
    if let Some(out) = &args.out {
        out_rules.check(out)?;
    }
    // What the run requires of a policy process's name, asked in its handshake: a free
    // default output directory, and the policy a resumed run was made with.
    let mut vet = |name: &str| -> Result<(), String> {
        let out = match &args.out {
            Some(out) => out.clone(),
            None => {
                let out = default_out(name, &spec);
                out_rules.check(&out).map_err(|e| format!("{e:#}"))?;
                out
            }
        };
        let run = RunDir::new(out);
        if args.run.resume && run.holds_run() {
            let previous = run.read_header().map_err(|e| e.to_string())?;
            if previous.policy != name {
                return Err(format!(
                    "--resume: {} is a run of policy `{}`, not `{name}`",
                    run.path().display(),
                    previous.policy
                ));
            }
        }
        Ok(())
    };
    let session = args.run.io.session_options(spec.io.budget_s)?;
    let mut policy = make_policy_vetted(
        &request.policy,
        &spec.robot,
        &spec.profile,
        &session,
        spec.envs,
        &mut vet,
    )?;
    let out = match &args.out {
        Some(out) => out.clone(),
        None => {
            thorarena::names::check_name("policy name", policy.name())?;
            let out = default_out(policy.name(), &spec);
            out_rules.check(&out)?;
            out
        }
    };
    super::eval_run::evaluate(args.run.resume, &spec, policy.as_mut(), &out, None)
}

/// `results/<policy>-<dataset name>`.
fn default_out(policy: &str, spec: &EvalSpec) -> PathBuf {
    PathBuf::from("results").join(format!("{policy}-{}", spec.dataset_name()))
}

/// What a run directory may already hold: `--resume`, `--overwrite`, and the dataset
/// it must not lie in.
pub(super) struct OutRules<'a> {
    resume: bool,
    overwrite: bool,
    dataset: &'a Path,
}

impl<'a> OutRules<'a> {
    /// The rules of `args` for a run of `spec`.
    pub fn of(args: &RunArgs, spec: &'a EvalSpec) -> Self {
        Self {
            resume: args.resume,
            overwrite: args.overwrite,
            dataset: &spec.dataset,
        }
    }

    /// Refuses to replace a finished or started run unless `--resume` or `--overwrite`
    /// says what to do with it, and checks that the directory can be written.
    pub fn check(&self, out: &Path) -> anyhow::Result<()> {
        thorarena::results::check_run_dir(out, true, Some(self.dataset))?;
        let run = RunDir::new(out);
        if run.holds_run() && !self.resume && !self.overwrite {
            bail!(
                "{} already holds a run: pass --resume to continue it, --overwrite to replace it, or choose another --out",
                out.display()
            );
        }
        // The run makes it again when it starts: a policy that fails to load leaves nothing.
        run.check_writable()?;
        Ok(())
    }
}
