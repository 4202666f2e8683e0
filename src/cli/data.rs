//! `thorarena data …`: import motion files, describe, export or synthesise a dataset.

use std::path::PathBuf;
use thorarena::eval::rollout_data::{import_data, DataImport};
use thorarena::sim::motion::import::news::ImportLines;
use thorarena::sim::motion::import::{ImportBatch, SourceFormat};
use thorarena::sim::motion::synth::{write_synthetic, SynthOptions, SynthWriteError};
use thorarena::sim::motion::{describe, Dataset};
use thorarena::sim::robot::RobotModel;

/// `thorarena data …`
#[derive(Debug, clap::Subcommand)]
pub enum DataCommand {
    /// Import motion files (and optional force logs) into a canonical dataset.
    Import(ImportArgs),
    /// Per task: sequences, total duration, force percentiles, joint-limit margin.
    Info(InfoArgs),
    /// Generate the synthetic six-task dataset (deterministic for a seed).
    Synth(SynthArgs),
    /// Export a dataset for Python users (one .npz per sequence plus index.json).
    Export(ExportArgs),
    /// Could the robot perform each motion under its recorded forces? Per task: the
    /// ground's centre of pressure from inverse dynamics against the feet's support, with
    /// and without the hand forces; PHUMA/PBHC kinematic checks; force levels.
    Check(super::data_check::CheckArgs),
    /// The datasets the binary carries, by the name `--dataset` takes.
    List,
}

/// Export formats.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum ExportFormat {
    /// numpy .npz files (`numpy.load`), float32 arrays.
    Npz,
}

/// Arguments of `data export`.
#[derive(Debug, clap::Args)]
pub struct ExportArgs {
    /// Output format.
    #[arg(long, value_enum, default_value = "npz")]
    pub format: ExportFormat,
    /// Dataset directory, or a bundled dataset by name (`sample`, `real-walks`).
    #[arg(value_parser = thorarena::sim::motion::dataset_arg)]
    pub dataset: PathBuf,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
    /// Robot of the dataset.
    #[arg(long, default_value = "g1_29dof")]
    pub robot: String,
    /// Write into a directory holding a run or a dataset (never the dataset exported).
    #[arg(long)]
    pub overwrite: bool,
}

/// Input formats of `data import`.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum Format {
    /// GMR / TWIST / TWIST2 / GMT pickles (root_rot xyzw; 29 or 23 DoF).
    TwistPkl,
    /// BeyondMimic / mjlab npz (body 0 = root, wxyz; the file's `joint_names` when it has
    /// them, else IsaacLab joint order).
    BeyondmimicNpz,
    /// Unitree's retargeted LAFAN1 CSV (no header, 36 columns, xyzw).
    LafanCsv,
    /// SoftMimic's clip CSV (LAFAN1's 36 columns and the left and right foot-contact flags;
    /// 30 fps at speed 1).
    SoftmimicCsv,
    /// The reference motion embedded in a BeyondMimic-style tracking network (holosoma's
    /// exports), read by evaluating its motion outputs at every time step; no forces.
    OnnxMotion,
    /// Rollout traces of `eval --trace`: the simulated root pose and joints at the control
    /// rate, with the hand forces that acted (docs/data-check.md).
    Rollout,
}

