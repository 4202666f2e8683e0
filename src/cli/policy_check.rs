//! `thorarena policy check SPEC`: the sanity check before a policy's scores count
//! (`thorarena::eval::sanity`), printed check by check with its numbers; a failed check makes
//! the command fail, naming it.

use std::path::PathBuf;
use thorarena::eval::pipeline::{check_named_policy, PolicyCheckRequest};

/// `thorarena policy …`
#[derive(Debug, clap::Subcommand)]
pub enum PolicyCommand {
    /// Check that a policy is wired right before scoring it: its file against the
    /// profile, standing 5 s, tracking without force, and doing clearly worse with zero
    /// action (so the network, not the PD, does the work). Exits non-zero on a failed check.
    Check(Args),
}

/// Arguments of `policy check`.
#[derive(Debug, clap::Args)]
pub struct Args {
    // Its help lists every family of the registry run in process.
    #[arg(value_parser = thorarena::policy::registry::PolicySource::parse, help = thorarena::policy::registry::policy_help(true))]
    pub policy: thorarena::policy::registry::PolicySource,
    // Its help says how the registry chooses the default.
    #[arg(long, help = thorarena::policy::registry::profile_help())]
    pub profile: Option<String>,
    /// Dataset holding the tracking reference [default: the bundled sample]; for a
    /// single-clip policy, its own clip (e.g. the dance imported from holosoma's network).
    #[arg(long, value_parser = thorarena::sim::motion::dataset_arg)]
    pub dataset: Option<PathBuf>,
    /// Sequence id to track [default: the dataset's sequence whose root travels farthest
    /// in the first --track-seconds, a walk].
    #[arg(long)]
    pub sequence: Option<String>,
    /// Seconds of the tracking reference to run.
    #[arg(long, default_value_t = 10.0)]
    pub track_seconds: f64,
    /// Largest RMS keypoint error tracking may have, mm.
    #[arg(long, default_value_t = 100.0)]
    pub max_kp_error_mm: f64,
    /// Robot.
    #[arg(long, default_value = "g1_29dof")]
    pub robot: String,
    /// Physics engine (as for `eval`).
    #[arg(long, value_enum, default_value = "rapier")]
    pub engine: super::choices::EngineArg,
    /// A user's MJCF for `--engine mujoco` (as for `eval`).
    #[arg(long)]
    pub mjcf: Option<PathBuf>,
    /// Print the report as one JSON object instead of lines.
    #[arg(long)]
    pub json: bool,
}

pub(super) fn run(cmd: &PolicyCommand) -> anyhow::Result<()> {
    let PolicyCommand::Check(args) = cmd;
    let report = check_named_policy(&PolicyCheckRequest {
        policy: args.policy.clone(),
        profile: args.profile.clone(),
        dataset: args.dataset.clone(),
        sequence: args.sequence.clone(),
        track_s: args.track_seconds,
        max_kp_rms_mm: args.max_kp_error_mm,
        robot: args.robot.clone(),
        engine: args.engine.into(),
        mjcf: args.mjcf.clone(),
    })?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print!("{report}");
    }
    Ok(report.verdict()?)
}
