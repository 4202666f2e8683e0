//! The paper's two tables — task-level FATS and the diagnostics averaged over tasks — for
//! one run in Markdown (`tables.md`), and for several runs side by side as a
//! [`NumberTable`] that renders to Markdown, CSV and HTML from the same numbers, so a
//! paper's CSV can never disagree with the report it came with.

use super::runs::Run;
use crate::eval::metrics::Diagnostics;
use crate::eval::results::SettingResults;
use std::fmt::Write;

/// One row of the diagnostics table: how to read it from [`Diagnostics`] and print it.
#[derive(Debug, Clone, Copy)]
pub struct DiagnosticRow {
    /// Row name as the paper prints it.
    pub name: &'static str,
    /// The value.
    pub value: fn(&Diagnostics) -> f64,
    /// Decimals printed.
    pub decimals: usize,
    /// Printed after the number (`×` for the power overhead).
    pub suffix: &'static str,
}

/// The diagnostics table's rows, in the paper's order (one definition for every table),
/// then the keypoint error without re-anchoring, which the paper does not report.
pub const DIAGNOSTIC_ROWS: [DiagnosticRow; 11] = [
    row("FATS (mean)", |d| d.fats, 2, ""),
    row("Survival (mean)", |d| d.survival, 3, ""),
    row("KP error, RMS (mm)", |d| d.kp_mm, 1, ""),
    row("Low KP, RMS (mm)", |d| d.low_kp_mm, 1, ""),
    row("High KP, RMS (mm)", |d| d.high_kp_mm, 1, ""),
    row("Robustness ρ", |d| d.robustness, 3, ""),
    row("Power η", |d| d.power_overhead, 2, "×"),
    row("Upper KP, RMS (mm)", |d| d.upper_kp_mm, 1, ""),
    row("Lower KP, RMS (mm)", |d| d.lower_kp_mm, 1, ""),
    row("FATS Std", |d| d.fats_std, 2, ""),
    row("Global KP, RMS (mm)", |d| d.global_kp_mm, 1, ""),
];

const fn row(
    name: &'static str,
    value: fn(&Diagnostics) -> f64,
    decimals: usize,
    suffix: &'static str,
) -> DiagnosticRow {
    DiagnosticRow {
        name,
        value,
        decimals,
        suffix,
    }
}

/// A number as the tables print it; undefined values (NaN: no high-force step anywhere,
/// say) print as a dash rather than as `NaN`.
fn format_number(v: f64, decimals: usize, suffix: &str) -> String {
    if v.is_nan() {
        "–".into()
    } else {
        format!("{v:.decimals$}{suffix}")
    }
}

/// What the diagnostics table's numbers are, printed under it (and in README).
pub const DIAGNOSTICS_NOTE: &str = "Each number is computed per task, then averaged over tasks. Per task: FATS and survival are means over its episodes; KP rows are the RMS of the keypoint error over its control steps (all its episodes pooled; low/high: steps of that force regime), with the reference re-anchored at the robot's root, except Global KP, which keeps the reference where it is in the world (drift included; – for a run recorded before it was); ρ = low / high KP RMS; η = mean power in high-force steps over low-force steps; FATS Std is the population standard deviation of its episode scores (– where every task has one episode); – marks a number that is undefined.";

/// Task-level FATS (mean episode score per task), one column per setting; under the
/// average, its bootstrap 95 % interval where `intervals` has the setting. A cell
/// `outside` names (setting, task) is marked †: its load lies outside the policy's
/// training ([`outside_training_note`] says what).
pub fn task_fats_table(
    results: &SettingResults,
    intervals: &std::collections::BTreeMap<String, [f64; 2]>,
    outside: &crate::eval::OutsideTraining,
) -> String {
    let settings: Vec<&String> = results.keys().collect();
    let mut tasks: Vec<&str> = results
        .values()
        .flat_map(|(t, _)| t.iter().map(|s| s.task.as_str()))
        .collect();
    tasks.sort();
    tasks.dedup();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "| Task | {} |",
        settings
            .iter()
            .map(|x| format!("FATS ({x}), mean of episodes"))
            .collect::<Vec<_>>()
            .join(" | ")
    );
    let _ = writeln!(s, "|---|{}", "---:|".repeat(settings.len()));
    for task in &tasks {
        let cells: Vec<String> = settings
            .iter()
            .map(|k| {
                results[*k]
                    .0
                    .iter()
                    .find(|t| t.task == *task)
                    .map_or("–".into(), |t| {
                        let mark = outside
                            .get(*k)
                            .is_some_and(|cells| cells.contains_key(*task));
                        format!("{:.2}{}", t.diagnostics.fats, if mark { " †" } else { "" })
                    })
            })
            .collect();
        let _ = writeln!(s, "| {task} | {} |", cells.join(" | "));
    }
    let avg: Vec<String> = settings
        .iter()
        .map(|k| format!("**{:.2}**", results[*k].1.fats))
        .collect();
    let _ = writeln!(s, "| **average** | {} |", avg.join(" | "));
    if !intervals.is_empty() {
        let ci: Vec<String> = settings
            .iter()
            .map(|k| {
                intervals
                    .get(*k)
                    .map_or("–".into(), |[lo, hi]| format!("[{lo:.2}, {hi:.2}]"))
            })
            .collect();
        let _ = writeln!(
            s,
            "| 95 % interval (bootstrap over episodes within tasks) | {} |",
            ci.join(" | ")
        );
    }
    s
}

