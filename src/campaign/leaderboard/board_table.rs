//! The general board as Markdown: one row per (policy, engine) with FATS, survival and
//! keypoint error under force and without, the cells outside a family's training marked
//! †, and `leaderboard.md`, the page around the tables.

use super::{Entry, TaskForceSpans};
use std::path::{Path, PathBuf};

/// The tasks of `entry`'s setting `setting` whose load lies outside what its family was
/// trained with (`eval::setting_outside`, the judgement every run's `tables.md` makes);
/// empty when the family has nothing to judge or the setting replays no force.
/// Each with what lies outside (`push_chair (61 N horizontal walking, above 40)`); a
/// disturbance or a push is judged once for every task (`every task (…)`).
pub fn tasks_outside_training(entry: &Entry, setting: &str, spans: &TaskForceSpans) -> Vec<String> {
    let header = &entry.summary.header;
    let Some(found) = header.settings.iter().find(|s| s.name == setting) else {
        return Vec::new();
    };
    let stiffness = header.policy_parameters.get("stiffness_n_per_m").copied();
    match crate::eval::setting_outside(&entry.trained_forces, found, stiffness, spans) {
        crate::eval::SettingOutside::Inside => Vec::new(),
        crate::eval::SettingOutside::EveryTask(why) => vec![format!("every task ({why})")],
        crate::eval::SettingOutside::Tasks(tasks) => tasks
            .into_iter()
            .map(|(task, why)| format!("{task} ({why})"))
            .collect(),
    }
}

/// The leaderboard as one Markdown table: per (policy, engine), FATS with its 95 %
/// interval, survival and keypoint error under each setting of the runs (the first
/// entry's, in its order), and the wall time. Give it the general entries, or the
/// own-clip ones. A FATS cell some of whose tasks replay forces outside the policy's
/// training (`spans`) is marked †, and a note under the table names those tasks.
pub fn leaderboard_table(entries: &[&Entry], spans: &TaskForceSpans) -> String {
    let settings: Vec<String> = entries
        .first()
        .map(|e| {
            e.summary
                .header
                .settings
                .iter()
                .map(|s| s.name.clone())
                .collect()
        })
        .unwrap_or_default();
    let mut out = String::from("| policy | engine |");
    let mut rule = String::from("|---|---|");
    for s in &settings {
        out.push_str(&format!(
            " FATS {s} (95 % CI) | survival {s} | keypoint error {s} (mm) | global keypoint error {s} (mm) |"
        ));
        rule.push_str("---:|---:|---:|---:|");
    }
    out.push_str(" wall time |\n");
    rule.push_str("---:|\n");
    out.push_str(&rule);
    let mut notes: Vec<String> = Vec::new();
    for e in entries {
        out.push_str(&format!("| {} | {} |", markdown_cell(&e.policy), e.engine));
        for s in &settings {
            match e.summary.settings.get(s.as_str()) {
                Some(r) => {
                    let ci = r
                        .fats_ci95
                        .map_or(" (n/a: one episode per task)".to_string(), |[lo, hi]| {
                            format!(" ({lo:.1}–{hi:.1})")
                        });
                    let outside = tasks_outside_training(e, s, spans);
                    let mark = if outside.is_empty() {
                        ""
                    } else {
                        let which = if e
                            .summary
                            .header
                            .settings
                            .iter()
                            .any(|h| h.name == *s && h.disturbance.is_some())
                        {
                            "its disturbance lies outside what it was trained with on".to_string()
                        } else {
                            format!(
                                "{} of {} tasks replay forces outside what it was trained with:",
                                outside.len(),
                                r.tasks.len()
                            )
                        };
                        let note = format!(
                            "{} under `{s}`: {which} {}. Its training: {}",
                            markdown_cell(&e.policy),
                            outside.join(", "),
                            e.trained_forces.describe()
                        );
                        if !notes.contains(&note) {
                            notes.push(note);
                        }
                        " †"
                    };
                    let global = if r.average.global_kp_mm.is_finite() {
                        format!("{:.1}", r.average.global_kp_mm)
                    } else {
                        "–".into()
                    };
                    out.push_str(&format!(
                        " {:.1}{ci}{mark} | {:.3} | {:.1} | {global} |",
                        r.average.fats, r.average.survival, r.average.kp_mm
                    ));
                }
                None => out.push_str(" – | – | – | – |"),
            }
        }
        out.push_str(&format!(" {} |\n", minutes(e.wall_s)));
    }
    for note in notes {
        out.push_str(&format!("\n† {note}.\n"));
    }
    out
}

/// Writes `out/leaderboard.md`: what was run (dataset and settings of the general board —
/// none for a board of single-clip policies or pairs only, each of whose tables says its
/// own —, where the runs are, the command and its wall time) and the tables; returns its
/// path.
pub fn write_leaderboard_page(
    out: &Path,
    dataset: &Path,
    settings: &[crate::eval::Setting],
    command: &str,
    wall_s: f64,
    tables: &str,
) -> std::io::Result<PathBuf> {
    let path = out.join("leaderboard.md");
    let general = if dataset.as_os_str().is_empty() {
        String::new()
    } else {
        format!(
            "Dataset `{}`, settings {}; ",
            dataset.display(),
            settings
                .iter()
                .map(crate::eval::Setting::spelling)
                .collect::<Vec<_>>()
                .join(", ")
        )
    };
    let text = format!(
        "# Leaderboard\n\n{general}one `eval` run per row in `{}`. Command: `thorarena {command}`. Wall time of this invocation: {wall_s:.0} s.\n\n{tables}",
        out.join("runs").display(),
    );
    crate::files::atomic_file::write(&path, text)?;
    Ok(path)
}

/// Text that stays one cell of a Markdown table and shows as text: `|` escaped, HTML's
/// special characters as entities (a file stem may hold either).
pub(crate) fn markdown_cell(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '|' => out.push_str("\\|"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '&' => out.push_str("&amp;"),
            c if c.is_control() => out.push(' '),
            c => out.push(c),
        }
    }
    out
}

pub(crate) fn minutes(s: f64) -> String {
    if s < 60.0 {
        format!("{s:.0} s")
    } else {
        format!("{} min {:02.0} s", (s / 60.0).floor(), s % 60.0)
    }
}
