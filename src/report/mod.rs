//! Results for people: the paper's tables (Markdown for `tables.md`; Markdown, CSV and
//! HTML side by side for several runs), the self-contained HTML report of
//! `thorarena report`, and the 3D episode replay of `thorarena view`.
//!
//! The HTML pages are one file each: our templates and styles (`web/src/`, compiled in),
//! the page data as JSON, and the page script — our code bundled with three.js and
//! Chart.js by `npm run build --prefix web` into `web/bundle/` — all inlined, so a report
//! opens from disk or an e-mail attachment with no network. The bundle is committed and
//! compiled in ([`WebBundle`]), so building and running need no node; a test proves the
//! committed copy is exactly what the lockfile builds.
//!
//! The figures are computed once as data ([`report_figures`]: colour per policy, dash and
//! marker per other axis, legends) and drawn twice: by the page script with Chart.js, and
//! as SVG files for papers ([`svg_figures`]).

mod comparison_files;
mod crosscheck_tables;
mod figures;
mod html;
mod run_tables;
mod runs;
mod scene;
mod style;
mod svg;
mod tables;

pub use comparison_files::{
    write_comparison_report, write_figures, write_page, write_sweep_report, ComparisonFiles,
    WrittenReport, WrittenSweepReport,
};
pub use crosscheck_tables::{crosscheck_report, crosscheck_tables};
pub use figures::{
    report_figures, CurveSeries, Dataset, Figure, FigureKind, LegendEntry, ReportFigures, Swatch,
    SweepChart,
};
pub use html::{escape, report_html, sweep_report_html, view_html, Page, WebBundle, WEB_DIST_ENV};
pub use run_tables::{run_tables, write_run_tables};
pub use runs::{
    comparison_notes, comparison_warnings, label_engines, label_runs, load_run, load_runs,
    mixed_engines, one_engine_or_labelled, ComparisonWarning, EpisodePoint, Run, WarningKind,
    MIXED_ENGINES_WHY,
};
pub use scene::{
    load_trace, trace_context, view_scene, write_view, BodyShapes, FeetView, ShapeView,
    TraceContext, ViewScene, WrittenView,
};
pub use style::{jitter, PolicyColors, DASHES, MARKERS, PALETTE, SURVIVAL_JITTER};
pub use svg::{figure_svg, svg_figures, SvgFigure};
pub use tables::{
    all_tasks, columns, comparison_markdown, diagnostics_multi_table, diagnostics_table,
    fats_table, outside_training_note, task_fats_table, DiagnosticRow, NumberRow, NumberTable,
    DIAGNOSTIC_ROWS,
};

use std::path::PathBuf;

/// Why a report or a view could not be made.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// A file could not be read.
    #[error("reading {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// A results file is not the JSON it should be.
    #[error("parsing {path}: {source}")]
    Json {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: serde_json::Error,
    },
    /// A run directory that cannot be reported.
    #[error("run {path}: {reason}")]
    BadRun {
        /// The run directory.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// A trace that does not fit the robot, or holds no step.
    #[error("trace {path}: {reason}")]
    BadTrace {
        /// The trace file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// A file or directory could not be written.
    #[error("writing {path}: {source}")]
    Write {
        /// The file or directory.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// An output would replace an input, or a run's or a dataset's file unasked.
    #[error(transparent)]
    Refused(#[from] crate::eval::results::OutputRefused),
    /// A run directory's files are unreadable or do not hold a valid run.
    #[error(transparent)]
    Results(#[from] crate::eval::results::ResultsError),
    /// The bundle directory named by [`WEB_DIST_ENV`] lacks a script.
    #[error(
        "the front-end bundle directory named by {WEB_DIST_ENV} has no {path} \
         (build one with `npm ci --prefix web && npm run build --prefix web -- --outdir=DIR`, \
         or unset {WEB_DIST_ENV} to use the bundle compiled into thorarena)"
    )]
    BundleMissing {
        /// The file looked for.
        path: PathBuf,
    },
}
