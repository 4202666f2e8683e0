//! Compliant and stiff pairs: two policies trained on the same clip — one to yield when
//! pushed (SoftMimic's `*-SoftMimic`), one to hold its reference (`*-Baseline`) — on that
//! clip, under no force, constant hand pushes of each magnitude from four directions, and
//! a force history grafted onto the clip ([`crate::sim::motion::force_graft`]: the hand forces
//! of a synthetic sequence, looped to the clip's length). The compliant member also runs
//! at each stiffness of a short sweep. Each (member, engine) is two ordinary `eval` runs —
//! the pushes on the clip, the force history on the grafted clip — resumed when the
//! command is run again; the paired differences (compliant − baseline) come with
//! bootstrap 95 % intervals over the push directions.
//!
//! A single clip is deterministic: one episode per setting. The intervals therefore
//! resample the four directions of one magnitude (for all pushes, the directions within
//! each magnitude), not repeated episodes: they are not confidence intervals of a
//! population, they say how much the difference depends on where the push comes from. The
//! tables label them so.

use super::{board_run, run_name, LeaderboardError, LeaderboardObserver, Player};
// `check_out` refuses an output directory holding a dataset or a run.
use crate::eval::results::Summary;
use crate::eval::{EngineChoice, Setting};
use crate::policy::registry::{self, PolicySource};
use crate::sim::motion::force_graft::{first_seconds, with_forces_of};
use crate::sim::motion::synth::{synthesize, SynthOptions};
use crate::sim::motion::{Dataset, DatasetWriter, Sequence};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Two policies trained on one clip, and the dataset of that clip.
#[derive(Debug, Clone, PartialEq)]
pub struct CompliancePair {
    /// The compliant member (its stiffness is swept).
    pub compliant: PolicySource,
    /// The stiff member.
    pub baseline: PolicySource,
    /// A dataset holding the clip alone.
    pub dataset: PathBuf,
}

/// `COMPLIANT vs BASELINE@DATASET`, as a command line gives it.
impl std::str::FromStr for CompliancePair {
    type Err = String;

    /// `COMPLIANT vs BASELINE@DATASET` (the dataset after the last `@`), each member
    /// parsed as `--policy` is.
    fn from_str(text: &str) -> Result<Self, String> {
        let spelled = || format!("`{text}`: give COMPLIANT vs BASELINE@DATASET");
        let (pair, dataset) = text.rsplit_once('@').ok_or_else(spelled)?;
        let (compliant, baseline) = pair.split_once(" vs ").ok_or_else(spelled)?;
        let (compliant, baseline) = (compliant.trim(), baseline.trim());
        if compliant.is_empty() || baseline.is_empty() || dataset.is_empty() {
            return Err(spelled());
        }
        let member = |m: &str| PolicySource::parse(m).map_err(|e| format!("`{text}`: {e}"));
        Ok(Self {
            compliant: member(compliant)?,
            baseline: member(baseline)?,
            dataset: PathBuf::from(dataset),
        })
    }
}

impl CompliancePair {
    /// Its name in directories and tables: `<compliant stem>-vs-<baseline stem>`.
    pub fn name(&self) -> String {
        let stem = |p: &PolicySource| p.file_stem().unwrap_or_else(|| p.to_string());
        let raw = format!("{}-vs-{}", stem(&self.compliant), stem(&self.baseline));
        raw.chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || "-_.".contains(c) {
                    c
                } else {
                    '_'
                }
            })
            .collect()
    }
}

/// How the pairs run.
#[derive(Debug, Clone, Default)]
pub struct PairOptions {
    /// The compliant member's stiffness sweep, N/m (a `softmimic:` policy; none for others).
    pub stiffness_n_per_m: Vec<f64>,
    /// The first seconds of the clip that run.
    pub seconds: f64,
    /// Push magnitudes per hand, N.
    pub push_n: Vec<f64>,
    /// Push directions, degrees from the clip's initial heading (also the events').
    pub push_headings_deg: Vec<f64>,
    /// Force event magnitudes on the right wrist, N: SoftMimic's training shape
    /// ([`PAIR_EVENT`]), from every direction.
    pub event_n: Vec<f64>,
    /// The synthetic task whose first sequence's forces are grafted onto the clip.
    pub force_task: String,
    /// Engines.
    pub engines: Vec<EngineChoice>,
    /// The leaderboard's directory (the pairs go under `<out>/pairs/<pair>`).
    pub out: PathBuf,
    /// Score policies without their sanity check.
    pub unchecked: bool,
}

