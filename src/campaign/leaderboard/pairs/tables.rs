//! The pairs for people: per pair and engine, each member's cells (a push or event column
//! averaging its directions) and the paired differences with their stratified intervals,
//! as Markdown (`pairs.md`) and every cell as CSV (`pairs.csv`).

use super::{event_setting, PairMember, PairResult, PAIR_EVENT};
use crate::eval::metrics::{stratified_mean_ci, MeanCi, BOOTSTRAP_RESAMPLES};
use crate::eval::results::Summary;
use crate::policy::registry::TrainedForces;
use std::path::{Path, PathBuf};

/// (FATS, survival, keypoint error mm) of one setting of a run.
fn cell(summary: &Summary, setting: &str) -> Option<[f64; 3]> {
    // Results name a setting canonically (`push:10@90` → `push-10@90`).
    let key = crate::eval::Setting::parse(setting).map_or_else(|_| setting.to_string(), |s| s.name);
    let r = summary.settings.get(&key)?;
    Some([r.average.fats, r.average.survival, r.average.kp_mm])
}

/// A magnitude's four directions (or every push), averaged per quantity.
fn mean_over(summary: &Summary, settings: &[String]) -> Option<[f64; 3]> {
    let cells: Vec<[f64; 3]> = settings
        .iter()
        .map(|s| cell(summary, s))
        .collect::<Option<_>>()?;
    let n = cells.len() as f64;
    Some(std::array::from_fn(|k| {
        cells.iter().map(|c| c[k]).sum::<f64>() / n
    }))
}

impl PairResult {
    /// The push settings of magnitude `n`, one per direction.
    fn settings_of(&self, n: f64) -> Vec<String> {
        self.push_headings_deg
            .iter()
            .map(|h| format!("push:{n}@{h}"))
            .collect()
    }

    /// Every push setting, grouped by magnitude (the strata of the "all pushes" column).
    fn all_pushes(&self) -> Vec<Vec<String>> {
        self.push_n.iter().map(|n| self.settings_of(*n)).collect()
    }

    /// The event settings of magnitude `n`, one per direction.
    fn events_of(&self, n: f64) -> Vec<String> {
        self.push_headings_deg
            .iter()
            .map(|h| event_setting(n, *h))
            .collect()
    }

    /// Every event setting, grouped by magnitude.
    fn all_events(&self) -> Vec<Vec<String>> {
        self.event_n.iter().map(|n| self.events_of(*n)).collect()
    }

    /// The baseline and the compliant member on `engine`.
    fn pair_on(&self, engine: &str) -> Option<(&PairMember, &PairMember)> {
        let find = |role| {
            self.members
                .iter()
                .find(|m| m.engine == engine && m.role == role)
        };
        Some((find("baseline")?, find("compliant")?))
    }

    /// The paired differences (compliant − baseline) of (FATS, survival, keypoint error)
    /// over `strata` of settings: the mean over strata of each stratum's mean, with a
    /// bootstrap interval that resamples settings within each stratum. One stratum of one
    /// magnitude's directions says how much the difference depends on the push's direction;
    /// the magnitudes as strata keep every resample's mix of magnitudes (resampling sixteen
    /// pushes freely would let a resample hold only the 50 N ones).
    fn differences(&self, engine: &str, strata: &[Vec<String>]) -> Option<[MeanCi; 3]> {
        let (base, soft) = self.pair_on(engine)?;
        let mut d: [Vec<Vec<f64>>; 3] = Default::default();
        for settings in strata {
            let mut within: [Vec<f64>; 3] = Default::default();
            for s in settings {
                let (b, c) = if s == "force" {
                    (cell(&base.force_log, s)?, cell(&soft.force_log, s)?)
                } else {
                    (cell(&base.pushes, s)?, cell(&soft.pushes, s)?)
                };
                for k in 0..3 {
                    within[k].push(c[k] - b[k]);
                }
            }
            for k in 0..3 {
                d[k].push(std::mem::take(&mut within[k]));
            }
        }
        Some(d.map(|groups| stratified_mean_ci(&groups, BOOTSTRAP_RESAMPLES, 0)))
    }
}

/// `FATS · survival · error` of a cell.
fn cell_text(c: Option<[f64; 3]>) -> String {
    c.map_or_else(
        || "–".into(),
        |[f, s, e]| format!("{f:.1} · {s:.2} · {e:.1}"),
    )
}

