//! A dataset directory: `manifest.json` plus one sequence file per entry, each checked
//! against the sha256 the manifest records.

use super::error::{bad, DataError};
use super::format::{decode_sequence, sha256_hex, write_sequence, SCHEMA_VERSION};
use super::sequence::Sequence;
use crate::sim::robot::RobotModel;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The manifest's file name inside a dataset directory.
pub const MANIFEST: &str = "manifest.json";
const SCHEMA_NAME: &str = "thorarena-dataset";

/// `manifest.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    /// Always `thorarena-dataset`.
    pub schema: String,
    /// On-disk schema version.
    pub schema_version: u32,
    /// Robot the motions are retargeted to (a `data/robots` name).
    pub robot: String,
    /// Joint order of every `joint_pos` tensor.
    pub joint_names: Vec<String>,
    /// Quaternion component order; always `wxyz`.
    pub quaternion: String,
    /// Frame of the stored hand forces; always `sensor`.
    pub force_frame: String,
    /// One entry per sequence file.
    pub sequences: Vec<ManifestEntry>,
}

/// One sequence of the manifest.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ManifestEntry {
    /// Path relative to the dataset directory.
    pub file: String,
    /// Task name.
    pub task: String,
    /// Sequence identifier.
    pub sequence_id: String,
    /// Frame rate, Hz.
    pub fps: f64,
    /// Number of frames.
    pub frames: usize,
    /// sha256 of the file, lowercase hex.
    pub sha256: String,
}

/// An opened, validated dataset; sequences are read (and checksummed) on demand.
#[derive(Debug, Clone)]
pub struct Dataset {
    /// The dataset directory.
    pub dir: PathBuf,
    /// Its manifest.
    pub manifest: Manifest,
}

/// The largest `manifest.json` read, bytes (64 MiB: a million sequences' entries).
pub const MAX_MANIFEST_BYTES: u64 = 64 << 20;

/// The largest sequence file read, bytes (1 GiB: hours of motion at 50 Hz).
pub const MAX_SEQUENCE_BYTES: u64 = 1 << 30;

impl Dataset {
    /// Opens `dir`, checking the manifest against the schema and the robot's joints.
    pub fn open(dir: &Path, robot: &RobotModel) -> Result<Self, DataError> {
        let path = dir.join(MANIFEST);
        let text =
            crate::files::bounded_read::read_to_string(&path, "manifest", MAX_MANIFEST_BYTES)
                .map_err(|source| DataError::Io {
                    path: path.clone(),
                    source,
                })?;
        let value: serde_json::Value = serde_json::from_str(&text)
            .map_err(|e| bad(&path, "(document)", format!("invalid JSON: {e}")))?;
        // The version is checked before the rest so that a newer manifest says so plainly.
        let found = value.get("schema_version").and_then(|v| v.as_u64());
        match found {
            Some(v) if v == SCHEMA_VERSION as u64 => {}
            Some(v) => {
                return Err(DataError::SchemaVersion {
                    path,
                    found: v,
                    supported: SCHEMA_VERSION,
                });
            }
            None => return Err(bad(&path, "schema_version", "missing or not an integer")),
        }
        let manifest: Manifest =
            serde_json::from_value(value).map_err(|e| bad(&path, "(document)", e.to_string()))?;
        if manifest.schema != SCHEMA_NAME {
            return Err(bad(
                &path,
                "schema",
                format!("`{}`, expected `{SCHEMA_NAME}`", manifest.schema),
            ));
        }
        if manifest.quaternion != "wxyz" || manifest.force_frame != "sensor" {
            return Err(bad(
                &path,
                "quaternion/force_frame",
                "must be `wxyz` and `sensor`",
            ));
        }
        if manifest.robot != robot.name {
            return Err(bad(
                &path,
                "robot",
                format!(
                    "`{}`, but the robot evaluated is `{}` (retarget the motions, or evaluate them on robot {})",
                    manifest.robot, robot.name, manifest.robot
                ),
            ));
        }
        check_joint_names(&path, "joint_names", &manifest.joint_names, robot)?;
        let mut seen = std::collections::HashSet::new();
        for (i, e) in manifest.sequences.iter().enumerate() {
            // Ids become file names (traces, exports, run directories).
            for (field, value) in [("task", &e.task), ("sequence_id", &e.sequence_id)] {
                crate::files::names::check_name(field, value)
                    .map_err(|n| bad(&path, format!("sequences[{i}].{field}"), n.to_string()))?;
            }
            if let Some(problem) = crate::sim::motion::fps_problem(e.fps) {
                return Err(bad(&path, format!("sequences[{i}].fps"), problem));
            }
            if !seen.insert((e.task.as_str(), e.sequence_id.as_str())) {
                return Err(bad(
                    &path,
                    format!("sequences[{i}]"),
                    format!("duplicate {}/{}", e.task, e.sequence_id),
                ));
            }
            if Path::new(&e.file).is_absolute() || e.file.split('/').any(|c| c == "..") {
                return Err(bad(
                    &path,
                    format!("sequences[{i}].file"),
                    "must be a relative path inside the dataset",
                ));
            }
        }
        Ok(Self {
            dir: dir.to_path_buf(),
            manifest,
        })
    }