/// What the family a run's policy is named by was trained with (empty for a name no
/// family has): the last line of [`outside_training_note`].
pub(super) fn family_training(policy: &str) -> String {
    crate::policy::registry::POLICY_FAMILIES
        .iter()
        .find(|f| f.name == policy)
        .map_or(String::new(), |f| f.trained_forces.describe())
}

/// The note under a table with † cells: per setting, the tasks outside the policy's
/// training and what lies outside; empty when none is.
pub fn outside_training_note(outside: &crate::eval::OutsideTraining, trained: &str) -> String {
    if outside.is_empty() {
        return String::new();
    }
    let mut s = String::from(
        "\n† The load of these cells lies outside what the policy's family was trained with: the score is of the network off its distribution.\n",
    );
    for (setting, cells) in outside {
        let mut by_reason: std::collections::BTreeMap<&str, Vec<&str>> = Default::default();
        for (task, why) in cells {
            by_reason
                .entry(why.as_str())
                .or_default()
                .push(task.as_str());
        }
        for (why, tasks) in by_reason {
            let _ = writeln!(s, "- `{setting}`, {}: {why}", tasks.join(", "));
        }
    }
    if !trained.is_empty() {
        let _ = writeln!(s, "\nIts training: {trained}.");
    }
    s
}

/// The diagnostics averaged over tasks, one column per setting.
pub fn diagnostics_table(results: &SettingResults) -> String {
    let settings: Vec<&String> = results.keys().collect();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "| Metric | {} |",
        settings
            .iter()
            .map(|x| x.as_str())
            .collect::<Vec<_>>()
            .join(" | ")
    );
    let _ = writeln!(s, "|---|{}", "---:|".repeat(settings.len()));
    for r in DIAGNOSTIC_ROWS {
        let cells: Vec<String> = settings
            .iter()
            .map(|k| format_number((r.value)(&results[*k].1), r.decimals, r.suffix))
            .collect();
        let _ = writeln!(s, "| {} | {} |", r.name, cells.join(" | "));
    }
    let _ = writeln!(s, "\n{DIAGNOSTICS_NOTE}");
    s
}

/// One row of a [`NumberTable`].
#[derive(Debug, Clone, PartialEq)]
pub struct NumberRow {
    /// First cell (task or metric).
    pub name: String,
    /// One value per column; `None` where the run has no such task or setting.
    pub values: Vec<Option<f64>>,
    /// Decimals printed in Markdown and HTML (CSV keeps full precision).
    pub decimals: usize,
    /// Printed after each number in Markdown and HTML.
    pub suffix: &'static str,
    /// Printed in bold (the average row).
    pub bold: bool,
    /// Per column, whether the cell's load lies outside what its policy's family was
    /// trained with: † after the number in Markdown and HTML (empty: none is).
    pub outside_training: Vec<bool>,
}

/// A table of numbers with one column per (run, setting): the multi-run form of the
/// paper's tables.
#[derive(Debug, Clone, PartialEq)]
pub struct NumberTable {
    /// Header of the first column (`Task`, `Metric`).
    pub corner: String,
    /// Column headers, `<run label> (<setting>)`.
    pub columns: Vec<String>,
    /// Rows.
    pub rows: Vec<NumberRow>,
}