/// A difference with its interval, or the single value when it has none.
fn difference_text(d: &MeanCi, digits: usize) -> String {
    if d.episodes > 1 {
        format!(
            "{:+.*} ({:+.*} to {:+.*})",
            digits, d.mean, digits, d.ci95[0], digits, d.ci95[1]
        )
    } else {
        format!("{:+.*}", digits, d.mean)
    }
}

/// The members' cells of pair `r` on `engine`, with the note naming what lies outside
/// a member family's training.
fn members_table(r: &PairResult, engine: &str) -> String {
    let mut out = String::new();
    out.push_str("| member | stiffness (N/m) | no force |");
    let mut rule = String::from("|---|---:|---:|");
    for n in &r.push_n {
        out.push_str(&format!(" {n} N |"));
        rule.push_str("---:|");
    }
    for n in &r.event_n {
        out.push_str(&format!(" event {n} N |"));
        rule.push_str("---:|");
    }
    out.push_str(" force log | wall time |\n");
    rule.push_str("---:|---:|\n");
    out.push_str(&rule);
    let mut outside_of: Vec<String> = Vec::new();
    for m in r.members.iter().filter(|m| m.engine == engine) {
        let trained = m.policy.family().trained_forces;
        let mut mark = |inside: Option<bool>| {
            if inside == Some(false) {
                let note = format!("`{}`: {}", m.policy.family().name, trained.describe());
                if !outside_of.contains(&note) {
                    outside_of.push(note);
                }
                " †"
            } else {
                ""
            }
        };
        let mut line = format!(
            "| {} ({}) | {} | {} |",
            super::super::markdown_cell(&m.policy.table_label()),
            m.role,
            m.stiffness().map_or_else(|| "–".into(), |k| format!("{k}")),
            cell_text(cell(&m.pushes, "no-force"))
        );
        for n in &r.push_n {
            // Every push acts on both hands for the whole clip.
            let inside = trained.holds_push(*n, r.seconds, true, m.stiffness(), false);
            line.push_str(&format!(
                " {}{} |",
                cell_text(mean_over(&m.pushes, &r.settings_of(*n))),
                mark(inside)
            ));
        }
        for n in &r.event_n {
            // Every direction of an event has the same envelope verdict.
            let inside = crate::sim::disturbance::Disturbance::parse(&event_setting(*n, 0.0))
                .and_then(Result::ok)
                .and_then(|d| trained.outside_disturbance(&d, m.stiffness()))
                .map(|why| why.is_empty());
            line.push_str(&format!(
                " {}{} |",
                cell_text(mean_over(&m.pushes, &r.events_of(*n))),
                mark(inside)
            ));
        }
        let log_inside = match trained {
            // A continuous history on both hands is no single-wrist event.
            TrainedForces::WristEvents { .. } => Some(false),
            _ => None,
        };
        line.push_str(&format!(
            " {}{} | {} |\n",
            cell_text(cell(&m.force_log, "force")),
            mark(log_inside),
            super::super::minutes(m.wall_s)
        ));
        out.push_str(&line);
    }
    out.push('\n');
    if !outside_of.is_empty() {
        out.push_str(&format!(
            "† outside the forces the member's family was trained with, shown as measured: {}.\n\n",
            outside_of.join("; ")
        ));
    }
    out
}

/// The paired differences of pair `r` on `engine`, each column's with its interval.
fn differences_table(r: &PairResult, engine: &str) -> String {
    let mut out = String::new();
    out.push_str("| compliant − baseline | no force |");
    let mut rule = String::from("|---|---:|");
    for n in &r.push_n {
        out.push_str(&format!(" {n} N (over directions) |"));
        rule.push_str("---:|");
    }
    out.push_str(" all pushes (over directions, by magnitude) |");
    rule.push_str("---:|");
    for n in &r.event_n {
        out.push_str(&format!(" event {n} N (over directions) |"));
        rule.push_str("---:|");
    }
    if !r.event_n.is_empty() {
        out.push_str(" all events (over directions, by magnitude) |");
        rule.push_str("---:|");
    }
    out.push_str(" force log |\n");
    rule.push_str("---:|\n");
    out.push_str(&rule);
    let one = |s: &str| vec![vec![s.to_string()]];
    let mut columns: Vec<Vec<Vec<String>>> = vec![one("no-force")];
    columns.extend(r.push_n.iter().map(|n| vec![r.settings_of(*n)]));
    columns.push(r.all_pushes());
    columns.extend(r.event_n.iter().map(|n| vec![r.events_of(*n)]));
    if !r.event_n.is_empty() {
        columns.push(r.all_events());
    }
    columns.push(one("force"));
    for (k, (what, digits)) in [
        ("Δ FATS", 1),
        ("Δ survival", 3),
        ("Δ keypoint error (mm)", 1),
    ]
    .into_iter()
    .enumerate()
    {
        out.push_str(&format!("| {what} |"));
        for settings in &columns {
            let text = r
                .differences(engine, settings)
                .map_or_else(|| "–".into(), |d| difference_text(&d[k], digits));
            out.push_str(&format!(" {text} |"));
        }
        out.push('\n');
    }
    out
}

