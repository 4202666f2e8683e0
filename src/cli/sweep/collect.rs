//! `sweep collect`: shards merged into cells, `results.csv`, and the report with the
//! sweep's curves.

use super::*;

/// What a cell's collected run holds.
pub(super) struct CellResult {
    pub(super) dir: PathBuf,
    pub(super) episodes: usize,
    pub(super) complete: bool,
    pub(super) summary: Summary,
    /// Summed over shards: deadline misses, invalid actions, policy failures.
    pub(super) faults: [u64; 3],
    /// p50, p99, p99.9 µs of a single-shard cell (shards keep separate histograms).
    pub(super) latency_us: Option<[f64; 3]>,
}

pub(super) fn collect(args: &CollectArgs) -> anyhow::Result<()> {
    let plan = Plan::load(&args.dir)?;
    let robot = thorarena::registry::robot(&plan.robot)?;
    // Scores are computed against the references as they are now: they must be the
    // ones the runs ran (`merge` and `--resume` check the same).
    let mut datasets: BTreeMap<PathBuf, Vec<thorarena::motion::Sequence>> = BTreeMap::new();
    for cell in &plan.cells {
        if datasets.contains_key(&cell.dataset) {
            continue;
        }
        let ds = Dataset::open(&cell.dataset, &robot)
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
    let c = census(&args.dir, &plan)?;
    // A task counts when its done.json is there and its run is complete and its own.
    let mut done: std::collections::HashSet<usize> = std::collections::HashSet::new();
    let mut not_counted: Vec<String> = Vec::new();
    for &i in &c.done {
        let run = Plan::task_dir(&args.dir, i).join("run");
        match check_task_run(&plan, &plan.tasks[i], &run)? {
            Ok(_) => {
                done.insert(i);
            }
            Err(RunProblem::NotThisTask(why)) => bail!(
                "{why}; a run that is not the cell's is never scored under its label: remove {} and run the task again",
                run.display()
            ),
            Err(RunProblem::Incomplete(why)) => not_counted.push(format!("task {i}: {why}")),
        }
    }
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
            .map(|t| Plan::task_dir(&args.dir, t.index).join("run"))
            .collect();
        if runs.is_empty() {
            results.push(None);
            continue;
        }
        let shard_dirs: Vec<RunDir> = runs.iter().map(RunDir::new).collect();
        let shards = thorarena::results::read_shards(&shard_dirs)?;
        let header = shards.header.clone();
        let sequences = &datasets[&cell.dataset];
        let out = RunDir::new(Plan::cell_dir(&args.dir, cell.index));
        let thresholds = thorarena::evaluation::task_thresholds(
            &header.planned_sequences(sequences),
            header.control_dt_s,
        );
        let summary = out.rewrite(&header, &mut shards.into_records(), thresholds)?;
        thorarena::report::write_run_tables(out.path(), &summary)?;
        let out = out.path().to_path_buf();
        let mut faults = [0u64; 3];
        let mut latency_us = None;
        for run in &runs {
            let Some(io) = read_summary(run)?.policy_io else {
                continue;
            };
            faults[0] += io.deadline_misses;
            faults[1] += io.invalid_actions;
            faults[2] += io.transport.map_or(0, |t| t.policy_failures);
            if runs.len() == 1 {
                let l = io.latency;
                latency_us = Some([l.p50_us, l.p99_us, l.p999_us]);
            }
        }
        results.push(Some(CellResult {
            dir: out,
            episodes: summary.episodes,
            complete: summary.episodes == cell.episodes && summary.complete,
            summary,
            faults,
            latency_us,
        }));
    }
    let csv = super::results_csv::results_csv(&plan, &results);
    let csv_path = args.dir.join("results.csv");
    std::fs::write(&csv_path, csv).with_context(|| format!("writing {}", csv_path.display()))?;
    let cell_dirs: Vec<PathBuf> = results.iter().flatten().map(|r| r.dir.clone()).collect();
    let report = args.dir.join("report.html");
    let mut runs = thorarena::report::load_runs(&cell_dirs)?;
    label_cells(&plan, &results, &mut runs);
    let charts = sweep_charts(&plan, &results);
    let script = thorarena::report::WebBundle::locate()?.script(thorarena::report::Page::Report)?;
    let title = sweep_title(&plan);
    let html = thorarena::report::sweep_report_html(&runs, &charts, &title, &script);
    std::fs::write(&report, html).with_context(|| format!("writing {}", report.display()))?;
    let figures_dir = args.dir.join("report-figures");
    let figures =
        thorarena::report::svg_figures(&thorarena::report::report_figures(&runs, &charts));
    crate::cli::report_html::write_figures(&figures_dir, &figures)?;
    eprintln!(
        "collected {} cells{}: {}, {} and {} SVG figures in {}",
        results.iter().flatten().count(),
        if unfinished.is_empty() {
            String::new()
        } else {
            format!(" ({} partial)", unfinished.len())
        },
        csv_path.display(),
        report.display(),
        figures.len(),
        figures_dir.display()
    );
    Ok(())
}