    /// Number of sequences.
    pub fn len(&self) -> usize {
        self.manifest.sequences.len()
    }

    /// True when the dataset has no sequence.
    pub fn is_empty(&self) -> bool {
        self.manifest.sequences.is_empty()
    }

    /// Reads sequence `i`, verifying its checksum and its agreement with the manifest.
    pub fn load(&self, i: usize) -> Result<Sequence, DataError> {
        let e = &self.manifest.sequences[i];
        let path = self.dir.join(&e.file);
        let bytes = crate::files::bounded_read::read(&path, "sequence file", MAX_SEQUENCE_BYTES)
            .map_err(|source| DataError::Io {
                path: path.clone(),
                source,
            })?;
        let actual = sha256_hex(&bytes);
        if actual != e.sha256 {
            return Err(DataError::Checksum {
                path,
                expected: e.sha256.clone(),
                actual,
            });
        }
        let seq = decode_sequence(&bytes, &path)?;
        let mismatch = |field: &str, what: String| {
            Err(bad(
                &path,
                field,
                format!("{what} (manifest entry {i} disagrees)"),
            ))
        };
        if seq.task != e.task || seq.sequence_id != e.sequence_id {
            return mismatch(
                "task/sequence_id",
                format!("{}/{}", seq.task, seq.sequence_id),
            );
        }
        if seq.fps != e.fps {
            return mismatch("fps", format!("{}", seq.fps));
        }
        if seq.n_frames() != e.frames {
            return mismatch("frames", format!("{}", seq.n_frames()));
        }
        if seq.joint_names != self.manifest.joint_names {
            return mismatch("joint_names", "a different joint order".into());
        }
        Ok(seq)
    }

    /// Reads every sequence, in manifest order.
    pub fn load_all(&self) -> Result<Vec<Sequence>, DataError> {
        (0..self.len()).map(|i| self.load(i)).collect()
    }

    /// sha256 over the manifest's sequence checksums: identifies the dataset's content.
    pub fn content_hash(&self) -> String {
        let joined: String = self
            .manifest
            .sequences
            .iter()
            .map(|e| format!("{}:{}\n", e.file, e.sha256))
            .collect();
        sha256_hex(joined.as_bytes())
    }
}

fn check_joint_names(
    path: &Path,
    field: &str,
    names: &[String],
    robot: &RobotModel,
) -> Result<(), DataError> {
    for (i, n) in names.iter().enumerate() {
        if robot.joint_index(n).is_none() {
            return Err(bad(
                path,
                format!("{field}[{i}]"),
                format!("unknown joint `{n}` for robot {}", robot.name),
            ));
        }
    }
    let missing: Vec<&str> = robot
        .joints
        .iter()
        .filter(|j| !names.contains(&j.name))
        .map(|j| j.name.as_str())
        .collect();
    if !missing.is_empty() {
        return Err(bad(
            path,
            field,
            format!("missing joints: {}", missing.join(", ")),
        ));
    }
    if names.len() != robot.n_joints() {
        return Err(bad(
            path,
            field,
            format!(
                "{} names for a {}-joint robot (duplicates?)",
                names.len(),
                robot.n_joints()
            ),
        ));
    }
    Ok(())
}