/// The (run, setting) pairs that become columns, runs in the order given, settings in
/// each run's schedule order.
pub fn columns(runs: &[Run]) -> Vec<(usize, String)> {
    runs.iter()
        .enumerate()
        .flat_map(|(i, r)| r.settings().into_iter().map(move |s| (i, s)))
        .collect()
}

fn column_names(runs: &[Run], prefix: &str) -> Vec<String> {
    columns(runs)
        .iter()
        .map(|(i, s)| format!("{}{} ({s})", prefix, runs[*i].label))
        .collect()
}

/// Task-level FATS of several runs side by side (rows: the union of their tasks, then the
/// average over tasks).
pub fn fats_table(runs: &[Run]) -> NumberTable {
    let cols = columns(runs);
    let mut rows: Vec<NumberRow> = all_tasks(runs)
        .into_iter()
        .map(|task| NumberRow {
            values: cols
                .iter()
                .map(|(i, s)| {
                    runs[*i]
                        .task(s, &task)
                        .map(|t| t.diagnostics.fats)
                        .filter(|v| !v.is_nan())
                })
                .collect(),
            outside_training: cols
                .iter()
                .map(|(i, s)| {
                    runs[*i]
                        .header
                        .outside_training
                        .get(s)
                        .is_some_and(|tasks| tasks.contains_key(&task))
                })
                .collect(),
            name: task,
            decimals: 2,
            suffix: "",
            bold: false,
        })
        .collect();
    rows.push(NumberRow {
        name: "average".into(),
        values: cols
            .iter()
            .map(|(i, s)| runs[*i].average(s).map(|d| d.fats))
            .collect(),
        decimals: 2,
        suffix: "",
        bold: true,
        outside_training: Vec::new(),
    });
    NumberTable {
        corner: "Task".into(),
        columns: column_names(runs, "FATS: "),
        rows,
    }
}

/// The diagnostics of several runs side by side, averaged over each run's tasks.
pub fn diagnostics_multi_table(runs: &[Run]) -> NumberTable {
    let cols = columns(runs);
    NumberTable {
        corner: "Metric".into(),
        columns: column_names(runs, ""),
        rows: DIAGNOSTIC_ROWS
            .iter()
            .map(|r| NumberRow {
                name: r.name.into(),
                values: cols
                    .iter()
                    .map(|(i, s)| runs[*i].average(s).map(|d| (r.value)(d)))
                    .map(|v| v.filter(|v| !v.is_nan()))
                    .collect(),
                decimals: r.decimals,
                suffix: r.suffix,
                bold: false,
                outside_training: Vec::new(),
            })
            .collect(),
    }
}

/// Every task of any run, sorted.
pub fn all_tasks(runs: &[Run]) -> Vec<String> {
    let mut tasks: Vec<String> = runs
        .iter()
        .flat_map(|r| r.results.values())
        .flat_map(|(t, _)| t.iter().map(|s| s.task.clone()))
        .collect();
    tasks.sort();
    tasks.dedup();
    tasks
}

impl NumberRow {
    /// Column `c`'s value as printed, † when it lies outside the policy's training.
    fn cell(&self, c: usize) -> String {
        let mark = if self.outside_training.get(c).copied().unwrap_or(false) {
            " †"
        } else {
            ""
        };
        self.values[c].map_or("–".into(), |v| {
            format!("{}{mark}", format_number(v, self.decimals, self.suffix))
        })
    }
}

impl NumberTable {
    /// GitHub Markdown, numbers rounded as in `tables.md`.
    pub fn markdown(&self) -> String {
        let mut s = format!("| {} | {} |\n", self.corner, self.columns.join(" | "));
        let _ = writeln!(s, "|---|{}", "---:|".repeat(self.columns.len()));
        for r in &self.rows {
            let bold = |c: String| if r.bold { format!("**{c}**") } else { c };
            let cells: Vec<String> = (0..r.values.len()).map(|c| bold(r.cell(c))).collect();
            let _ = writeln!(s, "| {} | {} |", bold(r.name.clone()), cells.join(" | "));
        }
        s
    }

