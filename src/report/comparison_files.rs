//! The files of a comparison report, named from its HTML page (`<stem>.html`): the tables
//! as Markdown and CSV beside it, and every figure as an SVG file in `<stem>-figures/`,
//! for papers. Written only after every one of them has passed the output guard
//! ([`crate::eval::results::check_file`]), so a refused report writes nothing.

use super::figures::report_figures;
use super::html::report_html;
use super::runs::{comparison_notes, comparison_warnings, ComparisonWarning, Run};
use super::svg::{svg_figures, SvgFigure};
use super::tables::{comparison_markdown, diagnostics_multi_table, fats_table};
use super::ReportError;
use crate::eval::results::{check_file, check_files_dir};
use std::path::{Path, PathBuf};

/// Where a comparison report goes.
#[derive(Debug, Clone, PartialEq)]
pub struct ComparisonFiles {
    /// The self-contained page.
    pub html: PathBuf,
    /// `<stem>.md`: the tables, warnings and notes.
    pub markdown: PathBuf,
    /// `<stem>-fats.csv`.
    pub fats_csv: PathBuf,
    /// `<stem>-diagnostics.csv`.
    pub diagnostics_csv: PathBuf,
    /// `<stem>-figures/`: one `<figure>.svg` per figure.
    pub figures_dir: PathBuf,
}

impl ComparisonFiles {
    /// The files of the page `html`.
    pub fn beside(html: &Path) -> Self {
        let stem = html
            .file_stem()
            .map_or_else(|| "report".into(), |s| s.to_string_lossy().to_string());
        let sibling = |suffix: &str| html.with_file_name(format!("{stem}{suffix}"));
        Self {
            html: html.to_path_buf(),
            markdown: sibling(".md"),
            fats_csv: sibling("-fats.csv"),
            diagnostics_csv: sibling("-diagnostics.csv"),
            figures_dir: sibling("-figures"),
        }
    }
}

/// What a written report said and where it went.
#[derive(Debug, Clone)]
pub struct WrittenReport {
    /// Differences between the runs that make a comparison questionable.
    pub warnings: Vec<ComparisonWarning>,
    /// What the reader should know (runs of one dataset under different names, …).
    pub notes: Vec<String>,
    /// The page, the Markdown and the CSVs, as written.
    pub files: Vec<PathBuf>,
    /// The figure files written into [`ComparisonFiles::figures_dir`].
    pub figures: Vec<String>,
}

impl WrittenReport {
    /// What a command says after writing the report into `files`: each warning and note,
    /// then the files and figures written.
    pub fn news(&self, files: &ComparisonFiles) -> Vec<String> {
        let mut news: Vec<String> = self
            .warnings
            .iter()
            .map(|w| format!("warning: {}", w.message))
            .collect();
        news.extend(self.notes.iter().map(|n| format!("note: {n}")));
        let written: Vec<String> = self.files.iter().map(|p| p.display().to_string()).collect();
        news.push(format!(
            "wrote {}, and {} SVG figures in {}: {}",
            written.join(", "),
            self.figures.len(),
            files.figures_dir.display(),
            self.figures.join(", ")
        ));
        news
    }
}

/// Writes the comparison of `runs` (read from `inputs`) to `files`, the page carrying
/// `script` (the front-end bundle's); nothing is written if any file would replace an
/// input, or a run's or a dataset's file without `overwrite`.
pub fn write_comparison_report(
    runs: &[Run],
    files: &ComparisonFiles,
    script: &str,
    overwrite: bool,
    inputs: &[PathBuf],
) -> Result<WrittenReport, ReportError> {
    for path in [
        &files.html,
        &files.markdown,
        &files.fats_csv,
        &files.diagnostics_csv,
    ] {
        check_file(path, overwrite, inputs)?;
    }
    let figures = svg_figures(&report_figures(runs, &[]));
    let names: Vec<String> = figures.iter().map(|f| f.file_name()).collect();
    check_files_dir(&files.figures_dir, &names, overwrite, inputs)?;
    if let Some(parent) = files.html.parent().filter(|p| !p.as_os_str().is_empty()) {
        create_dir(parent)?;
    }
    let warnings = comparison_warnings(runs);
    let notes = comparison_notes(runs);
    let outputs = [
        (
            &files.markdown,
            comparison_markdown(runs, &warnings, &notes),
        ),
        (&files.fats_csv, fats_table(runs).csv()),
        (&files.diagnostics_csv, diagnostics_multi_table(runs).csv()),
        (&files.html, report_html(runs, script)),
    ];
    for (path, text) in &outputs {
        write(path, text)?;
    }
    write_figures(&files.figures_dir, &figures)?;
    Ok(WrittenReport {
        warnings,
        notes,
        files: outputs.iter().map(|(p, _)| p.to_path_buf()).collect(),
        figures: names,
    })
}

/// Writes each figure as `dir/<id>.svg` (creating `dir`); figure files of an earlier
/// report that this one does not draw are left as they are.
pub fn write_figures(dir: &Path, figures: &[SvgFigure]) -> Result<(), ReportError> {
    // The report's own directory, made beside the page: a link planted under its name is
    // not entered.
    crate::files::no_follow::make_dir_within(dir.parent().unwrap_or(Path::new("")), dir).map_err(
        |source| ReportError::Write {
            path: dir.to_path_buf(),
            source,
        },
    )?;
    for f in figures {
        write(&dir.join(f.file_name()), &f.svg)?;
    }
    Ok(())
}

fn create_dir(dir: &Path) -> Result<(), ReportError> {
    std::fs::create_dir_all(dir).map_err(|source| ReportError::Write {
        path: dir.to_path_buf(),
        source,
    })
}

fn write(path: &Path, text: &str) -> Result<(), ReportError> {
    crate::files::atomic_file::write(path, text).map_err(|source| ReportError::Write {
        path: path.to_path_buf(),
        source,
    })
}

/// Writes a self-contained page to `path`, creating its directory.
pub fn write_page(path: &Path, html: &str) -> Result<(), ReportError> {
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        create_dir(parent)?;
    }
    write(path, html)
}

/// Where a sweep's report went.
#[derive(Debug, Clone)]
pub struct WrittenSweepReport {
    /// `report.html`.
    pub page: PathBuf,
    /// `report-figures/`.
    pub figures_dir: PathBuf,
    /// How many SVG figures it holds.
    pub figures: usize,
}

/// Writes a sweep's comparison of its cells' `runs` to `dir`/`report.html`, with its
/// `charts` (the sweep's axes) and every figure as SVG in `dir`/`report-figures/`.
pub fn write_sweep_report(
    dir: &Path,
    runs: &[Run],
    charts: &[super::SweepChart],
    title: &str,
    script: &str,
) -> Result<WrittenSweepReport, ReportError> {
    let page = dir.join("report.html");
    write(
        &page,
        &super::html::sweep_report_html(runs, charts, title, script),
    )?;
    let figures_dir = dir.join("report-figures");
    let figures = svg_figures(&report_figures(runs, charts));
    write_figures(&figures_dir, &figures)?;
    Ok(WrittenSweepReport {
        page,
        figures_dir,
        figures: figures.len(),
    })
}