/// Writes a dataset: sequence files as they are added, the manifest at the end.
pub struct DatasetWriter {
    dir: PathBuf,
    manifest: Manifest,
}

impl DatasetWriter {
    /// Starts a new dataset in `dir` for `robot` (the directory may not hold a manifest yet).
    pub fn create(dir: &Path, robot: &RobotModel) -> Result<Self, DataError> {
        let path = dir.join(MANIFEST);
        if path.exists() {
            return Err(bad(
                &path,
                "(file)",
                "a dataset exists here already (use append)",
            ));
        }
        let manifest = Manifest {
            schema: SCHEMA_NAME.into(),
            schema_version: SCHEMA_VERSION,
            robot: robot.name.clone(),
            joint_names: robot.joints.iter().map(|j| j.name.clone()).collect(),
            quaternion: "wxyz".into(),
            force_frame: "sensor".into(),
            sequences: Vec::new(),
        };
        Ok(Self {
            dir: dir.to_path_buf(),
            manifest,
        })
    }

    /// Continues an existing dataset (or starts one when `dir` has no manifest).
    pub fn append(dir: &Path, robot: &RobotModel) -> Result<Self, DataError> {
        if dir.join(MANIFEST).exists() {
            let ds = Dataset::open(dir, robot)?;
            if ds.manifest.robot != robot.name {
                return Err(bad(
                    &dir.join(MANIFEST),
                    "robot",
                    format!("`{}`, not `{}`", ds.manifest.robot, robot.name),
                ));
            }
            Ok(Self {
                dir: ds.dir,
                manifest: ds.manifest,
            })
        } else {
            Self::create(dir, robot)
        }
    }

    /// Whether the dataset already has `task`/`sequence_id`.
    pub fn contains(&self, task: &str, sequence_id: &str) -> bool {
        self.manifest
            .sequences
            .iter()
            .any(|e| e.task == task && e.sequence_id == sequence_id)
    }

    /// Writes `seq` to `<task>/<sequence_id>.safetensors` and records it.
    pub fn add(&mut self, seq: &Sequence) -> Result<(), DataError> {
        for (field, value) in [("task", &seq.task), ("sequence_id", &seq.sequence_id)] {
            crate::files::names::check_name(field, value)
                .map_err(|n| bad(&self.dir.join(MANIFEST), field, n.to_string()))?;
        }
        let file = format!("{}/{}.safetensors", seq.task, seq.sequence_id);
        let path = self.dir.join(&file);
        if self
            .manifest
            .sequences
            .iter()
            .any(|e| e.task == seq.task && e.sequence_id == seq.sequence_id)
        {
            return Err(bad(
                &path,
                "sequence_id",
                format!("{}/{} is already in the dataset", seq.task, seq.sequence_id),
            ));
        }
        if seq.joint_names != self.manifest.joint_names {
            return Err(bad(&path, "joint_names", "not the dataset's joint order"));
        }
        let sha256 = write_sequence(seq, &path)?;
        self.manifest.sequences.push(ManifestEntry {
            file,
            task: seq.task.clone(),
            sequence_id: seq.sequence_id.clone(),
            fps: seq.fps,
            frames: seq.n_frames(),
            sha256,
        });
        Ok(())
    }

    /// Writes the manifest (entries sorted by task, then id) and returns the dataset.
    pub fn finish(mut self) -> Result<Dataset, DataError> {
        self.manifest
            .sequences
            .sort_by(|a, b| (&a.task, &a.sequence_id).cmp(&(&b.task, &b.sequence_id)));
        let path = self.dir.join(MANIFEST);
        let mut text = serde_json::to_string_pretty(&self.manifest)
            .map_err(|e| bad(&path, "(document)", e.to_string()))?;
        text.push('\n');
        crate::files::atomic_file::write(&path, text).map_err(|source| DataError::Io {
            path: path.clone(),
            source,
        })?;
        Ok(Dataset {
            dir: self.dir,
            manifest: self.manifest,
        })
    }
}
