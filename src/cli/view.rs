//! `thorarena view`: one episode's rollout trace (`eval --trace`) as a 3D replay in a
//! self-contained HTML page — the robot's collision shapes, the reference as a ghost,
//! the replayed hand forces as arrows, a timeline, and the keypoint error under it.

use std::path::PathBuf;
use thorarena::report::{load_trace, trace_context, view_html, view_scene, Page, WebBundle};

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
    thorarena::results::check_file(&args.out, args.overwrite, std::slice::from_ref(&args.trace))?;
    let bundle = WebBundle::locate()?;
    for stale in bundle.stale_sources() {
        eprintln!(
            "warning: {} is newer than the bundle in {}; rebuild it with `npm run build --prefix web -- --outdir={}`",
            stale.display(),
            bundle.describe(),
            bundle.describe()
        );
    }
    let robot = thorarena::registry::robot(&args.robot)?;
    let trace = load_trace(&args.trace)?;
    let context = trace_context(&args.trace);
    let scene = view_scene(&robot, &trace, &args.trace, &context)?;
    let html = view_html(&scene, &bundle.script(Page::View)?);
    thorarena::report::write_page(&args.out, &html)?;
    eprintln!(
        "wrote {} ({} steps{})",
        args.out.display(),
        trace.len(),
        if scene.reference_poses.is_some() {
            ", reference ghost"
        } else {
            "; the trace has no reference joints: the reference shows as keypoints"
        }
    );
    Ok(())
}
