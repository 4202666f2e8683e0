//! Writing a run's results: `run.json`, `summary.json` and `tables.md` from the records
//! (shared by `eval` and `merge`, so a merged run is written exactly as a single one).

use crate::motion::Sequence;
use crate::policy::TransportStats;
use crate::report::{diagnostics_table, task_fats_table};
use crate::runner::{summarize, task_thresholds, EpisodeRecord, LatencySummary, RunHeader};
use anyhow::Context;
use std::path::Path;

/// Writes `run.json`.
pub fn write_header(out: &Path, header: &RunHeader) -> anyhow::Result<()> {
    let path = out.join("run.json");
    std::fs::write(&path, serde_json::to_string_pretty(header)? + "\n")
        .with_context(|| format!("writing {}", path.display()))
}

/// Reads `run.json`.
pub fn read_header(run: &Path) -> anyhow::Result<RunHeader> {
    let path = run.join("run.json");
    let text =
        std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
    serde_json::from_str(&text).with_context(|| format!("parsing {}", path.display()))
}

/// How the policy answered during a run: latency and faults (not part of the scores,
/// but part of the results: a deployment engineer reads these first).
#[derive(Debug, Clone, serde::Serialize)]
pub struct PolicyIoReport {
    /// Per-step latency of the policy.
    pub latency: LatencySummary,
    /// Transport counters of a remote policy.
    pub transport: Option<TransportStats>,
    /// Control steps whose actions missed the budget, summed over episodes.
    pub deadline_misses: u64,
    /// Control steps with unusable actions, summed over episodes.
    pub invalid_actions: u64,
}

impl PolicyIoReport {
    fn markdown(&self, header: &RunHeader) -> String {
        let l = &self.latency;
        let budget = header
            .io
            .budget_s
            .map_or("none (lock-step)".to_string(), |b| {
                format!("{:.3} ms", b * 1e3)
            });
        let mut s = format!(
            "## Policy I/O

Per-step latency over {} steps (µs): p50 {:.1}, p90 {:.1}, p99 {:.1}, p99.9 {:.1}, max {:.1}. Budget {budget}, miss rule `{:?}`, latency mode `{:?}`. Deadline misses: {}; invalid actions: {}.",
            l.count, l.p50_us, l.p90_us, l.p99_us, l.p999_us, l.max_us,
            header.io.miss_rule, header.io.latency_mode, self.deadline_misses, self.invalid_actions
        );
        if let Some(t) = &self.transport {
            s += &format!(
                " Late replies: {}; policy failures: {}; reconnections: {}.",
                t.late_replies, t.policy_failures, t.reconnections
            );
        }
        s + "\n"
    }
}

/// Scores the records, writes `summary.json` and `tables.md`, returns the tables. `io`:
/// the policy's latency and faults when this process ran the episodes (a merge of shards
/// has no single latency histogram and leaves it out).
pub fn write_results(
    out: &Path,
    header: &RunHeader,
    records: &[EpisodeRecord],
    sequences: &[Sequence],
    io: Option<&PolicyIoReport>,
) -> anyhow::Result<String> {
    let thresholds = task_thresholds(sequences, header.control_dt_s);
    let results = summarize(records, &thresholds);
    let shard_note = match header.shard {
        Some((i, n)) => format!("\n\n**Shard {i}/{n}: partial results; `thorarena merge` the shards for the benchmark.**"),
        None => String::new(),
    };
    let title = format!(
        "ThorArena {} — policy `{}`, profile `{}`, dataset {} (content sha256 {}), keypoints `{}`, termination: torso height error > {} m or tilt error > {} rad{shard_note}",
        header.version,
        header.policy,
        header.profile,
        header.dataset,
        &header.dataset_sha256[..16],
        header.keypoints,
        header.termination.max_torso_height_error_m,
        header.termination.max_torso_tilt_error_rad
    );
    let mut tables = format!(
        "{title}\n\n## Task-level FATS\n\n{}\n## Diagnostics (averaged over tasks)\n\n{}",
        task_fats_table(&results),
        diagnostics_table(&results)
    );
    if let Some(io) = io {
        tables += &format!("\n{}", io.markdown(header));
    }
    std::fs::write(out.join("tables.md"), &tables)?;
    let summary = serde_json::json!({
        "header": header,
        "episodes": records.len(),
        "thresholds": thresholds,
        "settings": results
            .iter()
            .map(|(k, (tasks, overall))| (k.clone(), serde_json::json!({"tasks": tasks, "average": overall})))
            .collect::<serde_json::Map<_, _>>(),
        "policy_io": io,
    });
    std::fs::write(
        out.join("summary.json"),
        serde_json::to_string_pretty(&summary)? + "\n",
    )?;
    Ok(tables)
}

/// Records sorted into schedule order (setting order of the header, then dataset order).
pub fn sort_records(records: &mut [EpisodeRecord], header: &RunHeader, sequences: &[Sequence]) {
    let setting_rank = |s: &str| {
        header
            .settings
            .iter()
            .position(|x| x.name == s)
            .unwrap_or(usize::MAX)
    };
    let seq_rank = |task: &str, id: &str| {
        sequences
            .iter()
            .position(|q| q.task == task && q.sequence_id == id)
            .unwrap_or(usize::MAX)
    };
    records.sort_by_key(|r| (setting_rank(&r.setting), seq_rank(&r.task, &r.sequence_id)));
}
