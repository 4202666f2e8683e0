//! Tables of results: the paper's task-level FATS table and its diagnostics table, in
//! Markdown.

use crate::runner::SettingResults;
use std::fmt::Write;

/// Task-level FATS, one column per setting.
pub fn task_fats_table(results: &SettingResults) -> String {
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
            .map(|x| format!("FATS ({x})"))
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
                    .map_or("–".into(), |t| format!("{:.2}", t.diagnostics.fats))
            })
            .collect();
        let _ = writeln!(s, "| {task} | {} |", cells.join(" | "));
    }
    let avg: Vec<String> = settings
        .iter()
        .map(|k| format!("**{:.2}**", results[*k].1.fats))
        .collect();
    let _ = writeln!(s, "| **average** | {} |", avg.join(" | "));
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
    type Row = (&'static str, fn(&crate::metrics::Diagnostics) -> String);
    let rows: [Row; 10] = [
        ("FATS", |d| format!("{:.2}", d.fats)),
        ("Survival", |d| format!("{:.3}", d.survival)),
        ("KP error (mm)", |d| format!("{:.1}", d.kp_mm)),
        ("Low KP (mm)", |d| format!("{:.1}", d.low_kp_mm)),
        ("High KP (mm)", |d| format!("{:.1}", d.high_kp_mm)),
        ("Robustness ρ", |d| format!("{:.3}", d.robustness)),
        ("Power η", |d| format!("{:.2}×", d.power_overhead)),
        ("Upper KP (mm)", |d| format!("{:.1}", d.upper_kp_mm)),
        ("Lower KP (mm)", |d| format!("{:.1}", d.lower_kp_mm)),
        ("FATS Std", |d| format!("{:.2}", d.fats_std)),
    ];
    for (name, f) in rows {
        // Undefined diagnostics (no high-force step anywhere, say) print as a dash.
        let cells: Vec<String> = settings
            .iter()
            .map(|k| f(&results[*k].1))
            .map(|c| if c.contains("NaN") { "–".into() } else { c })
            .collect();
        let _ = writeln!(s, "| {name} | {} |", cells.join(" | "));
    }
    s
}
