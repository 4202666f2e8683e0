//! Importing a batch of motion files into a dataset, all or nothing: sequence ids come
//! from file names and are checked (plain names, distinct, not already in the dataset)
//! before anything is read; every input is then read, checked and converted before the
//! first file is written, so one rejected motion (a glitch, a bad field) leaves the
//! dataset as it was.

use super::canonical::{to_sequence, ImportOptions};
use super::{force_csv, lafan_csv, npz, onnx_motion, twist_pkl, ImportError, RawMotion};
use crate::files::names::{check_name, NameError};
use crate::sim::motion::{
    correct_ground, ground_check, DataError, Dataset, DatasetWriter, GroundCheck, Sequence,
};
use crate::sim::robot::RobotModel;
use std::collections::HashSet;
use std::path::{Path, PathBuf};

/// A source format with what its reader needs.
#[derive(Debug, Clone, PartialEq)]
pub enum SourceFormat {
    /// A GMR/TWIST2 pickle.
    TwistPkl,
    /// A BeyondMimic/mjlab `.npz` motion; joint names when the file has none.
    BeyondMimicNpz {
        /// The file's joint order, if it does not say.
        joint_names: Option<Vec<String>>,
    },
    /// A LAFAN-style retargeted CSV at `fps`.
    LafanCsv {
        /// Its frame rate, Hz.
        fps: f64,
    },
    /// A SoftMimic clip CSV (LAFAN's columns and two foot-contact flags) at `fps`.
    SoftMimicCsv {
        /// Its frame rate, Hz.
        fps: f64,
    },
    /// The reference motion embedded in a BeyondMimic-style ONNX export.
    OnnxMotion {
        /// The anchor body the export's motion is expressed in.
        anchor_body: String,
        /// The policy's control step, s (one motion frame per step).
        control_dt_s: f64,
    },
}

impl SourceFormat {
    /// Reads `path` as this format.
    pub fn read(&self, path: &Path, robot: &RobotModel) -> Result<RawMotion, ImportError> {
        match self {
            SourceFormat::TwistPkl => twist_pkl::read_twist_pkl(path),
            SourceFormat::BeyondMimicNpz { joint_names } => {
                npz::read_beyondmimic_npz(path, joint_names.as_deref())
            }
            SourceFormat::LafanCsv { fps } => lafan_csv::read_lafan_csv(path, *fps),
            SourceFormat::SoftMimicCsv { fps } => lafan_csv::read_softmimic_csv(path, *fps),
            SourceFormat::OnnxMotion {
                anchor_body,
                control_dt_s,
            } => onnx_motion::read_onnx_motion(path, robot, anchor_body, *control_dt_s),
        }
    }
}

/// What to import, and how.
#[derive(Debug, Clone)]
pub struct ImportBatch {
    /// Motion files; each file's stem is its sequence id.
    pub inputs: Vec<PathBuf>,
    /// Their format.
    pub format: SourceFormat,
    /// The task every sequence is filed under.
    pub task: String,
    /// Left and right force logs (CSV, sensor frame) for a single input.
    pub force_logs: Option<[PathBuf; 2]>,
    /// Force log time = motion time + this offset, s.
    pub force_offset_s: f64,
    /// Multiplies the logged forces (−1: the sensor reports the hand's force on the world).
    pub force_sign: f64,
    /// Renormalise root quaternions off unit norm instead of refusing the file.
    pub renormalize_quaternions: bool,
    /// Drop leading and trailing teleoperation-glitch frames instead of refusing the file.
    pub trim_glitches: bool,
    /// Shift each motion so its soles rest on the ground (see [`ground_check`]).
    pub ground_correct: bool,
}

impl SourceFormat {
    /// The motion embedded in a tracking network that runs under `profile`: its control
    /// step is the motion's frame step, and its `[beyondmimic]` anchor body (else the
    /// torso) is the body whose pose the network outputs.
    pub fn onnx_motion_under(profile: &crate::sim::profile::Profile) -> Self {
        Self::OnnxMotion {
            anchor_body: profile
                .beyondmimic
                .as_ref()
                .map_or("torso_link", |b| b.anchor_body.as_str())
                .to_string(),
            control_dt_s: profile.control_dt_s,
        }
    }
}

/// What an import reports while it works.
pub trait ImportObserver {
    /// About to read `input`.
    fn reading(&mut self, _input: &Path) {}
    /// `input` became `seq` (before any ground correction); `ground` is what its soles
    /// showed.
    fn converted(&mut self, _input: &Path, _seq: &Sequence, _ground: Option<&GroundCheck>) {}
    /// `seq`, from `input`, is written into the dataset.
    fn imported(&mut self, _input: &Path, _seq: &Sequence) {}
}

