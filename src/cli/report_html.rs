//! The self-contained HTML pages. `thorarena report`: one page comparing runs (tables
//! side by side, FATS radar, tracking vs survival, low- vs high-force error, policy round
//! trips), with the tables also as Markdown and CSV next to it, and every figure as an SVG
//! file in `<stem>-figures/`, for papers.
//!
//! `thorarena view`: one episode's rollout trace (`eval --trace`) as a 3D replay in a
//! self-contained HTML page — the robot's collision shapes, the reference as a ghost,
//! the replayed hand forces as arrows, a timeline, and the keypoint error under it.

use std::path::PathBuf;
use thorarena::report::{
    load_runs, one_engine_or_labelled, write_comparison_report, write_view, ComparisonFiles, Page,
    WebBundle, WrittenReport,
};

/// Arguments of `report`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Run directories written by `eval`, `serve` or `merge` (one per policy).
    #[arg(required = true)]
    pub runs: Vec<PathBuf>,
    /// The HTML file; `<stem>.md`, `<stem>-fats.csv` and `<stem>-diagnostics.csv` are
    /// written next to it, and each figure as `<stem>-figures/<figure>.svg`.
    #[arg(long, default_value = "report.html")]
    pub out: PathBuf,
    /// Compare runs simulated by different physics engines (rapier, MuJoCo). Refused
    /// without it: under force the engines' scores differ by up to 30 FATS points on the
    /// same policy (docs/engines.md, "Force response: rapier against MuJoCo"). With it, every run's
    /// label names its engine.
    #[arg(long)]
    pub mixed_engines: bool,
    /// Replace files of a run or a dataset with the report's (never the runs reported).
    #[arg(long)]
    pub overwrite: bool,
}

pub(super) fn run(args: &Args) -> anyhow::Result<()> {
    // The bundle first: a missing bundle directory should fail before any file is written.
    let bundle = WebBundle::locate()?;
    for warning in bundle.stale_warnings() {
        eprintln!("{warning}");
    }
    let mut runs = load_runs(&args.runs)?;
    one_engine_or_labelled(&mut runs, args.mixed_engines)
        .map_err(|why| anyhow::anyhow!(super::flags::as_flags(&why)))?;
    let files = ComparisonFiles::beside(&args.out);
    let script = bundle.script(Page::Report)?;
    let written = write_comparison_report(&runs, &files, &script, args.overwrite, &args.runs)?;
    tell_written(&written, &files);
    Ok(())
}

/// What a comparison report wrote, on stderr: its warnings and notes, then its files and
/// figures.
pub(super) fn tell_written(written: &WrittenReport, files: &ComparisonFiles) {
    for line in written.news(files) {
        eprintln!("{line}");
    }
}

/// Arguments of `view`.
#[derive(Debug, clap::Args)]
pub struct ViewArgs {
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

/// `view`: the trace's replay page written.
pub(super) fn view(args: &ViewArgs) -> anyhow::Result<()> {
    let bundle = WebBundle::locate()?;
    for warning in bundle.stale_warnings() {
        eprintln!("{warning}");
    }
    let robot = thorarena::policy::registry::robot(&args.robot)?;
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