/// The shape of a pair's force events, after `event:<N>@<deg>`: one wrist (the right),
/// ramped over 0.5 s from the second second, held 1 s, released over 0.5 s — inside the
/// events SoftMimic was trained with (one wrist, ramps of 0.1–2 s, holds of 0.5–1 s).
pub const PAIR_EVENT: &str = "hand=right:start=2:ramp=0.5:hold=1:release=0.5";

/// The event setting of magnitude `n` from direction `heading_deg`.
fn event_setting(n: f64, heading_deg: f64) -> String {
    format!("event:{n}@{heading_deg}:{PAIR_EVENT}")
}

impl PairOptions {
    /// The settings of the push runs as `eval --settings` spells them: no force, then every
    /// push magnitude from every direction, then every event magnitude from every direction.
    pub fn push_spellings(&self) -> Vec<String> {
        let mut s = vec!["no-force".to_string()];
        for n in &self.push_n {
            for h in &self.push_headings_deg {
                s.push(format!("push:{n}@{h}"));
            }
        }
        for n in &self.event_n {
            for h in &self.push_headings_deg {
                s.push(event_setting(*n, *h));
            }
        }
        s
    }

    /// [`Self::push_spellings`] read as settings, refusing the first that is none (the
    /// options' numbers out of a setting's range).
    pub fn push_settings(&self) -> Result<Vec<Setting>, LeaderboardError> {
        self.push_spellings()
            .iter()
            .map(|s| {
                Setting::parse(s).map_err(|why| {
                    data_error("(every pair)", format!(
                        "`{s}` (from `option.pair_pushes`, `option.pair_events` and `option.pair_headings`) is no setting `eval` takes: {why}"
                    ))
                })
            })
            .collect()
    }
}

/// One member of a pair on one engine.
#[derive(Debug, Clone)]
pub struct PairMember {
    /// `baseline`, `compliant`, or `stiffness` (a value of the sweep).
    pub role: &'static str,
    /// Its policy.
    pub policy: PolicySource,
    /// The engine.
    pub engine: &'static str,
    /// The pushes run's scores.
    pub pushes: Summary,
    /// The grafted force history's scores.
    pub force_log: Summary,
    /// Wall time of this invocation's part, s.
    pub wall_s: f64,
}

impl PairMember {
    /// The stiffness command it ran with, N/m, when it has one.
    pub fn stiffness(&self) -> Option<f64> {
        self.pushes
            .header
            .policy_parameters
            .get("stiffness_n_per_m")
            .copied()
    }
}

/// A pair's runs.
#[derive(Debug, Clone)]
pub struct PairResult {
    /// The pair.
    pub pair: CompliancePair,
    /// The clip, `task/sequence`, and the seconds of it that ran.
    pub clip: String,
    /// Seconds of the clip that ran.
    pub seconds: f64,
    /// The sequence whose forces were grafted, `task/sequence`.
    pub force_source: String,
    /// The push settings, in order (no force first).
    pub push_settings: Vec<String>,
    /// Push magnitudes and directions.
    pub push_n: Vec<f64>,
    /// Push directions, degrees.
    pub push_headings_deg: Vec<f64>,
    /// Event magnitudes on the right wrist, N.
    pub event_n: Vec<f64>,
    /// Every member on every engine, engine by engine.
    pub members: Vec<PairMember>,
}

fn data_error(pair: &str, message: String) -> LeaderboardError {
    LeaderboardError::PairData {
        pair: pair.to_string(),
        message,
    }
}

