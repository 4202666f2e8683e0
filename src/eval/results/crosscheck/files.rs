//! A crosscheck read from its two engines' run directories and written out:
//! [`compare_runs`] pairs the runs' records by episode, attaches each engine's series
//! (joint angles of the first seconds, foot slip) and compares means per setting and per
//! push force; [`write_crosscheck`] writes `crosscheck.json` ([`CrosscheckFile`]) and
//! `crosscheck.csv` (one [`CrosscheckCsvRow`] per episode).

use super::series::SeriesLog;
use super::{
    compare_push_levels, compare_settings, foot_slip_pair, joint_divergence, pair_episodes,
    CrosscheckFile, EngineRuns, EpisodePair, SettingComparison,
};
use crate::eval::results::{ResultsError, RunDir};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// `crosscheck.json`.
pub const CROSSCHECK_JSON_FILE: &str = "crosscheck.json";
/// `crosscheck.csv`.
pub const CROSSCHECK_CSV_FILE: &str = "crosscheck.csv";

/// Two engines' runs of the same episodes, compared.
#[derive(Debug)]
pub struct Crosscheck {
    /// Per setting.
    pub settings: Vec<SettingComparison>,
    /// Per push force, over its directions (as many as settings when no push has two).
    pub push_levels: Vec<SettingComparison>,
    /// Every episode on both engines.
    pub pairs: Vec<EpisodePair>,
    /// Episodes without their series on one engine (a run resumed from an older
    /// crosscheck): no joint divergence or foot slip for them.
    pub without_series: usize,
}

/// Compares the runs `a` (rapier) and `b` (MuJoCo) of the same episodes, with their
/// series, `resamples` bootstrap resamples per interval (seeded: reproducible). Every
/// episode must have run on both engines.
pub fn compare_runs(
    runs: [&RunDir; 2],
    series: [&SeriesLog; 2],
    resamples: usize,
) -> Result<Crosscheck, ResultsError> {
    let read = |run: &RunDir| -> Result<_, ResultsError> {
        let header = run.read_header()?;
        let log = run.read_log(&header)?;
        Ok((header, log.records, run.read_summary()?.thresholds))
    };
    let (header, a, thresholds) = read(runs[0])?;
    let (_, b, _) = read(runs[1])?;
    let (mut pairs, unpaired) = pair_episodes(&a, &b, &thresholds);
    if let Some(example) = unpaired.first() {
        return Err(ResultsError::Unpaired {
            count: unpaired.len(),
            example: example.clone(),
        });
    }
    let mut without_series = 0;
    for p in &mut pairs {
        let key = p.key();
        let (a, b) = (series[0], series[1]);
        if let (Some(qa), Some(qb)) = (a.first_q.get(&key), b.first_q.get(&key)) {
            p.joint_divergence = joint_divergence(qa, qb);
        } else {
            without_series += 1;
        }
        if let (Some(sa), Some(sb)) = (a.foot_slip_m.get(&key), b.foot_slip_m.get(&key)) {
            p.foot_slip = foot_slip_pair(sa, sb, header.control_dt_s);
        }
    }
    let settings = compare_settings(&pairs, resamples, 0);
    let push_levels = compare_push_levels(&pairs, &header.settings, resamples, 0);
    Ok(Crosscheck {
        settings,
        push_levels,
        pairs,
        without_series,
    })
}