    /// CSV with full precision (shortest round-trip form of each f64); empty cells where a
    /// value is missing or undefined.
    pub fn csv(&self) -> String {
        let mut w = csv::Writer::from_writer(Vec::new());
        let header =
            std::iter::once(self.corner.as_str()).chain(self.columns.iter().map(|c| c.as_str()));
        w.write_record(header).expect("writing to memory");
        for r in &self.rows {
            let name = crate::files::names::csv_text::cell(&r.name).into_owned();
            let cells = std::iter::once(name).chain(
                r.values
                    .iter()
                    .map(|v| v.map_or(String::new(), |v| v.to_string())),
            );
            w.write_record(cells).expect("writing to memory");
        }
        String::from_utf8(w.into_inner().expect("flushing to memory")).expect("CSV of UTF-8 text")
    }

    /// An HTML `<table>` with the given id, numbers rounded as in Markdown.
    pub fn html(&self, id: &str) -> String {
        use super::html::escape;
        let mut s = format!(
            "<table id=\"{}\" class=\"numbers\"><thead><tr><th>{}</th>",
            escape(id),
            escape(&self.corner)
        );
        for c in &self.columns {
            let _ = write!(s, "<th>{}</th>", escape(c));
        }
        s += "</tr></thead><tbody>";
        for r in &self.rows {
            let class = if r.bold { " class=\"total\"" } else { "" };
            let _ = write!(s, "<tr{class}><th>{}</th>", escape(&r.name));
            for c in 0..r.values.len() {
                let _ = write!(s, "<td>{}</td>", escape(&r.cell(c)));
            }
            s += "</tr>";
        }
        s + "</tbody></table>"
    }
}

/// Each setting's FATS interval of a run, `n/a` where every task has one episode.
fn run_intervals(r: &Run) -> String {
    let intervals = crate::eval::results::fats_intervals(&crate::eval::results::episode_rows(
        &r.records,
        &r.thresholds,
    ));
    r.settings()
        .iter()
        .map(|s| match intervals.get(s) {
            Some([lo, hi]) => format!("{s} [{lo:.2}, {hi:.2}]"),
            None => format!("{s} n/a (one episode per task)"),
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// The Markdown report of several runs (`thorarena report`'s `.md`): each run with what
/// it measured, the notes and the comparability warnings, then the paper's two tables.
pub fn comparison_markdown(
    runs: &[Run],
    warnings: &[super::ComparisonWarning],
    notes: &[String],
) -> String {
    let mut md = String::from("# ThorArena report\n\n");
    for r in runs {
        md += &format!(
            "- **{}**: `{}` — policy {}, profile `{}`, engine {}, dataset {} (sha256 {}), keypoints `{}`; {} episodes; FATS 95 % interval (bootstrap over episodes within tasks): {}\n",
            r.label,
            r.dir.display(),
            r.header.policy_text(),
            r.header.profile,
            r.header.engine_label(),
            r.header.dataset,
            &r.header.dataset_sha256[..r.header.dataset_sha256.len().min(16)],
            r.header.keypoints,
            r.records.len(),
            run_intervals(r)
        );
    }
    for n in notes {
        md += &format!("\nNote: {n}\n");
    }
    if !warnings.is_empty() {
        md += "\n> **Warning: these runs are not comparable as they stand.**\n";
        for w in warnings {
            md += &format!(">\n> - {}\n", w.message);
        }
    }
    let outside: String = runs
        .iter()
        .filter(|r| !r.header.outside_training.is_empty())
        .map(|r| {
            format!(
                "\n{}:{}",
                r.label,
                outside_training_note(
                    &r.header.outside_training,
                    &family_training(&r.header.policy)
                )
            )
        })
        .collect();
    md += &format!(
        "\n## Task-level FATS\n\n{}{outside}\n## Diagnostics (averaged over tasks)\n\n{}",
        fats_table(runs).markdown(),
        diagnostics_multi_table(runs).markdown()
    );
    md
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cell_outside_training_is_marked_in_markdown_and_html_and_not_in_csv() {
        let table = NumberTable {
            corner: "Task".into(),
            columns: vec!["FATS: a (force)".into(), "FATS: a (no-force)".into()],
            rows: vec![NumberRow {
                name: "push_chair".into(),
                values: vec![Some(70.0), Some(80.0)],
                decimals: 2,
                suffix: "",
                bold: false,
                outside_training: vec![true, false],
            }],
        };
        assert!(table
            .markdown()
            .contains("| push_chair | 70.00 † | 80.00 |"));
        assert!(table.html("t").contains("<td>70.00 †</td><td>80.00</td>"));
        assert!(table.csv().contains("push_chair,70,80"));
    }
}
