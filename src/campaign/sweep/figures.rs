//! A sweep's report: its title from the axes that vary, each cell's run labelled by what
//! tells it apart, and the curves a sweep is for (FATS and survival against the force
//! coefficient or a push, FATS against the latency budget), from the cells' scores.

use super::{Cell, CellResult, Plan};
use crate::report::{CurveSeries, Run, SweepChart};
use std::collections::{BTreeMap, BTreeSet};

/// The report's title: the sweep's axes that vary, with how many values each takes
/// ("sweep: 2 policies × 4 force coefficients").
pub fn sweep_title(plan: &Plan) -> String {
    let count =
        |f: &dyn Fn(&Cell) -> String| plan.cells.iter().map(f).collect::<BTreeSet<_>>().len();
    let setting_noun = if plan.cells.iter().all(|c| c.setting.replay_only().is_some()) {
        ("force coefficient", "force coefficients")
    } else if plan.cells.iter().all(|c| c.setting.push_only().is_some()) {
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
        (count(&|c| c.setting.spelling()), setting_noun, true),
    ] {
        if n > 1 || always {
            axes.push(format!("{n} {}", if n == 1 { one } else { many }));
        }
    }
    format!("sweep: {}", axes.join(" × "))
}

/// A latency budget in ms, parsed as `--budget` parses it; `None` for `none`.
pub fn budget_ms(budget: &str) -> Option<f64> {
    crate::eval::parse_budget(budget)
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
        let varies = |f: &dyn Fn(&Cell) -> String| {
            plan.cells.iter().map(f).collect::<BTreeSet<_>>().len() > 1
        };
        Self {
            datasets: varies(&|c| c.dataset.display().to_string()),
            latency: varies(&|c| c.latency.name.clone()),
            engines: varies(&|c| c.engine.name.clone()),
            settings: varies(&|c| c.setting.spelling()),
        }
    }

    /// A cell's values of the varying axes other than its policy, `·`-separated (and the
    /// sweep's name of the policy when its runs name it otherwise): a line's dash in the
    /// curves, and with the policy a run's label.
    fn variant(&self, c: &Cell, policy: &str, with_latency: bool, with_setting: bool) -> String {
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
            parts.push(c.setting.spelling());
        }
        parts.join(" · ")
    }
}

/// Labels the cells' runs by what distinguishes them ("hold · 5ms · force") instead of
/// their directory numbers, so a legend reads without the runs table; cells that differ in
/// nothing a label names keep a number.
pub fn label_cells(plan: &Plan, results: &[Option<CellResult>], runs: &mut [Run]) {
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
pub fn sweep_charts(plan: &Plan, results: &[Option<CellResult>]) -> Vec<crate::report::SweepChart> {
    let axes = VaryingAxes::of(plan);
    let points = cell_points(plan, results);
    let lines = |x: &dyn Fn(&Cell) -> Option<f64>,
                 y: &dyn Fn(&CellPoint) -> f64,
                 with_latency: bool,
                 with_setting: bool| {
        curve_lines(&points, &axes, x, y, with_latency, with_setting)
    };
    let fats = |p: &CellPoint| p.fats;
    let survival = |p: &CellPoint| p.survival;
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
        lines(&coefficient_of, &fats, true, false),
    );
    chart(
        "sweep-survival-vs-coefficient",
        "Survival against the force replay coefficient",
        "force replay coefficient",
        "survival",
        lines(&coefficient_of, &survival, true, false),
    );
    if points
        .iter()
        .any(|p| push_of(p.cell).is_some_and(|n| n > 0.0))
    {
        chart(
            "sweep-fats-vs-push",
            "FATS against a constant push on each hand",
            "push per hand (N)",
            "FATS",
            lines(&push_of, &fats, true, false),
        );
        chart(
            "sweep-survival-vs-push",
            "Survival against a constant push on each hand",
            "push per hand (N)",
            "survival",
            lines(&push_of, &survival, true, false),
        );
    }
    chart(
        "sweep-fats-vs-budget",
        "FATS against the latency budget (latency mode measured: the policy's latency delays its action)",
        "latency budget (ms)",
        "FATS",
        lines(&budget_of, &fats, false, true),
    );
    charts
}

/// A cell with results, as the curves plot it.
struct CellPoint<'a> {
    cell: &'a Cell,
    /// The policy its run names.
    policy: &'a str,
    fats: f64,
    survival: f64,
}

/// Every cell with finite results.
fn cell_points<'a>(plan: &'a Plan, results: &'a [Option<CellResult>]) -> Vec<CellPoint<'a>> {
    plan.cells
        .iter()
        .zip(results)
        .filter_map(|(cell, r)| {
            let r = r.as_ref()?;
            let avg = &r.summary.settings.values().next()?.average;
            (avg.fats.is_finite() && avg.survival.is_finite()).then_some(CellPoint {
                cell,
                policy: r.summary.header.policy.as_str(),
                fats: avg.fats,
                survival: avg.survival,
            })
        })
        .collect()
}

/// One curve per (policy, variant of the other varying axes), its points sorted by the
/// value `x` maps a cell to (cells it maps to nothing are left out); `None` when fewer
/// than two x values are there to draw a curve through.
fn curve_lines(
    points: &[CellPoint],
    axes: &VaryingAxes,
    x: &dyn Fn(&Cell) -> Option<f64>,
    y: &dyn Fn(&CellPoint) -> f64,
    with_latency: bool,
    with_setting: bool,
) -> Option<Vec<CurveSeries>> {
    let mut by_line: BTreeMap<(String, String), Vec<[f64; 2]>> = BTreeMap::new();
    let mut xs = BTreeSet::new();
    for p in points {
        if let Some(xv) = x(p.cell) {
            xs.insert(xv.to_bits());
            by_line
                .entry((
                    p.policy.to_string(),
                    axes.variant(p.cell, p.policy, with_latency, with_setting),
                ))
                .or_default()
                .push([xv, y(p)]);
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
}

/// A force-replay cell's coefficient (not a push).
fn coefficient_of(c: &Cell) -> Option<f64> {
    c.setting.replay_only()
}

/// A push cell's force per hand, N.
fn push_of(c: &Cell) -> Option<f64> {
    c.setting.push_only()
}

/// A measured-latency cell's budget, ms.
fn budget_of(c: &Cell) -> Option<f64> {
    (c.latency.mode == "measured")
        .then(|| budget_ms(&c.latency.budget))
        .flatten()
}
