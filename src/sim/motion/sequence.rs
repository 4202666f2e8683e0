//! One canonical motion–force sequence in memory, and its validation.

use super::error::{bad, DataError};
use std::path::Path;

/// Largest accepted deviation of a stored quaternion's norm from 1.
pub const QUAT_NORM_TOLERANCE: f64 = 1e-3;

/// Index of the left and right hand in per-side arrays.
pub const LEFT: usize = 0;
/// See [`LEFT`].
pub const RIGHT: usize = 1;

/// The frame a sequence's hand forces are stored in.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ForceFrame {
    /// Each hand's sensor frame: replayed through the simulated hand's pose at each step,
    /// so the force turns with the hand, as a held object's reaction does.
    #[default]
    Sensor,
    /// The world frame of the sequence's own reference: replayed as it is, whatever the
    /// simulated hand does.
    World,
}

impl ForceFrame {
    /// True for [`ForceFrame::Sensor`] (the default, left out of files).
    pub fn is_sensor(&self) -> bool {
        *self == Self::Sensor
    }
}

/// A reference motion with the two hand forces recorded with it, at its own frame rate.
///
/// Frames are uniformly spaced at `fps`; frame `k` is at `k / fps` seconds. Hand forces are
/// what the environment exerts on the robot's hand, in each hand's sensor frame
/// (or, for a grafted history, the world's: [`ForceFrame`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Sequence {
    /// Task name (e.g. `push_chair`).
    pub task: String,
    /// Sequence identifier, unique within the task.
    pub sequence_id: String,
    /// Frame rate, Hz.
    pub fps: f64,
    /// Joint names of the `joint_pos` columns (the robot's canonical order).
    pub joint_names: Vec<String>,
    /// Root (pelvis) position, world frame, m, z up; one per frame.
    pub root_pos: Vec<[f64; 3]>,
    /// Root orientation (w, x, y, z); one per frame.
    pub root_quat_wxyz: Vec<[f64; 4]>,
    /// Joint angles, rad; one row per frame.
    pub joint_pos: Vec<Vec<f64>>,
    /// Joint velocities, rad/s, if the source had them.
    pub joint_vel: Option<Vec<Vec<f64>>>,
    /// Left and right hand force, N, in each hand's sensor frame (or in the world, when
    /// `force_frame` says so); one per frame each.
    pub force_sensor: [Vec<[f64; 3]>; 2],
    /// The frame `force_sensor` is in: the sensors' (a recording), or the world's (a force
    /// history grafted from another motion, which keeps its direction whatever the hands do).
    pub force_frame: ForceFrame,
    /// Per side rotation from sensor to hand frame (w, x, y, z).
    pub hand_from_sensor_wxyz: [[f64; 4]; 2],
    /// Per side force application point in the hand frame, m.
    pub force_point_hand: [[f64; 3]; 2],
    /// False when the source had no force recording (forces are then zero).
    pub forces_recorded: bool,
    /// Where the data came from and what was done to it (JSON object).
    pub provenance: serde_json::Value,
}

impl Sequence {
    /// Number of frames.
    pub fn n_frames(&self) -> usize {
        self.root_pos.len()
    }

    /// Duration from the first to the last frame, s.
    pub fn duration_s(&self) -> f64 {
        self.n_frames().saturating_sub(1) as f64 / self.fps
    }

