//! `sweep collect` in one call: the datasets checked to be the ones planned, the tasks
//! that count, each cell's shards merged into `cells/<C>/` with its `tables.md`, the
//! sweep's `results.csv`, and its report with the curves over its axes (`figures.rs`).

use super::figures::{label_cells, sweep_charts, sweep_title};
use super::{planned_sequences, write_results_csv, CellResult, CountedTasks, Plan, SweepError};
use crate::eval::results::{ResultsError, RunDir};
use crate::report::{load_runs, write_run_tables, MIXED_ENGINES_WHY};
use crate::report::{write_sweep_report, Page, ReportError, WebBundle, WrittenSweepReport};
use std::collections::BTreeSet;
use std::fmt::{self, Display, Formatter};
use std::path::{Path, PathBuf};

/// A collect as asked for.
#[derive(Debug, Clone, Copy)]
pub struct SweepCollect<'a> {
    /// The sweep directory.
    pub dir: &'a Path,
    /// Collect although some cells are unfinished (their rows say how many episodes they
    /// hold).
    pub partial: bool,
    /// Put cells simulated by different physics engines into one table and one set of
    /// curves.
    pub mixed_engines: bool,
}

/// What a collect wrote.
#[derive(Debug)]
pub struct CollectedSweep {
    /// Cells collected (a cell with no done task has none to merge).
    pub cells: usize,
    /// Cells unfinished among the planned.
    pub unfinished: usize,
    /// `results.csv`.
    pub results_csv: PathBuf,
    /// The report and its SVG figures.
    pub report: WrittenSweepReport,
}

/// Why a sweep could not be collected.
#[derive(Debug, thiserror::Error)]
pub enum CollectError {
    /// The plan, a dataset, a task's run or `results.csv`.
    #[error(transparent)]
    Sweep(#[from] SweepError),
    /// A cell's shards could not be merged, or its tables written.
    #[error(transparent)]
    Results(#[from] ResultsError),
    /// The report could not be made.
    #[error(transparent)]
    Report(#[from] ReportError),
    /// Cells of different physics engines, not asked to be compared.
    #[error(
        "this sweep's cells were simulated by different physics engines ({engines}); {}: collect with `option.mixed_engines` to put them in one table and one set of curves (rows and labels then name their engine)",
        MIXED_ENGINES_WHY
    )]
    MixedEngines {
        /// The engines, comma-separated.
        engines: String,
    },
}

/// Collects the sweep `collect` names; `note` hears each task marked done whose run does
/// not count (`not counted: task I: why`) before the cells are merged.
pub fn collect_sweep(
    collect: &SweepCollect,
    note: &mut dyn FnMut(&str),
) -> Result<CollectedSweep, CollectError> {
    let dir = collect.dir;
    let plan = Plan::load(dir)?;
    let robot = crate::policy::registry::robot(&plan.robot).map_err(SweepError::from)?;
    let datasets = planned_sequences(&plan, &robot)?;
    let counted = CountedTasks::of(dir, &plan)?;
    counted.require_finished(&plan, collect.partial)?;
    for why in &counted.not_counted {
        note(&format!("not counted: {why}"));
    }
    let engines: BTreeSet<&str> = plan
        .cells
        .iter()
        .map(|c| c.engine.engine.as_str())
        .collect();
    if engines.len() > 1 && !collect.mixed_engines {
        return Err(CollectError::MixedEngines {
            engines: engines.into_iter().collect::<Vec<_>>().join(", "),
        });
    }
    let mut results: Vec<Option<CellResult>> = Vec::new();
    for cell in &plan.cells {
        let shards: Vec<RunDir> = counted
            .runs_of_cell(dir, &plan, cell.index)
            .iter()
            .map(RunDir::new)
            .collect();
        if shards.is_empty() {
            results.push(None);
            continue;
        }
        let out = RunDir::new(Plan::cell_dir(dir, cell.index));
        let result = CellResult::collect(&shards, &out, &datasets[&cell.dataset], cell.episodes)?;
        write_run_tables(out.path(), &result.summary)?;
        results.push(Some(result));
    }
    let results_csv = write_results_csv(dir, &plan, &results)?;
    let cell_dirs: Vec<PathBuf> = results.iter().flatten().map(|r| r.dir.clone()).collect();
    let mut runs = load_runs(&cell_dirs)?;
    label_cells(&plan, &results, &mut runs);
    let charts = sweep_charts(&plan, &results);
    let script = WebBundle::locate()?.script(Page::Report)?;
    let report = write_sweep_report(dir, &runs, &charts, &sweep_title(&plan), &script)?;
    Ok(CollectedSweep {
        cells: results.iter().flatten().count(),
        unfinished: counted.unfinished_cells.len(),
        results_csv,
        report,
    })
}

impl Display for CollectedSweep {
    /// The line `sweep collect` ends with.
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        write!(f, "collected {} cells", self.cells)?;
        if self.unfinished > 0 {
            write!(f, " ({} partial)", self.unfinished)?;
        }
        write!(
            f,
            ": {}, {} and {} SVG figures in {}",
            self.results_csv.display(),
            self.report.page.display(),
            self.report.figures,
            self.report.figures_dir.display()
        )
    }
}
