//! `thorarena leaderboard`: every policy given on the synthetic dataset (or yours), force
//! and no-force, on each engine — one `eval` run per (policy, engine), resumed when the
//! command is run again — then one table (`leaderboard.md`, printed) and the paper's
//! tables and figures over the same runs (`report.html`, `report.md`, CSVs, SVGs); single-
//! clip policies on their own clips under pushes in a table and a report of their own
//! (`single-clip.html`, …).

use std::path::PathBuf;
use std::time::Instant;
use thorarena::campaign::leaderboard::{
    run_leaderboard_job, CompliancePair, LeaderboardJob, OwnClip, PairOptions,
};
use thorarena::eval::pipeline::ProgressLines;

/// Arguments of `leaderboard`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// A general policy, as `eval --policy` takes it, run in process (`twist2:FILE.onnx`,
    /// `wbc-mjlab:FILE.onnx`, `beyondmimic:FILE.onnx`, a built-in); repeat for each.
    #[arg(long = "policy", value_parser = thorarena::policy::registry::PolicySource::parse, required_unless_present_any = ["clips", "policy_file", "pairs"])]
    pub policies: Vec<thorarena::policy::registry::PolicySource>,
    /// More general policies from a TOML file of `[[policy]]` tables, in a sweep spec's
    /// format: `policy = "wbc-mjlab:FILE.onnx"` runs in process; `command = "…"` is a
    /// policy process in any language, started for each run and joining session
    /// `{session}` (`{thorarena}` is this binary), with `name`, `profile` [default:
    /// `default`] and `connect_timeout_s` [default 30]. Paths and commands are taken in the
    /// file's directory; a process's output goes to OUT/runs/NAME-ENGINE.policy.log.
    #[arg(long)]
    pub policy_file: Option<PathBuf>,
    /// A single-clip policy on its own clip, `POLICY@DATASET` (e.g.
    /// `beyondmimic:fastsac_g1_29dof_dancing.onnx@dance`, the dance imported from the
    /// network); each runs under --clip-settings in a table of its own. Repeat for each.
    #[arg(long = "clip")]
    pub clips: Vec<OwnClip>,
    /// A compliant policy and its stiff twin trained on the same clip, on that clip:
    /// `COMPLIANT vs BASELINE@DATASET` (a dataset of the clip alone, e.g.
    /// `softmimic:Pour-SoftMimic.onnx vs softmimic:Pour-Baseline.onnx@pour`); each runs
    /// under no force, --pair-pushes from --pair-headings, and the hand forces of a synthetic
    /// --pair-force-task sequence replayed on the clip, the compliant one also at each
    /// --pair-stiffness. Tables in OUT/pairs.md, every cell in OUT/pairs.csv. Repeat for each.
    #[arg(long = "pair")]
    pub pairs: Vec<CompliancePair>,
    /// The compliant member's stiffness sweep, N/m, comma separated (a softmimic network).
    #[arg(long, value_delimiter = ',', default_value = "30,60,150,300,600")]
    pub pair_stiffness: Vec<f64>,
    /// Seconds of each pair's clip that run (from its start).
    #[arg(long, default_value_t = 20.0)]
    pub pair_seconds: f64,
    /// Push magnitudes per hand of the pairs, N, comma separated.
    #[arg(long, value_delimiter = ',', default_value = "10,20,30,50")]
    pub pair_pushes: Vec<f64>,
    /// Force events of the pairs on the right wrist, N, comma separated: ramped over 0.5 s
    /// from the second second, held 1 s, released over 0.5 s — inside SoftMimic's training
    /// (one wrist, ramps of 0.1–2 s, holds of 0.5–1 s) up to stiffness × 0.7 m.
    #[arg(long, value_delimiter = ',', default_value = "10,20,30")]
    pub pair_events: Vec<f64>,
    /// Push (and event) directions of the pairs, degrees from the clip's initial heading.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "0,90,180,270",
        allow_negative_numbers = true
    )]
    pub pair_headings: Vec<f64>,
    /// The synthetic task whose first sequence's hand forces are replayed on each pair's
    /// clip (looped to its length).
    #[arg(long, default_value = "push_chair")]
    pub pair_force_task: String,
    /// Settings of the single-clip table, comma separated.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "no-force,push:10,push:20,push:30",
        value_parser = super::choices::SettingArg
    )]
    pub clip_settings: Vec<thorarena::eval::Setting>,
    /// Engines, comma separated; every policy runs on each [default: mujoco in a build
    /// with the `mujoco` feature, else rapier].
    #[arg(long, value_enum, value_delimiter = ',')]
    pub engines: Vec<super::choices::EngineArg>,
    /// Dataset [default: the synthetic six-task dataset, generated once into
    /// OUT/synthetic with --per-task sequences per task].
    #[arg(long, value_parser = thorarena::sim::motion::dataset_arg)]
    pub dataset: Option<PathBuf>,
    /// Sequences per task of the generated synthetic dataset (60: the paper's).
    #[arg(long, default_value_t = 60)]
    pub per_task: usize,
    /// Settings, comma separated, as for `eval`.
    #[arg(long, value_delimiter = ',', default_value = "force,no-force", value_parser = super::choices::SettingArg)]
    pub settings: Vec<thorarena::eval::Setting>,
    /// Also score every general policy on the bundled real human walks (`real-walks`)
    /// under these settings, comma separated (e.g. no-force,push:10,push:20,push:30).
    #[arg(long, value_delimiter = ',', value_parser = super::choices::SettingArg)]
    pub real_walks: Vec<thorarena::eval::Setting>,
    /// Directory of the runs, the dataset it generates and the tables.
    #[arg(long, default_value = "results/leaderboard")]
    pub out: PathBuf,
    /// Score policies without their sanity check (recorded in each run.json).
    #[arg(long)]
    pub unchecked: bool,
    /// A policy (its --policy argument, or a policy file's `name`) whose runs start again
    /// from the start instead of resuming: after its command, file or settings changed.
    /// Repeat for each.
    #[arg(long, value_name = "NAME")]
    pub rerun: Vec<String>,
}

