//! An episode's simulated motion as a dataset sequence: the root pose and joint angles the
//! robot really had at each control step, with the hand forces that really acted on it
//! (`eval --trace` records both), written as a canonical dataset
//! (`thorarena data import --format rollout`).
//!
//! A rollout is motion a simulator produced under the forces it lists, so `data check` on
//! it measures the check's own floor — what differentiating positions twice at the control
//! rate leaves — and peer tools get the root pose for their own metrics.
//!
//! The trace holds world-frame forces; a sequence stores sensor-frame ones with a
//! calibration. The rollout's sensor frame is its hand frame (identity calibration, force
//! point at the hand frame's origin), and each force is rotated into it through the
//! rollout's own hand pose at that step, so replaying the sequence on its own motion gives
//! back the world forces of the trace.

use crate::eval::episode::TraceStep;
use crate::sim::motion::{DataError, Dataset, DatasetWriter, Sequence, LEFT, RIGHT};
use crate::sim::robot::{forward_kinematics, RobotModel};
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3};
use std::path::{Path, PathBuf};

/// Why a trace cannot become a sequence.
#[derive(Debug, thiserror::Error)]
pub enum RolloutError {
    /// The trace file could not be read or is not a trace.
    #[error("reading a trace written by `eval --trace`: {0}")]
    Read(#[from] crate::eval::results::ResultsError),
    /// The trace cannot make a sequence.
    #[error("{path}: {reason}")]
    Unusable {
        /// The file.
        path: PathBuf,
        /// Why.
        reason: String,
    },
    /// Writing the dataset failed.
    #[error(transparent)]
    Data(#[from] DataError),
}

/// The sequence of a rollout's trace steps, at the trace's own (control) rate.
/// `path` names the trace in errors.
pub fn rollout_sequence(
    steps: &[TraceStep],
    robot: &RobotModel,
    task: &str,
    sequence_id: &str,
    path: &Path,
) -> Result<Sequence, RolloutError> {
    let unusable = |reason: String| RolloutError::Unusable {
        path: path.to_path_buf(),
        reason,
    };
    if steps.len() < 2 {
        return Err(unusable(format!(
            "{} steps; a sequence needs at least 2",
            steps.len()
        )));
    }
    let dt = steps[1].time_s - steps[0].time_s;
    let uniform = steps
        .windows(2)
        .all(|w| ((w[1].time_s - w[0].time_s) - dt).abs() <= 1e-6 * dt.abs().max(1e-9));
    if !(dt > 0.0 && uniform) {
        return Err(unusable(
            "its steps are not evenly spaced in time (a trace of one control rate is)".into(),
        ));
    }
    if let Some(k) = steps.iter().position(|s| s.q.len() != robot.n_joints()) {
        return Err(unusable(format!(
            "step {k} has {} joint angles; robot `{}` has {}",
            steps[k].q.len(),
            robot.name,
            robot.n_joints()
        )));
    }
    check_steps(steps, robot).map_err(unusable)?;
    let mut poses = Vec::new();
    let mut force_sensor = [Vec::new(), Vec::new()];
    for s in steps {
        let q = s.root_quat_wxyz;
        let world_from_root = Isometry3::from_parts(
            Translation3::from(Vector3::from(s.root_pos)),
            UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3])),
        );
        forward_kinematics(robot, &world_from_root, &s.q, &mut poses);
        for side in [LEFT, RIGHT] {
            let frame = &robot.frames[robot.hands[side].frame];
            let world_from_hand = poses[frame.body] * frame.body_from_frame;
            let f = world_from_hand
                .rotation
                .inverse_transform_vector(&Vector3::from(s.hand_force_w[side]));
            force_sensor[side].push([f.x, f.y, f.z]);
        }
    }
    let seq = Sequence {
        task: task.to_string(),
        sequence_id: sequence_id.to_string(),
        fps: 1.0 / dt,
        joint_names: robot.joints.iter().map(|j| j.name.clone()).collect(),
        root_pos: steps.iter().map(|s| s.root_pos).collect(),
        root_quat_wxyz: steps.iter().map(|s| s.root_quat_wxyz).collect(),
        joint_pos: steps.iter().map(|s| s.q.clone()).collect(),
        joint_vel: None,
        forces_recorded: steps
            .iter()
            .any(|s| s.hand_force_w.iter().flatten().any(|f| *f != 0.0)),
        force_sensor,
        hand_from_sensor_wxyz: [[1.0, 0.0, 0.0, 0.0]; 2],
        force_frame: Default::default(),
        force_point_hand: [[0.0; 3]; 2],
        provenance: serde_json::json!({
            "format": "rollout",
            "file": path.display().to_string(),
            "note": "simulated motion from `eval --trace`: root pose and joints as simulated, hand forces as applied (world → hand frame through the rollout's own hand pose)",
        }),
    };
    seq.validate(path)?;
    Ok(seq)
}