/// Arguments of `data import`.
#[derive(Debug, clap::Args)]
pub struct ImportArgs {
    /// Input format.
    #[arg(long, value_enum)]
    pub format: Format,
    /// Motion files; each becomes one sequence named after its file stem.
    #[arg(required = true)]
    pub inputs: Vec<PathBuf>,
    /// Dataset directory (created, or appended to when it holds a manifest).
    #[arg(long)]
    pub out: PathBuf,
    /// Task name of the imported sequences.
    #[arg(long)]
    pub task: String,
    /// Robot the motions are retargeted to.
    #[arg(long, default_value = "g1_29dof")]
    pub robot: String,
    /// Force logs (CSV: time, fx, fy, fz) of the left and right hand; only with one input.
    #[arg(long, num_args = 2, value_names = ["LEFT", "RIGHT"])]
    pub forces: Option<Vec<PathBuf>>,
    /// Force-log time minus motion time, s.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub force_offset: f64,
    /// Multiply logged forces by −1 (sensor reports the force the hand exerts).
    #[arg(long)]
    pub flip_force_sign: bool,
    /// Frame rate of CSV motions, Hz.
    #[arg(long, default_value_t = 30.0)]
    pub fps: f64,
    /// onnx-motion: the profile (a name under data/profiles or a .toml path) the network runs under (its control rate is the motion's
    /// frame rate; its `[beyondmimic]` anchor body is the body whose pose the network
    /// outputs).
    #[arg(long, default_value = "holosoma-wbt")]
    pub profile: String,
    /// Joint names of npz columns, comma separated (default: the file's own `joint_names`,
    /// else the IsaacLab G1 order); a list contradicting the file's names is refused.
    #[arg(long, value_delimiter = ',')]
    pub joint_names: Option<Vec<String>>,
    /// Renormalise root quaternions that are off unit norm instead of rejecting the file.
    #[arg(long)]
    pub renormalize_quaternions: bool,
    /// Drop teleoperation-glitch frames at the start and end of a motion (root jumps faster
    /// than 10 m/s between consecutive frames) instead of rejecting the file. Jumps inside
    /// the motion are rejected even with it.
    #[arg(long)]
    pub trim_glitches: bool,
    /// Shift each motion vertically so that its feet touch the ground in stance (the
    /// median lowest sole point over the motion goes to z = 0). Without it the offset is
    /// only reported.
    #[arg(long)]
    pub ground_correct: bool,
}

/// Arguments of `data info`.
#[derive(Debug, clap::Args)]
pub struct InfoArgs {
    /// Dataset directory, or a bundled dataset by name (`sample`, `real-walks`).
    #[arg(value_parser = thorarena::sim::motion::dataset_arg)]
    pub dataset: PathBuf,
    /// Robot of the dataset.
    #[arg(long, default_value = "g1_29dof")]
    pub robot: String,
}

/// Arguments of `data synth`.
#[derive(Debug, clap::Args)]
pub struct SynthArgs {
    /// Dataset directory to create.
    #[arg(long)]
    pub out: PathBuf,
    /// Sequences per task.
    #[arg(long, default_value_t = 60)]
    pub per_task: usize,
    /// Master seed; the same seed gives the same files.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Tasks to generate, comma separated (default: all six).
    #[arg(long, value_delimiter = ',')]
    pub tasks: Vec<String>,
    /// Robot to generate for.
    #[arg(long, default_value = "g1_29dof")]
    pub robot: String,
    /// Replace a dataset already in `--out` (its manifest and the files it lists).
    #[arg(long, visible_alias = "overwrite")]
    pub force: bool,
    /// Generator version: 2 (real force levels, each motion balanced with its forces and
    /// without them) or 1 (forces scaled below real levels, motions planned kinematically;
    /// reproduces datasets made before version 2 bit for bit).
    #[arg(long, default_value_t = thorarena::sim::motion::synth::GENERATOR_VERSION)]
    pub generator: u32,
}

pub(super) fn run(cmd: &DataCommand) -> anyhow::Result<()> {
    match cmd {
        DataCommand::Import(a) => import(a),
        DataCommand::Info(a) => info(a),
        DataCommand::Export(a) => export(a),
        DataCommand::Synth(a) => synth(a),
        DataCommand::Check(a) => super::data_check::run(a),
        DataCommand::List => super::data_list::run(),
    }
}

/// The reader `--format` names, with what it needs from the other flags.
fn source_format(args: &ImportArgs, robot: &RobotModel) -> anyhow::Result<SourceFormat> {
    Ok(match args.format {
        Format::TwistPkl => SourceFormat::TwistPkl,
        Format::BeyondmimicNpz => SourceFormat::BeyondMimicNpz {
            joint_names: args.joint_names.clone(),
        },
        Format::LafanCsv => SourceFormat::LafanCsv { fps: args.fps },
        Format::SoftmimicCsv => SourceFormat::SoftMimicCsv { fps: args.fps },
        Format::OnnxMotion => SourceFormat::onnx_motion_under(
            &thorarena::policy::registry::profile(&args.profile, robot)?,
        ),
        Format::Rollout => anyhow::bail!("a rollout is no motion file"),
    })
}