/// Writes `seq` as the one sequence of dataset `dir`, or checks that `dir` already holds
/// it (a rerun resumes its runs; a changed clip or option is refused, not mixed).
fn one_sequence_dataset(
    pair: &str,
    dir: &Path,
    seq: &Sequence,
    robot: &crate::sim::robot::RobotModel,
) -> Result<(), LeaderboardError> {
    let fail =
        |e: crate::sim::motion::DataError| data_error(pair, format!("{}: {e}", dir.display()));
    if dir.join(crate::sim::motion::MANIFEST).exists() {
        let ds = Dataset::open(dir, robot).map_err(fail)?;
        let same = ds.len() == 1
            && ds.load(0).map_err(fail)?.sequence_id == seq.sequence_id
            && ds.load(0).map_err(fail)?.n_frames() == seq.n_frames();
        if !same {
            return Err(data_error(
                pair,
                format!(
                    "{} holds another clip than this invocation makes (another `option.pair_seconds` or dataset?): remove {} to start the pair anew",
                    dir.display(),
                    dir.parent().unwrap_or(dir).display()
                ),
            ));
        }
        return Ok(());
    }
    std::fs::create_dir_all(dir)
        .map_err(|e| data_error(pair, format!("{}: {e}", dir.display())))?;
    let mut writer = DatasetWriter::create(dir, robot).map_err(fail)?;
    writer.add(seq).map_err(fail)?;
    writer.finish().map_err(fail)?;
    Ok(())
}

/// The shortest stretch of a clip a pair runs, s: a policy's sanity check and the
/// velocity errors of the scores need a second of motion.
pub const MIN_PAIR_SECONDS: f64 = 1.0;

/// The longest stretch of a clip a pair runs, s: an hour, longer than any clip (a longer
/// clip runs whole); a larger number is a mistake, once turned into a clip of 0 s.
pub const MAX_PAIR_SECONDS: f64 = 3600.0;

/// Checks the pairs and their options before anything runs — the leaderboard's own runs
/// included — and gives each pair's stiffness sweep (the compliant member's arguments at
/// each stiffness besides its default): a pair is two different network files, the
/// seconds are a number of [`MIN_PAIR_SECONDS`] to [`MAX_PAIR_SECONDS`], the pushes settings `eval`
/// takes, and a stiffness the family's declared one (a value repeated, as `30,30.0`, runs
/// once).
pub fn check_pairs(
    pairs: &[CompliancePair],
    options: &PairOptions,
) -> Result<Vec<Vec<PolicySource>>, LeaderboardError> {
    if pairs.is_empty() {
        return Ok(Vec::new());
    }
    let all = |message: String| data_error("(every pair)", message);
    if !(MIN_PAIR_SECONDS..=MAX_PAIR_SECONDS).contains(&options.seconds) {
        return Err(all(format!(
            "`option.pair_seconds` {}: give {MIN_PAIR_SECONDS} to {MAX_PAIR_SECONDS} s of the clip (a clip shorter runs whole)",
            crate::eval::short_number(options.seconds)
        )));
    }
    options.push_settings()?;
    let mut seen = std::collections::BTreeSet::new();
    for pair in pairs {
        if !seen.insert((pair.compliant.to_string(), pair.baseline.to_string())) {
            return Err(data_error(&pair.name(), "given twice".into()));
        }
        let mut networks = Vec::new();
        for member in [&pair.compliant, &pair.baseline] {
            let Some(file) = member.file() else {
                return Err(data_error(
                    &pair.name(),
                    format!(
                        "`{member}` is no network file: a pair is two networks trained on one clip"
                    ),
                ));
            };
            networks.push(
                crate::policy::network_file::NetworkFile::read(file)
                    .ok()
                    .map(|(_, id)| id),
            );
        }
        let same_file = matches!(&networks[..], [Some(a), Some(b)] if a == b);
        if pair.compliant == pair.baseline || same_file {
            return Err(data_error(
                &pair.name(),
                "both members are one network: a pair compares two".into(),
            ));
        }
    }
    pairs.iter().map(|p| sweep_of(p, options)).collect()
}

