//! A crosscheck for people: the two engines' means and their paired difference with its
//! interval, per setting or per push force, and how soon their joints and feet part.

use crate::eval::results::crosscheck::{Compared, MeanCi, SettingComparison, SLIP_PARTING_M};
use std::fmt::Write as _;

fn fmt(c: &Compared, decimals: usize) -> String {
    format!(
        "{:.d$} | {:.d$} | {:+.d$} [{:+.d$}, {:+.d$}]",
        c.a,
        c.b,
        c.diff,
        c.ci95[0],
        c.ci95[1],
        d = decimals
    )
}

/// The comparison table of `rows` (per setting, or per push force: `first_column`) and
/// the table of their joint-angle divergence and foot slip, in Markdown.
pub fn crosscheck_tables(
    first_column: &str,
    rows: &[SettingComparison],
    divergence_seconds: f64,
) -> String {
    let mut table = format!(
        "| {first_column} | episodes | metric | rapier | mujoco | mujoco − rapier [95 % CI] |\n|---|---:|---|---:|---:|---|\n",
    );
    for s in rows {
        for (metric, c, d) in [
            ("survival", &s.survival, 3),
            ("keypoint error (mm)", &s.kp_mm, 1),
            ("FATS", &s.fats, 2),
            ("foot slip per episode (m)", &s.foot_slip_m, 3),
        ] {
            let _ = writeln!(
                table,
                "| {} | {} | {metric} | {} |",
                s.setting,
                s.episodes,
                fmt(c, d)
            );
        }
    }
    let _ = write!(
        table,
        "\n| {first_column} | episodes | RMS joint-angle divergence over the first {divergence_seconds} s, rad [95 % CI] | feet's slip parts by > {parting_cm} cm: episodes, at (s) [95 % CI] |\n|---|---:|---|---|\n",
        parting_cm = SLIP_PARTING_M * 100.0,
    );
    for s in rows {
        let MeanCi {
            episodes,
            mean,
            ci95,
        } = s.joint_divergence_rad;
        let parts = &s.slip_parts_at_s;
        let when = if s.slip_parted == 0 {
            "—".to_string()
        } else {
            format!(
                "{:.2} [{:.2}, {:.2}]",
                parts.mean, parts.ci95[0], parts.ci95[1]
            )
        };
        let _ = writeln!(
            table,
            "| {} | {episodes} | {mean:.4} [{:.4}, {:.4}] | {} of {}, {when} |",
            s.setting, ci95[0], ci95[1], s.slip_parted, s.episodes,
        );
    }
    table
}

/// A crosscheck's report as `thorarena crosscheck` prints it: the tables per setting, and
/// per push force over its directions when the settings push from several directions.
pub fn crosscheck_report(
    check: &crate::eval::results::crosscheck::Crosscheck,
    divergence_s: f64,
) -> String {
    let mut text = crosscheck_tables("setting", &check.settings, divergence_s);
    if check.push_levels.len() < check.settings.len() {
        text += "\nPer push force, over its directions:\n\n";
        text += &crosscheck_tables("push per hand", &check.push_levels, divergence_s);
    }
    text
}