/// One episode of `crosscheck.csv`; an undefined number (NaN, no series) is empty.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CrosscheckCsvRow {
    /// Task.
    #[serde(serialize_with = "crate::files::names::csv_text::serialize")]
    pub task: String,
    /// Sequence id.
    #[serde(serialize_with = "crate::files::names::csv_text::serialize")]
    pub sequence_id: String,
    /// Setting.
    #[serde(serialize_with = "crate::files::names::csv_text::serialize")]
    pub setting: String,
    /// Survival on rapier.
    pub survival_rapier: Option<f64>,
    /// Survival on MuJoCo.
    pub survival_mujoco: Option<f64>,
    /// Mean keypoint error on rapier, mm.
    pub kp_mm_rapier: Option<f64>,
    /// Mean keypoint error on MuJoCo, mm.
    pub kp_mm_mujoco: Option<f64>,
    /// Episode score on rapier.
    pub score_rapier: Option<f64>,
    /// Episode score on MuJoCo.
    pub score_mujoco: Option<f64>,
    /// Control steps the joint angles were compared over.
    pub joint_divergence_steps: Option<usize>,
    /// RMS joint-angle divergence, rad.
    pub joint_divergence_rms_rad: Option<f64>,
    /// Largest joint-angle divergence, rad.
    pub joint_divergence_max_rad: Option<f64>,
    /// Total foot slip on rapier, m.
    pub foot_slip_m_rapier: Option<f64>,
    /// Total foot slip on MuJoCo, m.
    pub foot_slip_m_mujoco: Option<f64>,
    /// When the engines' slip parted, s.
    pub foot_slip_parts_at_s: Option<f64>,
}

fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

impl CrosscheckCsvRow {
    /// The row of one episode.
    pub fn of(p: &EpisodePair) -> Self {
        Self {
            task: p.task.clone(),
            sequence_id: p.sequence_id.clone(),
            setting: p.setting.clone(),
            survival_rapier: finite(p.a.survival),
            survival_mujoco: finite(p.b.survival),
            kp_mm_rapier: finite(p.a.kp_mm),
            kp_mm_mujoco: finite(p.b.kp_mm),
            score_rapier: finite(p.a.score),
            score_mujoco: finite(p.b.score),
            joint_divergence_steps: p.joint_divergence.map(|d| d.steps),
            joint_divergence_rms_rad: p.joint_divergence.and_then(|d| finite(d.rms_rad)),
            joint_divergence_max_rad: p.joint_divergence.and_then(|d| finite(d.max_rad)),
            foot_slip_m_rapier: p.foot_slip.and_then(|f| finite(f.total_m[0])),
            foot_slip_m_mujoco: p.foot_slip.and_then(|f| finite(f.total_m[1])),
            foot_slip_parts_at_s: p.foot_slip.and_then(|f| f.parts_at_s.and_then(finite)),
        }
    }
}

/// Writes `crosscheck.json` and `crosscheck.csv` of `check` into `dir`, naming the two
/// runs; returns their paths.
pub fn write_crosscheck(
    dir: &Path,
    runs: [&Path; 2],
    check: &Crosscheck,
    resamples: usize,
    divergence_seconds: f64,
) -> Result<[PathBuf; 2], ResultsError> {
    let file = CrosscheckFile {
        runs: EngineRuns {
            rapier: runs[0],
            mujoco: runs[1],
        },
        bootstrap_resamples: resamples,
        divergence_seconds,
        settings: &check.settings,
        push_levels: &check.push_levels,
        episodes: &check.pairs,
    };
    let json_path = dir.join(CROSSCHECK_JSON_FILE);
    let text = serde_json::to_string_pretty(&file).map_err(|source| ResultsError::Json {
        path: json_path.clone(),
        line: None,
        source,
    })? + "\n";
    crate::files::atomic_file::write(&json_path, text).map_err(ResultsError::io(&json_path))?;
    let csv_path = dir.join(CROSSCHECK_CSV_FILE);
    let csv_error = |e: csv::Error| ResultsError::io(&csv_path)(std::io::Error::other(e));
    let mut w = csv::Writer::from_writer(Vec::new());
    for p in &check.pairs {
        w.serialize(CrosscheckCsvRow::of(p)).map_err(csv_error)?;
    }
    let bytes = w
        .into_inner()
        .map_err(|e| ResultsError::io(&csv_path)(std::io::Error::other(e.to_string())))?;
    crate::files::atomic_file::write(&csv_path, bytes).map_err(ResultsError::io(&csv_path))?;
    Ok([json_path, csv_path])
}