/// Runs every pair: the clip and its grafted twin written under `<out>/pairs/<pair>/`,
/// then each member's two runs on each engine; `sweeps` are [`check_pairs`]' answer for
/// `pairs` and `options` (checked before anything else runs, so not again here).
pub fn run_pairs(
    pairs: &[CompliancePair],
    sweeps: Vec<Vec<PolicySource>>,
    options: &PairOptions,
    observer: &mut dyn LeaderboardObserver,
) -> Result<Vec<PairResult>, LeaderboardError> {
    if pairs.is_empty() {
        return Ok(Vec::new());
    }
    if options.engines.is_empty() {
        return Err(LeaderboardError::Empty);
    }
    super::check_out(&options.out)?;
    let robot = registry::robot("g1_29dof").map_err(|e| data_error("(robot)", e.to_string()))?;
    let synth = SynthOptions {
        per_task: 1,
        tasks: vec![options.force_task.clone()],
        ..SynthOptions::default()
    };
    let source = synthesize(&robot, &synth, |_, _| {})
        .map_err(|e| data_error("(force history)", e.to_string()))?
        .into_iter()
        .next()
        .ok_or_else(|| data_error("(force history)", "nothing synthesized".into()))?;
    let settings = options.push_settings()?;
    let mut results = Vec::new();
    let total = sweeps.iter().map(|s| 2 + s.len()).sum::<usize>() * options.engines.len();
    let mut index = 0;
    for (pair, sweep) in pairs.iter().zip(sweeps) {
        let name = pair.name();
        let ds = Dataset::open(&pair.dataset, &robot)
            .map_err(|e| data_error(&name, format!("{}: {e}", pair.dataset.display())))?;
        if ds.len() != 1 {
            return Err(data_error(
                &name,
                format!(
                    "{} holds {} sequences: a pair runs on its own clip, so give a dataset of that clip alone",
                    pair.dataset.display(),
                    ds.len()
                ),
            ));
        }
        let full = ds.load(0).map_err(|e| data_error(&name, e.to_string()))?;
        let clip = first_seconds(&full, options.seconds);
        let grafted = with_forces_of(&robot, &clip, &source);
        let dir = options.out.join("pairs").join(&name);
        let (clip_dir, graft_dir) = (dir.join("clip"), dir.join("force-log"));
        super::make_run_dir(&options.out, &clip_dir)?;
        super::make_run_dir(&options.out, &graft_dir)?;
        one_sequence_dataset(&name, &clip_dir, &clip, &robot)?;
        one_sequence_dataset(&name, &graft_dir, &grafted, &robot)?;
        let mut players = vec![
            ("baseline", pair.baseline.clone()),
            ("compliant", pair.compliant.clone()),
        ];
        players.extend(sweep.into_iter().map(|p| ("stiffness", p)));
        let mut members = Vec::new();
        for &engine in &options.engines {
            for (role, policy) in &players {
                let player = Player::Argument(policy.clone());
                observer.run_starting(index, total, &policy.to_string(), engine.name());
                index += 1;
                let started = Instant::now();
                let run = dir.join("runs").join(run_name(&policy.dir_label(), engine));
                super::make_run_dir(&dir, &run.with_extension("pushes"))?;
                super::make_run_dir(&dir, &run.with_extension("force-log"))?;
                let pushes = board_run(
                    options.unchecked,
                    &player,
                    &clip_dir,
                    &settings,
                    engine,
                    &run.with_extension("pushes"),
                    super::Resume::Alone,
                    observer,
                )?;
                let force_log = board_run(
                    options.unchecked,
                    &player,
                    &graft_dir,
                    &[Setting::force()],
                    engine,
                    &run.with_extension("force-log"),
                    super::Resume::Alone,
                    observer,
                )?;
                members.push(PairMember {
                    role,
                    policy: policy.clone(),
                    engine: engine.name(),
                    pushes,
                    force_log,
                    wall_s: started.elapsed().as_secs_f64(),
                });
            }
        }
        results.push(PairResult {
            pair: pair.clone(),
            clip: format!("{}/{}", full.task, full.sequence_id),
            seconds: clip.duration_s(),
            force_source: format!("{}/{}", source.task, source.sequence_id),
            push_settings: options.push_spellings(),
            push_n: options.push_n.clone(),
            push_headings_deg: options.push_headings_deg.clone(),
            event_n: options.event_n.clone(),
            members,
        });
    }
    Ok(results)
}

