//! What a leaderboard invocation leaves besides its runs: its tables — the general
//! policies, the same on the real walks, the single-clip ones, the compliant and stiff pairs, each group under its
//! heading — in `leaderboard.md`, the pairs' own files, and a comparison report over each
//! group of runs (`report.html` over the general policies', `real-walks.html` over their
//! real-walks runs, `single-clip.html` over the single-clip ones, engines labelled when
//! they differ).

use super::pairs::{pairs_table, write_pair_files, PairResult};
use super::{leaderboard_table, write_leaderboard_page, Entry, TaskForceSpans, Track};
use crate::report::{
    label_engines, load_runs, mixed_engines, write_comparison_report, ComparisonFiles, ReportError,
    WrittenReport,
};
use std::path::{Path, PathBuf};

/// What `leaderboard.md` says of the invocation beside its tables.
#[derive(Debug, Clone)]
pub struct PageHeader<'a> {
    /// The dataset of the general policies.
    pub dataset: &'a Path,
    /// Their settings.
    pub settings: &'a [crate::eval::Setting],
    /// The command's arguments, as typed.
    pub command: &'a str,
    /// Wall time of the invocation so far, s.
    pub wall_s: f64,
}

/// The files written, for the caller to tell.
#[derive(Debug)]
pub struct LeaderboardOutputs {
    /// The tables, as in `leaderboard.md`.
    pub tables: String,
    /// `leaderboard.md`.
    pub page: PathBuf,
    /// `pairs.md` and `pairs.csv`, when there are pairs.
    pub pair_files: Option<[PathBuf; 2]>,
    /// Each comparison report written, and where.
    pub reports: Vec<(WrittenReport, ComparisonFiles)>,
}

/// Why the leaderboard's own files could not be written.
#[derive(Debug, thiserror::Error)]
pub enum OutputsError {
    /// `leaderboard.md` or a pair file.
    #[error("{}: {source}", .path.display())]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// A comparison report.
    #[error(transparent)]
    Report(#[from] ReportError),
}

/// The tables of `entries` and `pairs`, each group under its heading; `spans`, where the
/// general dataset's forces point per task, marks the general entries' cells outside
/// their policies' training.
pub fn leaderboard_tables(
    entries: &[Entry],
    pairs: &[PairResult],
    spans: &TaskForceSpans,
) -> String {
    let on = |track| -> Vec<&Entry> { entries.iter().filter(|e| e.track == track).collect() };
    let (general, real, own) = (on(Track::General), on(Track::RealWalks), on(Track::OwnClip));
    let mut parts = Vec::new();
    if !general.is_empty() {
        parts.push(leaderboard_table(&general, spans));
    }
    if !real.is_empty() {
        parts.push(format!(
            "The same general policies on real human walks (the bundled `real-walks`: TWIST2's ten, no force logs; their runs are recorded `unchecked`, the gate being the run above):\n\n{}",
            leaderboard_table(&real, &TaskForceSpans::new())
        ));
    }
    if !own.is_empty() {
        parts.push(format!(
            "Single-clip policies, each on its own clip:\n\n{}",
            leaderboard_table(&own, &TaskForceSpans::new())
        ));
    }
    if !pairs.is_empty() {
        parts.push(format!(
            "Compliant and stiff pairs, each on its own clip:\n\n{}",
            pairs_table(pairs)
        ));
    }
    parts.join("\n")
}

/// Writes the tables, the pairs' files and the reports into `out`; `script` is the
/// reports' front end.
pub fn write_leaderboard_outputs(
    out: &Path,
    entries: &[Entry],
    pairs: &[PairResult],
    spans: &TaskForceSpans,
    header: &PageHeader,
    script: &str,
) -> Result<LeaderboardOutputs, OutputsError> {
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| OutputsError::Io { path, source }
    };
    let tables = leaderboard_tables(entries, pairs, spans);
    let pair_files = if pairs.is_empty() {
        None
    } else {
        Some(write_pair_files(out, pairs).map_err(io(out))?)
    };
    let page = write_leaderboard_page(
        out,
        header.dataset,
        header.settings,
        header.command,
        header.wall_s,
        &tables,
    )
    .map_err(io(out))?;
    let mut reports = Vec::new();
    for (track, name) in [
        (Track::General, "report.html"),
        (Track::RealWalks, "real-walks.html"),
        (Track::OwnClip, "single-clip.html"),
    ] {
        let dirs: Vec<PathBuf> = entries
            .iter()
            .filter(|e| e.track == track)
            .map(|e| e.run.clone())
            .collect();
        if dirs.is_empty() {
            continue;
        }
        let mut runs = load_runs(&dirs)?;
        if mixed_engines(&runs).is_some() {
            label_engines(&mut runs);
        }
        let files = ComparisonFiles::beside(&out.join(name));
        let written = write_comparison_report(&runs, &files, script, true, &dirs)?;
        reports.push((written, files));
    }
    Ok(LeaderboardOutputs {
        tables,
        page,
        pair_files,
        reports,
    })
}