pub(super) fn run(args: &Args) -> anyhow::Result<()> {
    let started = Instant::now();
    let job = LeaderboardJob {
        policies: args.policies.clone(),
        policy_file: args.policy_file.clone(),
        clips: args.clips.clone(),
        clip_settings: args.clip_settings.clone(),
        pairs: args.pairs.clone(),
        pair_options: PairOptions {
            stiffness_n_per_m: args.pair_stiffness.clone(),
            seconds: args.pair_seconds,
            push_n: args.pair_pushes.clone(),
            push_headings_deg: args.pair_headings.clone(),
            event_n: args.pair_events.clone(),
            force_task: args.pair_force_task.clone(),
            ..PairOptions::default() // engines, output and checking: the job's
        },
        engines: args.engines.iter().map(|&e| e.into()).collect(),
        dataset: args.dataset.clone(),
        per_task: args.per_task,
        settings: args.settings.clone(),
        real_walks_settings: args.real_walks.clone(),
        out: args.out.clone(),
        unchecked: args.unchecked,
        command: std::env::args().skip(1).collect::<Vec<_>>().join(" "),
        rerun: args.rerun.clone(),
    };
    let mut say = |line: &str| eprintln!("{}", super::flags::as_flags(line));
    let written = run_leaderboard_job(&job, &mut ProgressLines::new(&mut say))?;
    if let Some([md, csv]) = &written.pair_files {
        eprintln!("wrote {} and {}", md.display(), csv.display());
    }
    print!("{}", written.tables);
    for (report, files) in &written.reports {
        super::report_html::tell_written(report, files);
    }
    let wall_s = started.elapsed().as_secs_f64();
    eprintln!("wrote {} ({wall_s:.0} s in all)", written.page.display());
    Ok(())
}