/// The compliant member at each stiffness of the sweep, for a `softmimic:` policy naming
/// no stiffness of its own, but the default it already runs at (its `compliant` row);
/// nothing otherwise. A stiffness the family does not take is refused before anything
/// runs, never dropped.
fn sweep_of(
    pair: &CompliancePair,
    options: &PairOptions,
) -> Result<Vec<PolicySource>, LeaderboardError> {
    let compliant = &pair.compliant;
    if compliant.family().name != "softmimic" {
        return Ok(Vec::new());
    }
    if let Some(own) = compliant.parameters() {
        return Err(data_error(
            &pair.name(),
            format!(
                "the compliant member names its parameters (`@{own}`), but its stiffness is what the pair sweeps (`option.pair_stiffness`): name the network alone"
            ),
        ));
    }
    let mut stiffness: Vec<f64> = Vec::new();
    for &k in &options.stiffness_n_per_m {
        if !stiffness.contains(&k) && k != crate::policy::softmimic::DEFAULT_STIFFNESS.linear {
            stiffness.push(k);
        }
    }
    stiffness
        .iter()
        .map(|k| {
            compliant
                .with_parameters(&format!("stiffness={k}"))
                .map_err(|why| data_error(&pair.name(), format!("`option.pair_stiffness`: {why}")))
        })
        .collect()
}

mod tables;

pub use tables::{pairs_csv, pairs_table, write_pair_files};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pair_parses_with_parameters_and_a_dataset() {
        let p: CompliancePair =
            "softmimic:a/Pour-SoftMimic.onnx vs softmimic:a/Pour-Baseline.onnx@ds/pour"
                .parse()
                .unwrap();
        assert_eq!(p.compliant.to_string(), "softmimic:a/Pour-SoftMimic.onnx");
        assert_eq!(p.baseline.to_string(), "softmimic:a/Pour-Baseline.onnx");
        assert_eq!(p.dataset, PathBuf::from("ds/pour"));
        assert_eq!(p.name(), "Pour-SoftMimic-vs-Pour-Baseline");
        let p: CompliancePair = "softmimic:S.onnx@stiffness=60 vs softmimic:B.onnx@d"
            .parse()
            .unwrap();
        assert_eq!(p.compliant.to_string(), "softmimic:S.onnx@stiffness=60");
        for bad in [
            "a vs b",
            "hold@d",
            " vs b@d",
            "hold vs @d",
            "hold vs balance@",
        ] {
            let e = bad.parse::<CompliancePair>().unwrap_err();
            assert!(
                e.contains("give COMPLIANT vs BASELINE@DATASET"),
                "{bad}: {e}"
            );
        }
        // A member is parsed where the pair is: a typo is refused there.
        let e = "holdx vs balance@d".parse::<CompliancePair>().unwrap_err();
        assert!(e.contains("unknown policy `holdx`"), "{e}");
    }

    #[test]
    fn the_push_settings_cover_every_magnitude_and_direction() {
        let o = PairOptions {
            stiffness_n_per_m: vec![],
            seconds: 10.0,
            push_n: vec![10.0, 50.0],
            push_headings_deg: vec![0.0, 90.0],
            event_n: vec![20.0],
            force_task: "push_chair".into(),
            engines: vec![],
            out: PathBuf::new(),
            unchecked: false,
        };
        assert_eq!(
            o.push_spellings(),
            [
                "no-force",
                "push:10@0",
                "push:10@90",
                "push:50@0",
                "push:50@90",
                "event:20@0:hand=right:start=2:ramp=0.5:hold=1:release=0.5",
                "event:20@90:hand=right:start=2:ramp=0.5:hold=1:release=0.5",
            ]
        );
        // Inside SoftMimic's events at its default stiffness (60 N/m: up to 42 N).
        let d = crate::sim::disturbance::Disturbance::parse(&o.push_spellings()[5])
            .unwrap()
            .unwrap();
        assert_eq!(
            crate::policy::registry::SOFTMIMIC_FORCES.outside_disturbance(&d, Some(60.0)),
            Some(vec![])
        );
        assert_eq!(o.push_settings().unwrap().len(), o.push_spellings().len());
    }
}
