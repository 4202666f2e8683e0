//! `thorarena report`: one self-contained HTML page comparing runs (tables side by side,
//! FATS radar, tracking vs survival, low- vs high-force error, policy round trips), with
//! the tables also as Markdown and CSV next to it, and every figure as an SVG file in
//! `<stem>-figures/`, for papers.

use std::path::PathBuf;
use thorarena::report::{
    label_engines, load_runs, mixed_engines, write_comparison_report, ComparisonFiles, Page,
    WebBundle, WrittenReport, MIXED_ENGINES_WHY,
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
    if let Some(groups) = mixed_engines(&runs) {
        if !args.mixed_engines {
            anyhow::bail!(
                "these runs were simulated by different physics engines ({groups}); {MIXED_ENGINES_WHY}: compare runs of one engine, or pass --mixed-engines to compare them anyway (each label then names its engine)"
            );
        }
        label_engines(&mut runs);
    }
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
