//! `tables.md`: one run's scores for people — a title naming everything that was measured,
//! what part of the plan the run holds, the paper's two tables and the policy's I/O — made
//! from the run's [`Summary`], so it always says what `summary.json` says.

use super::{diagnostics_table, outside_training_note, task_fats_table};
use crate::eval::results::{
    PolicyIoReport, ResultsError, RunHeader, SettingResults, Summary, TABLES_FILE,
};
use crate::files::log_text::short_number;
use std::collections::BTreeMap;
use std::path::Path;

/// The Markdown of `tables.md` for a run's summary. A run that does not hold its whole
/// plan says so at the top, cell by cell.
pub fn run_tables(summary: &Summary) -> String {
    let header = &summary.header;
    let shard_note = match header.shard {
        Some((i, n)) => format!("\n\n**Shard {i}/{n}: partial results; `thorarena merge` the shards for the benchmark.**"),
        None => String::new(),
    };
    let subset_note = match &header.subset {
        Some(subset) => format!(
            "\n\n**Part of the dataset: {}; not the benchmark's full coverage.**",
            subset.describe(header.sequences.len())
        ),
        None => String::new(),
    };
    let termination_note = match header.termination.not_the_benchmarks() {
        Some(why) => format!("\n\n**Warning — {why}.**"),
        None => String::new(),
    };
    let partial_note = match summary.coverage.sentence() {
        Some(s) => format!("\n\n**Warning — {s}.**\n\n{}", summary.coverage.markdown()),
        None => String::new(),
    };
    let title = format!(
        "ThorArena {} — policy {}, profile `{}`, engine {}, dataset {} (content sha256 {}), keypoints `{}`, termination: torso height error > {} m or tilt error > {} rad{termination_note}{subset_note}{shard_note}{partial_note}",
        header.version,
        header.policy_text(),
        header.profile,
        header.engine_label(),
        header.dataset,
        &header.dataset_sha256[..header.dataset_sha256.len().min(16)],
        header.keypoints,
        short_number(header.termination.max_torso_height_error_m),
        short_number(header.termination.max_torso_tilt_error_rad)
    );
    let results: SettingResults = summary
        .settings
        .iter()
        .map(|(k, s)| (k.clone(), (s.tasks.clone(), s.average.clone())))
        .collect();
    let intervals: BTreeMap<String, [f64; 2]> = summary
        .settings
        .iter()
        .filter_map(|(k, s)| Some((k.clone(), s.fats_ci95?)))
        .collect();
    let no_interval = if intervals.len() < summary.settings.len() {
        "\nNo 95 % interval where every task has one episode: there is nothing to resample (n/a).\n"
    } else {
        ""
    };
    // A run marks cells only when its policy's family was known at its start, by the name
    // a family's policies run under.
    let trained = super::tables::family_training(&header.policy);
    let mut tables = format!(
        "{title}\n\n## Task-level FATS\n\n{}{no_interval}{}\n## Diagnostics (averaged over tasks)\n\n{}",
        task_fats_table(&results, &intervals, &header.outside_training),
        outside_training_note(&header.outside_training, &trained),
        diagnostics_table(&results)
    );
    if let Some(io) = &summary.policy_io {
        tables += &format!("\n{}", policy_io_markdown(io, header));
    }
    tables
}

/// Writes [`run_tables`] to `<dir>/tables.md` and returns it.
pub fn write_run_tables(dir: &Path, summary: &Summary) -> Result<String, ResultsError> {
    let tables = run_tables(summary);
    let path = dir.join(TABLES_FILE);
    crate::files::atomic_file::write(&path, &tables)
        .map_err(|source| ResultsError::Io { path, source })?;
    Ok(tables)
}

/// The "Policy I/O" section: latency percentiles, the rules, faults and transport counters.
fn policy_io_markdown(io: &PolicyIoReport, header: &RunHeader) -> String {
    let l = &io.latency;
    let budget = header
        .io
        .budget_s
        .map_or("none (lock-step)".to_string(), |b| {
            format!("{:.3} ms", b * 1e3)
        });
    let latency = if l.count == 0 {
        "No control step ran in this attempt (a resume found every episode done): no latency"
            .to_string()
    } else {
        format!(
            "Per-step latency over {} steps (µs): p50 {:.1}, p90 {:.1}, p99 {:.1}, p99.9 {:.1}, max {:.1}",
            l.count, l.p50_us, l.p90_us, l.p99_us, l.p999_us, l.max_us
        )
    };
    let resumed = if io.resumed_episodes > 0 {
        format!(
            " The run was resumed: latency and the transport's counters are of its last attempt, without the {} episodes finished before; deadline misses and invalid actions count every episode.",
            io.resumed_episodes
        )
    } else {
        String::new()
    };
    let mut s = format!(
            "## Policy I/O

{latency}. Budget {budget}, miss rule `{:?}`, latency mode `{:?}`. Deadline misses: {}; invalid actions: {}.{resumed}",
            header.io.miss_rule, header.io.latency_mode, io.deadline_misses, io.invalid_actions
        );
    if let Some(t) = &io.transport {
        s += &format!(
            " Late replies: {}; policy failures: {}; reconnections: {}.",
            t.late_replies, t.policy_failures, t.reconnections
        );
    }
    s + "\n"
}