/// The report's title: the sweep's axes that vary, with how many values each takes
/// ("sweep: 2 policies × 4 force coefficients").
pub(super) fn sweep_title(plan: &Plan) -> String {
    use std::collections::BTreeSet;
    let count = |f: &dyn Fn(&thorarena::sweep::Cell) -> String| {
        plan.cells.iter().map(f).collect::<BTreeSet<_>>().len()
    };
    let settings: Vec<Option<thorarena::evaluation::Setting>> = plan
        .cells
        .iter()
        .map(|c| thorarena::evaluation::Setting::parse(&c.setting))
        .collect();
    let setting_noun = if settings
        .iter()
        .all(|s| s.as_ref().is_some_and(|s| s.push_n == 0.0))
    {
        ("force coefficient", "force coefficients")
    } else if settings
        .iter()
        .all(|s| s.as_ref().is_some_and(|s| s.coefficient == 0.0))
    {
        ("push", "pushes")
    } else {
        ("force setting", "force settings")
    };
    let mut axes = Vec::new();
    for (n, (one, many), always) in [
        (
            count(&|c| c.policy.name.clone()),
            ("policy", "policies"),
            true,
        ),
        (
            count(&|c| c.dataset.display().to_string()),
            ("dataset", "datasets"),
            false,
        ),
        (
            count(&|c| c.engine.name.clone()),
            ("engine", "engines"),
            false,
        ),
        (
            count(&|c| c.latency.name.clone()),
            ("latency rule", "latency rules"),
            false,
        ),
        (count(&|c| c.setting.clone()), setting_noun, true),
    ] {
        if n > 1 || always {
            axes.push(format!("{n} {}", if n == 1 { one } else { many }));
        }
    }
    format!("sweep: {}", axes.join(" × "))
}

/// A latency budget in ms, parsed as `--budget` parses it; `None` for `none`.
pub(super) fn budget_ms(budget: &str) -> Option<f64> {
    thorarena::evaluation::parse_budget(budget)
        .ok()
        .and_then(|b| b.0)
        .map(|d| d.as_secs_f64() * 1e3)
}

/// Which of a sweep's axes take more than one value: the ones a label must name.
struct VaryingAxes {
    datasets: bool,
    latency: bool,
    engines: bool,
    settings: bool,
}

impl VaryingAxes {
    fn of(plan: &Plan) -> Self {
        use std::collections::BTreeSet;
        let varies = |f: &dyn Fn(&thorarena::sweep::Cell) -> String| {
            plan.cells.iter().map(f).collect::<BTreeSet<_>>().len() > 1
        };
        Self {
            datasets: varies(&|c| c.dataset.display().to_string()),
            latency: varies(&|c| c.latency.name.clone()),
            engines: varies(&|c| c.engine.name.clone()),
            settings: varies(&|c| c.setting.clone()),
        }
    }

    /// A cell's values of the varying axes other than its policy, `·`-separated (and the
    /// sweep's name of the policy when its runs name it otherwise): a line's dash in the
    /// curves, and with the policy a run's label.
    fn variant(
        &self,
        c: &thorarena::sweep::Cell,
        policy: &str,
        with_latency: bool,
        with_setting: bool,
    ) -> String {
        let mut parts: Vec<String> = Vec::new();
        if c.policy.name != policy {
            parts.push(c.policy.name.clone());
        }
        if self.engines {
            parts.push(c.engine.name.clone());
        }
        if self.datasets {
            parts.push(
                c.dataset
                    .file_name()
                    .map_or(String::new(), |n| n.to_string_lossy().into()),
            );
        }
        if with_latency && self.latency {
            parts.push(c.latency.name.clone());
        }
        if with_setting && self.settings {
            parts.push(c.setting.clone());
        }
        parts.join(" · ")
    }
}

/// Labels the cells' runs by what distinguishes them ("hold · 5ms · force") instead of
/// their directory numbers, so a legend reads without the runs table; cells that differ in
/// nothing a label names keep a number.
fn label_cells(plan: &Plan, results: &[Option<CellResult>], runs: &mut [thorarena::report::Run]) {
    let axes = VaryingAxes::of(plan);
    let cells = plan.cells.iter().zip(results).filter(|(_, r)| r.is_some());
    let mut labels: Vec<String> = cells
        .zip(runs.iter())
        .map(|((c, _), run)| {
            let variant = axes.variant(c, &run.header.policy, true, true);
            if variant.is_empty() {
                run.header.policy.clone()
            } else {
                format!("{} · {variant}", run.header.policy)
            }
        })
        .collect();
    let snapshot = labels.clone();
    for (l, (c, _)) in labels
        .iter_mut()
        .zip(plan.cells.iter().zip(results).filter(|(_, r)| r.is_some()))
    {
        if snapshot.iter().filter(|x| *x == l).count() > 1 {
            *l = format!("{l} ({:06})", c.index);
        }
    }
    for (run, label) in runs.iter_mut().zip(labels) {
        run.label = label;
    }
}