/// Holds a trace's steps to the bounds every import meets
/// ([`crate::sim::motion::import::bounds`]): a root quaternion that is a rotation, joint
/// angles within their limits widened as for motion files, and hand forces within the
/// plausibility bound; the refusal names the step and the field.
fn check_steps(steps: &[TraceStep], robot: &RobotModel) -> Result<(), String> {
    use crate::sim::motion::import::bounds;
    for (k, s) in steps.iter().enumerate() {
        if let Some(why) = bounds::rotation_problem(&s.root_quat_wxyz) {
            return Err(format!("step {k}, field `root_quat_wxyz`: {why}"));
        }
        if let Some(why) = robot
            .joints
            .iter()
            .zip(&s.q)
            .find_map(|(j, v)| bounds::joint_angle_problem(j, *v))
        {
            return Err(format!("step {k}, field `q`: {why}"));
        }
        for (side, f) in s.hand_force_w.iter().enumerate() {
            if let Some(why) = bounds::hand_force_problem(f) {
                let hand = if side == LEFT { "left" } else { "right" };
                return Err(format!("step {k}, field `hand_force_w` ({hand}): {why}"));
            }
        }
    }
    Ok(())
}

/// Writes the rollouts of `traces` into the dataset `out` (created, or appended to when it
/// holds one), all under `task`, each named after its file's stem; all or nothing.
pub fn import_rollouts(
    traces: &[PathBuf],
    out: &Path,
    task: &str,
    robot: &RobotModel,
) -> Result<Dataset, RolloutError> {
    let mut seqs = Vec::with_capacity(traces.len());
    for path in traces {
        let id = path
            .file_stem()
            .map(|s| s.to_string_lossy().to_string())
            .unwrap_or_default();
        let steps = crate::eval::results::RunDir::read_trace(path)?;
        seqs.push(rollout_sequence(&steps, robot, task, &id, path)?);
    }
    let mut writer = if out.join(crate::sim::motion::MANIFEST).is_file() {
        DatasetWriter::append(out, robot)?
    } else {
        DatasetWriter::create(out, robot)?
    };
    for s in &seqs {
        writer.add(s)?;
    }
    Ok(writer.finish()?)
}

/// What `thorarena data import` reads into a dataset: motion files of one format with
/// their force logs, or rollout traces, whose forces are the ones that acted.
#[derive(Debug, Clone)]
pub enum DataImport {
    /// Motion files ([`crate::sim::motion::import::import_batch`]).
    Motions(crate::sim::motion::import::ImportBatch),
    /// Traces of `eval --trace` ([`import_rollouts`]), all under `task`.
    Rollouts {
        /// The trace files.
        traces: Vec<PathBuf>,
        /// The task they are filed under.
        task: String,
    },
}

/// Why a `data import` failed.
#[derive(Debug, thiserror::Error)]
pub enum DataImportError {
    /// Motion files.
    #[error(transparent)]
    Motions(#[from] crate::sim::motion::import::BatchError),
    /// Rollout traces.
    #[error(transparent)]
    Rollouts(#[from] RolloutError),
}

/// Writes `what` into the dataset `out` (created, or appended to), telling `observer` about
/// each motion file; all or nothing.
pub fn import_data(
    out: &Path,
    robot: &RobotModel,
    what: &DataImport,
    observer: &mut dyn crate::sim::motion::import::ImportObserver,
) -> Result<Dataset, DataImportError> {
    Ok(match what {
        DataImport::Motions(batch) => {
            crate::sim::motion::import::import_batch(out, robot, batch, observer)?
        }
        DataImport::Rollouts { traces, task } => import_rollouts(traces, out, task, robot)?,
    })
}
