//! `thorarena merge`: combine the shards of one evaluation into the single run they add
//! up to — the same records, summary and tables as an unsharded run.

use anyhow::{bail, Context};
use std::collections::BTreeMap;
use std::path::PathBuf;
use thorarena::evaluation::EpisodeRecord;
use thorarena::motion::Dataset;
use thorarena::results::{
    read_header, sort_records, write_header, write_record, write_results, EpisodeLog, RunHeader,
    EPISODES_FILE,
};
use thorarena::runner::task_thresholds;

/// Episode records keyed by (task, sequence, setting).
pub(super) type EpisodesByKey = BTreeMap<(String, String, String), EpisodeRecord>;

/// The records of `runs`, shards of one evaluation: their common header (with the first
/// shard's `shard`) and every episode once, keyed by (task, sequence, setting). Refuses
/// runs of another configuration and an episode two shards disagree on.
pub(super) fn read_shards(runs: &[PathBuf]) -> anyhow::Result<(RunHeader, EpisodesByKey)> {
    let first = runs.first().context("no run to merge")?;
    let header = read_header(first)?;
    let mut by_key = EpisodesByKey::new();
    for run in runs {
        let own = read_header(run)?;
        let mut h = own.clone();
        h.shard = header.shard;
        if h != header {
            bail!("{} is not a shard of the same evaluation as {} (policy, profile, dataset, keypoints, termination and settings must agree)", run.display(), first.display());
        }
        let log = EpisodeLog::read(&run.join(EPISODES_FILE), &own)?;
        if log.torn_tail {
            bail!("{}: episodes.jsonl ends in a line cut short (the shard was killed mid-write); `thorarena eval --resume` it first", run.display());
        }
        for r in log.records {
            let key = (r.task.clone(), r.sequence_id.clone(), r.setting.clone());
            match by_key.get(&key) {
                Some(existing) if existing != &r => bail!(
                    "{}: episode {}/{} ({}) differs from another shard's",
                    run.display(),
                    key.0,
                    key.1,
                    key.2
                ),
                _ => {
                    by_key.insert(key, r);
                }
            }
        }
    }
    Ok((header, by_key))
}

/// Arguments of `merge`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Run directories (shards of the same evaluation).
    #[arg(required = true)]
    pub runs: Vec<PathBuf>,
    /// Output run directory.
    #[arg(long)]
    pub out: PathBuf,
    /// Robot.
    #[arg(long, default_value = "g1_29dof")]
    pub robot: String,
    /// Replace a run already in `--out` (never one of the shards).
    #[arg(long)]
    pub overwrite: bool,
}

pub(super) fn run(args: &Args) -> anyhow::Result<()> {
    super::overwrite::check_dir(&args.out, args.overwrite, &args.runs)?;
    let robot = super::load_robot(&args.robot)?;
    let (mut header, by_key) = read_shards(&args.runs)?;
    header.shard = None;
    let ds = Dataset::open(std::path::Path::new(&header.dataset), &robot)?;
    if ds.content_hash() != header.dataset_sha256 {
        bail!(
            "dataset {} changed since the shards ran (content hash differs)",
            header.dataset
        );
    }
    let sequences = ds.load_all()?;
    let missing: Vec<String> = header
        .planned_jobs()
        .into_iter()
        .map(|(q, s)| {
            (
                header.sequences[q].task.clone(),
                header.sequences[q].sequence_id.clone(),
                header.settings[s].name.clone(),
            )
        })
        .filter(|k| !by_key.contains_key(k))
        .map(|(t, i, s)| format!("{t}/{i} ({s})"))
        .collect();
    if !missing.is_empty() {
        bail!(
            "{} episodes are in no shard: {}",
            missing.len(),
            missing
                .iter()
                .take(5)
                .cloned()
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    let mut records: Vec<EpisodeRecord> = by_key.into_values().collect();
    sort_records(&mut records, &header);
    std::fs::create_dir_all(&args.out)?;
    let mut w = std::io::BufWriter::new(std::fs::File::create(args.out.join("episodes.jsonl"))?);
    for r in &records {
        write_record(&mut w, r)?;
    }
    write_header(&args.out, &header)?;
    let thresholds = task_thresholds(&sequences, header.control_dt_s);
    let summary = write_results(&args.out, &header, &records, thresholds, None)?;
    let tables = thorarena::report::write_run_tables(&args.out, &summary)?;
    println!("{tables}");
    eprintln!(
        "merged {} runs, {} episodes → {}",
        args.runs.len(),
        records.len(),
        args.out.display()
    );
    Ok(())
}