/// The curves a sweep is for, from its cells' averages: FATS and survival against the
/// force coefficient (and against a constant push), one line per policy, and FATS against
/// the latency budget under `--latency-mode measured`. A quantity that takes fewer than
/// two values is not plotted; labels name only the axes that vary.
pub(super) fn sweep_charts(
    plan: &Plan,
    results: &[Option<CellResult>],
) -> Vec<thorarena::report::SweepChart> {
    use std::collections::BTreeSet;
    use thorarena::report::{CurveSeries, SweepChart};
    let axes = VaryingAxes::of(plan);
    let variant =
        |c: &thorarena::sweep::Cell, policy: &str, with_latency: bool, with_setting: bool| {
            axes.variant(c, policy, with_latency, with_setting)
        };
    // (cell, its runs' policy, fats, survival) of every cell with results.
    let points: Vec<(&thorarena::sweep::Cell, &str, f64, f64)> = plan
        .cells
        .iter()
        .zip(results)
        .filter_map(|(c, r)| {
            let r = r.as_ref()?;
            let avg = &r.summary.settings.values().next()?.average;
            (avg.fats.is_finite() && avg.survival.is_finite()).then_some((
                c,
                r.summary.header.policy.as_str(),
                avg.fats,
                avg.survival,
            ))
        })
        .collect();
    // Lines of (label → sorted points) for the cells `x` maps to a value.
    let lines = |x: &dyn Fn(&thorarena::sweep::Cell) -> Option<f64>,
                 y: &dyn Fn(f64, f64) -> f64,
                 with_latency: bool,
                 with_setting: bool| {
        let mut by_line: BTreeMap<(String, String), Vec<[f64; 2]>> = BTreeMap::new();
        let mut xs = BTreeSet::new();
        for &(c, policy, fats, survival) in &points {
            if let Some(xv) = x(c) {
                xs.insert(xv.to_bits());
                by_line
                    .entry((
                        policy.to_string(),
                        variant(c, policy, with_latency, with_setting),
                    ))
                    .or_default()
                    .push([xv, y(fats, survival)]);
            }
        }
        let series: Vec<CurveSeries> = by_line
            .into_iter()
            .map(|((policy, variant), mut points)| {
                points.sort_by(|a, b| a[0].total_cmp(&b[0]));
                let label = if variant.is_empty() {
                    policy.clone()
                } else {
                    format!("{policy} · {variant}")
                };
                CurveSeries {
                    label,
                    policy,
                    variant,
                    points,
                }
            })
            .collect();
        (xs.len() >= 2).then_some(series)
    };
    let setting = |c: &thorarena::sweep::Cell| thorarena::evaluation::Setting::parse(&c.setting);
    let coefficient = |c: &thorarena::sweep::Cell| {
        setting(c)
            .filter(|s| s.push_n == 0.0)
            .map(|s| s.coefficient)
    };
    let push = |c: &thorarena::sweep::Cell| {
        setting(c)
            .filter(|s| s.coefficient == 0.0)
            .map(|s| s.push_n)
    };
    let budget = |c: &thorarena::sweep::Cell| {
        (c.latency.mode == "measured")
            .then(|| budget_ms(&c.latency.budget))
            .flatten()
    };
    let fats = |f: f64, _s: f64| f;
    let survival = |_f: f64, s: f64| s;
    let mut charts = Vec::new();
    let mut chart =
        |id: &str, title: &str, x_label: &str, y_label: &str, series: Option<Vec<CurveSeries>>| {
            if let Some(series) = series {
                charts.push(SweepChart {
                    id: id.into(),
                    title: title.into(),
                    x_label: x_label.into(),
                    y_label: y_label.into(),
                    series,
                });
            }
        };
    chart(
        "sweep-fats-vs-coefficient",
        "FATS against the force replay coefficient (0 = no force, 1 = the recorded forces)",
        "force replay coefficient",
        "FATS",
        lines(&coefficient, &fats, true, false),
    );
    chart(
        "sweep-survival-vs-coefficient",
        "Survival against the force replay coefficient",
        "force replay coefficient",
        "survival",
        lines(&coefficient, &survival, true, false),
    );
    if points
        .iter()
        .any(|(c, _, _, _)| push(c).is_some_and(|p| p > 0.0))
    {
        chart(
            "sweep-fats-vs-push",
            "FATS against a constant push on each hand",
            "push per hand (N)",
            "FATS",
            lines(&push, &fats, true, false),
        );
        chart(
            "sweep-survival-vs-push",
            "Survival against a constant push on each hand",
            "push per hand (N)",
            "survival",
            lines(&push, &survival, true, false),
        );
    }
    chart(
        "sweep-fats-vs-budget",
        "FATS against the latency budget (latency mode measured: the policy's latency delays its action)",
        "latency budget (ms)",
        "FATS",
        lines(&budget, &fats, false, true),
    );
    charts
}
