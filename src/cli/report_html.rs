//! `thorarena report`: one self-contained HTML page comparing runs (tables side by side,
//! FATS radar, tracking vs survival, low- vs high-force error, policy round trips), with
//! the tables also as Markdown and CSV next to it, and every figure as an SVG file in
//! `<stem>-figures/`, for papers.

use anyhow::Context;
use std::path::{Path, PathBuf};
use thorarena::report::{
    comparison_markdown, comparison_notes, comparison_warnings, diagnostics_multi_table,
    fats_table, label_engines, load_runs, mixed_engines, report_figures, report_html, svg_figures,
    Page, SvgFigure, WebBundle, MIXED_ENGINES_WHY,
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
    /// same policy (README, "Force response: rapier against MuJoCo"). With it, every run's
    /// label names its engine.
    #[arg(long)]
    pub mixed_engines: bool,
    /// Replace files of a run or a dataset with the report's (never the runs reported).
    #[arg(long)]
    pub overwrite: bool,
}

/// `dir/stem.html` → `dir/stem<suffix>`.
fn sibling(html: &Path, suffix: &str) -> PathBuf {
    let stem = html
        .file_stem()
        .map_or_else(|| "report".into(), |s| s.to_string_lossy().to_string());
    html.with_file_name(format!("{stem}{suffix}"))
}

fn write(path: &Path, text: &str) -> anyhow::Result<()> {
    std::fs::write(path, text).with_context(|| format!("writing {}", path.display()))
}

/// Writes each figure as `dir/<id>.svg` (creating `dir`); figure files of an earlier report
/// that this one does not draw are left as they are.
pub(super) fn write_figures(dir: &Path, figures: &[SvgFigure]) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    for f in figures {
        write(&dir.join(f.file_name()), &f.svg)?;
    }
    Ok(())
}

pub(super) fn run(args: &Args) -> anyhow::Result<()> {
    // The bundle first: a missing bundle directory should fail before any file is written.
    let bundle = WebBundle::locate()?;
    for stale in bundle.stale_sources() {
        eprintln!(
            "warning: {} is newer than the bundle in {}; rebuild it with `npm run build --prefix web -- --outdir={}`",
            stale.display(),
            bundle.describe(),
            bundle.describe()
        );
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
    for path in [
        args.out.clone(),
        sibling(&args.out, ".md"),
        sibling(&args.out, "-fats.csv"),
        sibling(&args.out, "-diagnostics.csv"),
    ] {
        thorarena::results::check_file(&path, args.overwrite, &args.runs)?;
    }
    let figures = svg_figures(&report_figures(&runs, &[]));
    let figures_dir = sibling(&args.out, "-figures");
    thorarena::results::check_files_dir(
        &figures_dir,
        &figures.iter().map(|f| f.file_name()).collect::<Vec<_>>(),
        args.overwrite,
        &args.runs,
    )?;
    if let Some(parent) = args.out.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent)
            .with_context(|| format!("creating {}", parent.display()))?;
    }
    let warnings = comparison_warnings(&runs);
    for w in &warnings {
        eprintln!("warning: {}", w.message);
    }
    let notes = comparison_notes(&runs);
    for n in &notes {
        eprintln!("note: {n}");
    }
    let fats = fats_table(&runs);
    let diagnostics = diagnostics_multi_table(&runs);
    let md = comparison_markdown(&runs, &warnings, &notes);
    let outputs = [
        (sibling(&args.out, ".md"), md),
        (sibling(&args.out, "-fats.csv"), fats.csv()),
        (sibling(&args.out, "-diagnostics.csv"), diagnostics.csv()),
        (
            args.out.clone(),
            report_html(&runs, &bundle.script(Page::Report)?),
        ),
    ];
    for (path, text) in &outputs {
        write(path, text)?;
    }
    write_figures(&figures_dir, &figures)?;
    eprintln!(
        "wrote {}, and {} SVG figures in {}: {}",
        outputs
            .iter()
            .map(|(p, _)| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", "),
        figures.len(),
        figures_dir.display(),
        figures
            .iter()
            .map(|f| f.file_name())
            .collect::<Vec<_>>()
            .join(", ")
    );
    Ok(())
}