/// An import that reports nothing.
impl ImportObserver for () {}

/// Why a batch was not imported; nothing was written.
#[derive(Debug, thiserror::Error)]
pub enum BatchError {
    /// Force logs given for more than one input.
    #[error("`option.forces` pairs one left and one right log with one motion; import motions with forces one at a time")]
    ForcesForSeveral,
    /// An input path has no file name to take the sequence id from.
    #[error("{}: no file name", .0.display())]
    NoFileName(PathBuf),
    /// The task or a sequence id is not a plain name.
    #[error("{}{rule}", .input.as_ref().map(|p| format!("{}: ", p.display())).unwrap_or_default())]
    BadName {
        /// The input whose file name it is, if it is a sequence id.
        input: Option<PathBuf>,
        /// The rule it breaks.
        rule: NameError,
    },
    /// Two inputs share a file name.
    #[error("two inputs are named `{0}`: sequence ids come from file names and must differ")]
    SameId(String),
    /// The dataset already holds a sequence of that id under the task.
    #[error("{task}/{sequence_id} is already in {}: rename the file or import into another dataset", .dataset.display())]
    AlreadyThere {
        /// The task.
        task: String,
        /// The sequence id.
        sequence_id: String,
        /// The dataset.
        dataset: PathBuf,
    },
    /// A file could not be read or converted.
    #[error(transparent)]
    Import(Box<ImportError>),
    /// The dataset could not be opened or written.
    #[error(transparent)]
    Data(#[from] DataError),
}

impl From<ImportError> for BatchError {
    fn from(e: ImportError) -> Self {
        BatchError::Import(Box::new(e))
    }
}

/// Imports `batch` into the dataset at `out` (created if absent) for `robot`, all or
/// nothing, and returns the dataset as written.
pub fn import_batch(
    out: &Path,
    robot: &RobotModel,
    batch: &ImportBatch,
    observer: &mut dyn ImportObserver,
) -> Result<Dataset, BatchError> {
    if batch.force_logs.is_some() && batch.inputs.len() != 1 {
        return Err(BatchError::ForcesForSeveral);
    }
    let forces = match &batch.force_logs {
        Some([left, right]) => Some([
            force_csv::read_force_csv(left)?,
            force_csv::read_force_csv(right)?,
        ]),
        None => None,
    };
    check_name("`option.task`", &batch.task)
        .map_err(|rule| BatchError::BadName { input: None, rule })?;
    let mut writer = DatasetWriter::append(out, robot)?;
    let ids = sequence_ids(batch, &writer, out)?;
    let mut seqs = Vec::with_capacity(batch.inputs.len());
    for (input, id) in batch.inputs.iter().zip(ids) {
        observer.reading(input);
        let raw = batch.format.read(input, robot)?;
        let opts = ImportOptions {
            task: batch.task.clone(),
            sequence_id: id.to_string(),
            renormalize_quaternions: batch.renormalize_quaternions,
            trim_glitches: batch.trim_glitches,
            forces: forces.clone(),
            force_offset_s: batch.force_offset_s,
            force_sign: batch.force_sign,
        };
        let mut seq = to_sequence(raw, robot, &opts, input)?;
        let ground = ground_check(robot, &seq);
        observer.converted(input, &seq, ground.as_ref());
        if let (Some(g), true) = (&ground, batch.ground_correct) {
            correct_ground(&mut seq, g);
        }
        seqs.push((input, seq));
    }
    for (input, seq) in &seqs {
        writer.add(seq)?;
        observer.imported(input, seq);
    }
    Ok(writer.finish()?)
}

/// The inputs' sequence ids (their file stems), checked before anything is read.
fn sequence_ids<'a>(
    batch: &'a ImportBatch,
    writer: &DatasetWriter,
    out: &Path,
) -> Result<Vec<&'a str>, BatchError> {
    let mut seen = HashSet::new();
    let mut ids = Vec::with_capacity(batch.inputs.len());
    for input in &batch.inputs {
        let stem = input
            .file_stem()
            .and_then(|s| s.to_str())
            .ok_or_else(|| BatchError::NoFileName(input.clone()))?;
        check_name("sequence id (the file name)", stem).map_err(|rule| BatchError::BadName {
            input: Some(input.clone()),
            rule,
        })?;
        if !seen.insert(stem) {
            return Err(BatchError::SameId(stem.to_string()));
        }
        if writer.contains(&batch.task, stem) {
            return Err(BatchError::AlreadyThere {
                task: batch.task.clone(),
                sequence_id: stem.to_string(),
                dataset: out.to_path_buf(),
            });
        }
        ids.push(stem);
    }
    Ok(ids)
}