fn import(args: &ImportArgs) -> anyhow::Result<()> {
    let robot = thorarena::policy::registry::robot(&args.robot)?;
    let what = match args.format {
        Format::Rollout if args.forces.is_some() => {
            anyhow::bail!("a rollout holds the forces that acted: --forces is for motion files")
        }
        Format::Rollout => DataImport::Rollouts {
            traces: args.inputs.clone(),
            task: args.task.clone(),
        },
        _ => DataImport::Motions(ImportBatch {
            inputs: args.inputs.clone(),
            format: source_format(args, &robot)?,
            task: args.task.clone(),
            force_logs: args.forces.as_ref().map(|f| [f[0].clone(), f[1].clone()]),
            force_offset_s: args.force_offset,
            force_sign: if args.flip_force_sign { -1.0 } else { 1.0 },
            renormalize_quaternions: args.renormalize_quaternions,
            trim_glitches: args.trim_glitches,
            ground_correct: args.ground_correct,
        }),
    };
    let mut say = |line: &str| eprintln!("{}", super::flags::as_flags(line));
    let ds = import_data(&args.out, &robot, &what, &mut ImportLines { say: &mut say })?;
    let sequences = thorarena::sim::motion::plural(ds.len(), "sequence");
    eprintln!("{}: {sequences}", ds.dir.display());
    Ok(())
}

fn export(args: &ExportArgs) -> anyhow::Result<()> {
    let dataset = std::slice::from_ref(&args.dataset);
    thorarena::eval::results::check_dir(&args.out, args.overwrite, dataset)?;
    let robot = thorarena::policy::registry::robot(&args.robot)?;
    let ds = Dataset::open(&args.dataset, &robot)?;
    let ExportFormat::Npz = args.format;
    let files = thorarena::sim::motion::export_npz(&ds, &args.out, |done, total| {
        eprint!("\rexported {done}/{total}")
    })?;
    eprintln!("\n{}: {} files", args.out.display(), files.len());
    Ok(())
}

fn info(args: &InfoArgs) -> anyhow::Result<()> {
    let robot = thorarena::policy::registry::robot(&args.robot)?;
    let ds = Dataset::open(&args.dataset, &robot)?;
    let text = describe(&ds, &ds.load_all()?, &robot);
    print!("{}", super::flags::as_flags(&text));
    Ok(())
}

/// `data synth`: the synthetic six-task dataset written, sequence by sequence, and named.
fn synth(args: &SynthArgs) -> anyhow::Result<()> {
    thorarena::eval::results::check_dataset_dir(&args.out)?;
    let robot = thorarena::policy::registry::robot(&args.robot)?;
    let opts = SynthOptions {
        per_task: args.per_task,
        seed: args.seed,
        fps: 50.0,
        tasks: args.tasks.clone(),
        version: args.generator,
    };
    let started = std::time::Instant::now();
    let mut shown = false;
    let written = write_synthetic(&args.out, &robot, &opts, args.force, |done, total| {
        shown = true;
        eprint!(
            "\rsynth: {done}/{total} sequences written ({:.1} s)",
            started.elapsed().as_secs_f64()
        )
    });
    if shown {
        eprintln!();
    }
    let (ds, replaced) = match written {
        Err(e @ SynthWriteError::Exists(_)) => anyhow::bail!("{e}: pass --force"),
        written => written?,
    };
    if let Some(old) = replaced {
        eprintln!("{old}");
    }
    println!(
        "{}: {} sequences in {:.1} s, content sha256 {} (`thorarena data info` describes it)",
        ds.dir.display(),
        ds.len(),
        started.elapsed().as_secs_f64(),
        &ds.content_hash()[..16],
    );
    Ok(())
}