    /// Checks every invariant of the format; `file` names the source in errors. Hand
    /// forces are held to the import bound
    /// ([`crate::sim::motion::import::bounds::MAX_HAND_FORCE_N`]) here, so a dataset file
    /// holding one beyond it is refused on load as on import.
    pub fn validate(&self, file: &Path) -> Result<(), DataError> {
        let t = self.n_frames();
        if let Some(problem) = crate::sim::motion::fps_problem(self.fps) {
            return Err(bad(file, "fps", problem));
        }
        if t < 2 {
            return Err(bad(
                file,
                "root_pos",
                format!("needs at least 2 frames, has {t}"),
            ));
        }
        if self.task.is_empty() || self.sequence_id.is_empty() {
            return Err(bad(file, "task/sequence_id", "must not be empty"));
        }
        let j = self.joint_names.len();
        let lengths = [
            ("root_quat_wxyz", self.root_quat_wxyz.len()),
            ("joint_pos", self.joint_pos.len()),
            ("force_left_sensor", self.force_sensor[LEFT].len()),
            ("force_right_sensor", self.force_sensor[RIGHT].len()),
        ];
        for (name, n) in lengths {
            if n != t {
                return Err(bad(file, name, format!("{n} frames, but root_pos has {t}")));
            }
        }
        check_rows(file, "joint_pos", &self.joint_pos, j)?;
        if let Some(v) = &self.joint_vel {
            if v.len() != t {
                return Err(bad(
                    file,
                    "joint_vel",
                    format!("{} frames, but root_pos has {t}", v.len()),
                ));
            }
            check_rows(file, "joint_vel", v, j)?;
        }
        check_finite(file, "root_pos", self.root_pos.iter().flatten())?;
        check_finite(file, "root_quat_wxyz", self.root_quat_wxyz.iter().flatten())?;
        for (k, q) in self.root_quat_wxyz.iter().enumerate() {
            let n = q.iter().map(|x| x * x).sum::<f64>().sqrt();
            if (n - 1.0).abs() > QUAT_NORM_TOLERANCE {
                return Err(bad(
                    file,
                    "root_quat_wxyz",
                    format!(
                        "frame {k}: root quaternion norm {n:.6} is off unit by more than {QUAT_NORM_TOLERANCE}"
                    ),
                ));
            }
        }
        for (side, name) in [(LEFT, "force_left_sensor"), (RIGHT, "force_right_sensor")] {
            check_finite(file, name, self.force_sensor[side].iter().flatten())?;
            for (k, f) in self.force_sensor[side].iter().enumerate() {
                if let Some(why) = super::import::bounds::hand_force_problem(f) {
                    return Err(bad(file, name, format!("frame {k}: {why}")));
                }
            }
        }
        for side in [LEFT, RIGHT] {
            let q = self.hand_from_sensor_wxyz[side];
            let n = q.iter().map(|x| x * x).sum::<f64>().sqrt();
            if !n.is_finite() || (n - 1.0).abs() > QUAT_NORM_TOLERANCE {
                return Err(bad(
                    file,
                    "hand_from_sensor_wxyz",
                    format!("side {side}: not a unit quaternion"),
                ));
            }
            check_finite(file, "force_point_hand", self.force_point_hand[side].iter())?;
        }
        Ok(())
    }
}

fn check_rows(file: &Path, name: &str, rows: &[Vec<f64>], width: usize) -> Result<(), DataError> {
    for (k, row) in rows.iter().enumerate() {
        if row.len() != width {
            return Err(bad(
                file,
                name,
                format!(
                    "frame {k} has {} values, expected {width} (one per joint)",
                    row.len()
                ),
            ));
        }
        for (c, v) in row.iter().enumerate() {
            if !storable(*v) {
                return Err(bad(
                    file,
                    name,
                    format!(
                        "frame {k}, column {c} is {}: {}",
                        crate::files::names::short_number(*v),
                        NOT_STORABLE
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Why a value is refused: sequence files store float32, so a finite f64 beyond its range
/// would be written as infinity and leave the dataset unreadable.
const NOT_STORABLE: &str = "not a finite number a float32 sequence file can hold";

/// Finite, and finite still as the float32 a sequence file stores.
fn storable(v: f64) -> bool {
    v.is_finite() && v.abs() <= f64::from(f32::MAX)
}

fn check_finite<'a>(
    file: &Path,
    name: &str,
    values: impl Iterator<Item = &'a f64>,
) -> Result<(), DataError> {
    for (i, v) in values.enumerate() {
        if !storable(*v) {
            return Err(bad(
                file,
                name,
                format!(
                    "element {i} is {}: {NOT_STORABLE}",
                    crate::files::names::short_number(*v)
                ),
            ));
        }
    }
    Ok(())
}
