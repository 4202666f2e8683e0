//! `thorarena view`: one episode's rollout trace (`eval --trace`) as a 3D replay in a
//! self-contained HTML page — the robot's collision shapes, the reference as a ghost,
//! the replayed hand forces as arrows, a timeline, and the keypoint error under it.

use std::path::PathBuf;
use thorarena::report::{write_view, WebBundle};

/// Arguments of `view`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// A trace file, `<run>/traces/<task>-<id>-<setting>.json`.
    pub trace: PathBuf,
    /// The HTML file to write.
    #[arg(long, default_value = "view.html")]
    pub out: PathBuf,
    /// Robot the trace was recorded on (a bundled name or a robot directory).
    #[arg(long, default_value = "g1_29dof")]
    pub robot: String,
    /// Replace a file of a run or a dataset with the page (never the trace shown).
    #[arg(long)]
    pub overwrite: bool,
}

pub(super) fn run(args: &Args) -> anyhow::Result<()> {
    let bundle = WebBundle::locate()?;
    for warning in bundle.stale_warnings() {
        eprintln!("{warning}");
    }
    let robot = thorarena::registry::robot(&args.robot)?;
    let written = write_view(&args.trace, &robot, &bundle, &args.out, args.overwrite)?;
    let shown = if written.reference_ghost {
        ", reference ghost"
    } else {
        "; the trace has no reference joints: the reference shows as keypoints"
    };
    eprintln!(
        "wrote {} ({} steps{shown})",
        args.out.display(),
        written.steps
    );
    Ok(())
}