/// The pairs as Markdown: per pair and engine, one table of every member's cells (FATS ·
/// survival · keypoint error in mm; a push magnitude's cell averages its directions) and
/// one of the paired differences with their bootstrap 95 % intervals.
pub fn pairs_table(results: &[PairResult]) -> String {
    let mut out = String::new();
    for r in results {
        let engines: Vec<&str> = {
            let mut e: Vec<&str> = r.members.iter().map(|m| m.engine).collect();
            e.dedup();
            e
        };
        for engine in engines {
            out.push_str(&format!(
                "**{}** on {} ({:.1} s of it), {engine}; pushes per hand and events on the right wrist (`{PAIR_EVENT}`) from {} degrees off the clip's initial heading; force log: the hand forces of synthetic {} replayed on the clip (looped, in the world frame), not a recording of this motion. Cells: FATS · survival · keypoint error (mm); a push or event column averages its directions.\n\n",
                r.pair.name(),
                r.clip,
                r.seconds,
                r.push_headings_deg.iter().map(|h| format!("{h}")).collect::<Vec<_>>().join("/"),
                r.force_source
            ));
            out.push_str(&members_table(r, engine));
            out.push_str(&differences_table(r, engine));
            out.push('\n');
        }
    }
    out
}

/// Every cell of every pair as CSV: pair, engine, role, policy, stiffness, setting, FATS,
/// survival, keypoint error (names spreadsheet-safe, `names::csv_text`).
pub fn pairs_csv(results: &[PairResult]) -> String {
    use crate::files::names::csv_text::cell as text;
    let mut w = csv::Writer::from_writer(Vec::new());
    let mut row = |fields: &[&str]| {
        // Writing to memory cannot fail.
        let _ = w.write_record(fields);
    };
    row(&[
        "pair",
        "engine",
        "role",
        "policy",
        "stiffness_n_per_m",
        "setting",
        "fats",
        "survival",
        "kp_mm",
    ]);
    for r in results {
        for m in &r.members {
            let runs = r
                .push_settings
                .iter()
                .map(|s| (s.as_str(), &m.pushes))
                .chain(std::iter::once(("force", &m.force_log)));
            for (setting, summary) in runs {
                let Some([f, s, e]) = cell(summary, setting) else {
                    continue;
                };
                let setting = if setting == "force" {
                    format!("force-log:{}", r.force_source)
                } else {
                    setting.to_string()
                };
                row(&[
                    &text(&r.pair.name()),
                    m.engine,
                    m.role,
                    &text(&m.policy.to_string()),
                    &m.stiffness().map_or_else(String::new, |k| k.to_string()),
                    &text(&setting),
                    &f.to_string(),
                    &s.to_string(),
                    &e.to_string(),
                ]);
            }
        }
    }
    String::from_utf8(w.into_inner().unwrap_or_default()).unwrap_or_default()
}

/// Writes `pairs.md` (the tables) and `pairs.csv` (every cell) into `out`, each whole or
/// not at all; returns their paths.
pub fn write_pair_files(out: &Path, results: &[PairResult]) -> std::io::Result<[PathBuf; 2]> {
    let md = out.join("pairs.md");
    let csv = out.join("pairs.csv");
    crate::files::atomic_file::write(
        &md,
        format!("# Compliant and stiff pairs\n\n{}", pairs_table(results)),
    )?;
    crate::files::atomic_file::write(&csv, pairs_csv(results))?;
    Ok([md, csv])
}
