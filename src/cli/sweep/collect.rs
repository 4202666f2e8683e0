//! `sweep collect`: shards merged into cells, `results.csv`, and the report with the
//! sweep's curves.

use super::CollectArgs;
use anyhow::{bail, Context};
use std::collections::{BTreeMap, HashSet};
use std::path::{Path, PathBuf};
use thorarena::motion::{Dataset, Sequence};
use thorarena::report::{label_cells, sweep_charts, sweep_title};
use thorarena::results::RunDir;
use thorarena::sweep::{compact_ranges, CellResult, Plan, Task, TaskDir};
use thorarena::sweep::{CheckedCensus, RunProblem};

/// Each dataset of the plan, loaded, after checking it is the one planned: scores are
/// computed against the references as they are now, so they must be the ones the runs
/// ran (`merge` and `--resume` check the same).
fn planned_datasets(
    plan: &Plan,
    robot: &thorarena::robot::RobotModel,
) -> anyhow::Result<BTreeMap<PathBuf, Vec<Sequence>>> {
    let mut datasets: BTreeMap<PathBuf, Vec<Sequence>> = BTreeMap::new();
    for cell in &plan.cells {
        if datasets.contains_key(&cell.dataset) {
            continue;
        }
        let ds = Dataset::open(&cell.dataset, robot)
            .with_context(|| format!("dataset of cell {}", cell.index))?;
        let now = ds.content_hash();
        if now != cell.dataset_sha256 {
            bail!(
                "dataset {} changed since the sweep was planned (content hash {} then, {} now): its runs would be scored against other references; restore it, or plan a new sweep",
                cell.dataset.display(),
                &cell.dataset_sha256[..cell.dataset_sha256.len().min(12)],
                &now[..12]
            );
        }
        datasets.insert(cell.dataset.clone(), ds.load_all()?);
    }
    Ok(datasets)
}

/// The done tasks that count — `done.json` there, and a run complete and the task's own
/// — and why the others do not; a done task whose run is another configuration's is an
/// error.
fn counted_tasks(dir: &Path, plan: &Plan) -> anyhow::Result<(HashSet<usize>, Vec<String>)> {
    let checked = CheckedCensus::of(dir, plan)?;
    let mut not_counted: Vec<String> = Vec::new();
    for (i, problem) in &checked.not_counted {
        match problem {
            RunProblem::NotThisTask(why) => bail!(
                "{why}; a run that is not the cell's is never scored under its label: remove {} and run the task again",
                TaskDir::of(dir, *i).run_dir().display()
            ),
            RunProblem::Incomplete(why) => not_counted.push(format!("task {i}: {why}")),
        }
    }
    Ok((checked.census.done.into_iter().collect(), not_counted))
}

pub(super) fn collect(args: &CollectArgs) -> anyhow::Result<()> {
    let plan = Plan::load(&args.dir)?;
    let robot = thorarena::registry::robot(&plan.robot)?;
    let datasets = planned_datasets(&plan, &robot)?;
    let (done, not_counted) = counted_tasks(&args.dir, &plan)?;
    let mut by_cell: BTreeMap<usize, Vec<&Task>> = BTreeMap::new();
    for t in &plan.tasks {
        by_cell.entry(t.cell).or_default().push(t);
    }
    let unfinished: Vec<usize> = by_cell
        .iter()
        .filter(|(_, ts)| ts.iter().any(|t| !done.contains(&t.index)))
        .map(|(&c, _)| c)
        .collect();
    let not_done: Vec<usize> = plan
        .tasks
        .iter()
        .map(|t| t.index)
        .filter(|i| !done.contains(i))
        .collect();
    if !unfinished.is_empty() && !args.partial {
        bail!(
            "{} of {} cells are unfinished (cells {}; tasks not done: {}{}): run them (`sweep run` resumes them), or collect with --partial",
            unfinished.len(),
            plan.cells.len(),
            compact_ranges(&unfinished),
            compact_ranges(&not_done),
            not_counted
                .iter()
                .map(|w| format!("; {w}"))
                .collect::<String>()
        );
    }
    for w in &not_counted {
        eprintln!("not counted: {w}");
    }
    let engines: std::collections::BTreeSet<&str> = plan
        .cells
        .iter()
        .map(|c| c.engine.engine.as_str())
        .collect();
    if engines.len() > 1 && !args.mixed_engines {
        bail!(
            "this sweep's cells were simulated by different physics engines ({}); {}: collect with --mixed-engines to put them in one table and one set of curves (rows and labels then name their engine)",
            engines.into_iter().collect::<Vec<_>>().join(", "),
            thorarena::report::MIXED_ENGINES_WHY
        );
    }
    let mut results: Vec<Option<CellResult>> = Vec::new();
    for cell in &plan.cells {
        let tasks = &by_cell[&cell.index];
        let runs: Vec<PathBuf> = tasks
            .iter()
            .filter(|t| done.contains(&t.index))
            .map(|t| TaskDir::of(&args.dir, t.index).run_dir())
            .collect();
        if runs.is_empty() {
            results.push(None);
            continue;
        }
        let shard_dirs: Vec<RunDir> = runs.iter().map(RunDir::new).collect();
        let out = RunDir::new(Plan::cell_dir(&args.dir, cell.index));
        let result =
            CellResult::collect(&shard_dirs, &out, &datasets[&cell.dataset], cell.episodes)?;
        thorarena::report::write_run_tables(out.path(), &result.summary)?;
        results.push(Some(result));
    }
    let csv_path = thorarena::sweep::write_results_csv(&args.dir, &plan, &results)?;
    let cell_dirs: Vec<PathBuf> = results.iter().flatten().map(|r| r.dir.clone()).collect();
    let mut runs = thorarena::report::load_runs(&cell_dirs)?;
    label_cells(&plan, &results, &mut runs);
    let charts = sweep_charts(&plan, &results);
    let script = thorarena::report::WebBundle::locate()?.script(thorarena::report::Page::Report)?;
    let report = thorarena::report::write_sweep_report(
        &args.dir,
        &runs,
        &charts,
        &sweep_title(&plan),
        &script,
    )?;
    eprintln!(
        "collected {} cells{}: {}, {} and {} SVG figures in {}",
        results.iter().flatten().count(),
        if unfinished.is_empty() {
            String::new()
        } else {
            format!(" ({} partial)", unfinished.len())
        },
        csv_path.display(),
        report.page.display(),
        report.figures,
        report.figures_dir.display()
    );
    Ok(())
}
