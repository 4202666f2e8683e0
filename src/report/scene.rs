//! The data of `thorarena view`: the robot's collision shapes per body, and per step the
//! world pose of every body — for the robot and for the reference ghost — computed here
//! with the same forward kinematics the metrics use, so the page draws exactly what was
//! scored and needs no kinematics of its own.

use super::ReportError;
use crate::eval::episode::TraceStep;
use crate::eval::results::{read_header, EpisodeLog, RunHeader, EPISODES_FILE};
use crate::eval::EpisodeRecord;
use crate::sim::robot::{forward_kinematics, frame_pose, Geometry, RobotModel};
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};
use serde::Serialize;
use std::path::Path;

/// One primitive collision shape, posed in its body frame.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ShapeView {
    /// `box`, `sphere`, `capsule` or `cylinder` (capsules and cylinders along local z).
    pub kind: &'static str,
    /// Box: half extents (x, y, z); sphere: (radius, 0, 0); capsule and cylinder:
    /// (radius, half length, 0); m.
    pub size: [f64; 3],
    /// Position in the body frame, m.
    pub pos: [f64; 3],
    /// Orientation in the body frame, (x, y, z, w) as three.js orders it.
    pub quat_xyzw: [f64; 4],
    /// A foot sole contact sphere (drawn in another colour).
    pub sole: bool,
}

/// A body's name and shapes.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BodyShapes {
    /// The moving URDF link's name.
    pub name: String,
    /// Its collision shapes (merged fixed links included).
    pub shapes: Vec<ShapeView>,
}

/// Everything the viewer page draws, step by step.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ViewScene {
    /// Page title.
    pub title: String,
    /// Labelled facts about the episode (policy, setting, how it ended, …).
    pub info: Vec<(String, String)>,
    /// Robot name.
    pub robot: String,
    /// Bodies in the robot model's order.
    pub bodies: Vec<BodyShapes>,
    /// Time of each step, s.
    pub time_s: Vec<f64>,
    /// Per step, per body: world pose as (x, y, z, qx, qy, qz, qw), flattened.
    pub robot_poses: Vec<Vec<f64>>,
    /// Per step, per body: the reference's world pose (same layout), where it is — not
    /// re-anchored. `None` for traces written before they carried the reference joints.
    pub reference_poses: Option<Vec<Vec<f64>>>,
    /// Per step: the metric's re-anchoring transform `robot root · reference root⁻¹`
    /// (x, y, z, qx, qy, qz, qw); applied to the reference poses it puts the ghost where
    /// the keypoint error compares it.
    pub anchor: Option<Vec<[f64; 7]>>,
    /// Per step: force application points of the (left, right) hand, world, m.
    pub hand_points_w: Vec<[[f64; 3]; 2]>,
    /// Per step: replayed (left, right) hand force, world, N.
    pub hand_force_w: Vec<[[f64; 3]; 2]>,
    /// Per step: robot keypoints, world, m.
    pub keypoints_w: Vec<Vec<[f64; 3]>>,
    /// Per step: re-anchored reference keypoints, world, m.
    pub reference_keypoints_w: Vec<Vec<[f64; 3]>>,
    /// Per step: keypoint error, mm.
    pub kp_err_mm: Vec<f64>,
    /// The feet on the ground, when the trace has them.
    pub feet: Option<FeetView>,
}

/// The feet's ground contact, step by step (see [`crate::sim::feet::FootContact`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FeetView {
    /// The feet's body names.
    pub names: Vec<String>,
    /// Per step, per foot: load-weighted sliding speed of its sole points, m/s.
    pub slip_speed_mps: Vec<Vec<f64>>,
    /// Per step, per foot: slip accumulated since the start, m.
    pub slip_m: Vec<Vec<f64>>,
    /// Per step, per foot: normal force, N.
    pub normal_n: Vec<Vec<f64>>,
    /// Per step, per foot: the ground's whole reaction (normal + friction), world, N.
    pub reaction_w: Vec<Vec<[f64; 3]>>,
    /// Per step, per foot: centre of pressure, world, m (`None` without load).
    pub cop_w: Vec<Vec<Option<[f64; 3]>>>,
}

/// The feet's view of a trace whose every step has the same feet; `None` otherwise.
fn feet_view(trace: &[TraceStep]) -> Option<FeetView> {
    let first = trace.first()?.feet.as_ref()?;
    let names: Vec<String> = first.iter().map(|f| f.body.clone()).collect();
    let same = |s: &TraceStep| {
        s.feet.as_ref().is_some_and(|f| {
            f.len() == names.len() && f.iter().zip(&names).all(|(f, n)| &f.body == n)
        })
    };
    if names.is_empty() || !trace.iter().all(same) {
        return None;
    }
    let per = |f: &dyn Fn(&crate::sim::feet::FootContact) -> f64| -> Vec<Vec<f64>> {
        trace
            .iter()
            .map(|s| {
                s.feet
                    .iter()
                    .flatten()
                    .map(|c| (f(c) * 1e4).round() / 1e4)
                    .collect()
            })
            .collect()
    };
    Some(FeetView {
        slip_speed_mps: per(&|c| c.slip_speed_mps),
        slip_m: per(&|c| c.slip_m),
        normal_n: per(&|c| c.normal_n),
        reaction_w: trace
            .iter()
            .map(|s| {
                s.feet
                    .iter()
                    .flatten()
                    .map(|c| {
                        [
                            c.friction_w[0],
                            c.friction_w[1],
                            c.friction_w[2] + c.normal_n,
                        ]
                        .map(r4)
                    })
                    .collect()
            })
            .collect(),
        cop_w: trace
            .iter()
            .map(|s| {
                s.feet
                    .iter()
                    .flatten()
                    .map(|c| c.cop_w.map(|p| p.map(r4)))
                    .collect()
            })
            .collect(),
        names,
    })
}

/// What the run directory around a trace says about its episode (when the trace sits in
/// `<run>/traces/`).
#[derive(Debug, Clone, Default)]
pub struct TraceContext {
    /// The run's `run.json`.
    pub header: Option<RunHeader>,
    /// The episode's record in `episodes.jsonl`.
    pub record: Option<EpisodeRecord>,
}

/// Reads a trace file written by `eval --trace`.
pub fn load_trace(path: &Path) -> Result<Vec<TraceStep>, ReportError> {
    use crate::eval::results::{ResultsError, RunDir};
    RunDir::read_trace(path).map_err(|e| match e {
        ResultsError::Io { path, source } => ReportError::Io { path, source },
        ResultsError::Json { path, source, .. } => ReportError::Json { path, source },
        other => ReportError::BadTrace {
            path: path.to_path_buf(),
            reason: other.to_string(),
        },
    })
}

/// Finds the run around a trace (`<run>/traces/<task>-<id>-<setting>.json`) and its
/// episode record; anything missing is left out (a trace may have been copied elsewhere).
pub fn trace_context(trace: &Path) -> TraceContext {
    let Some(run) = trace.parent().and_then(Path::parent) else {
        return TraceContext::default();
    };
    let header: Option<RunHeader> = read_header(run).ok();
    let stem = trace.file_stem().map(|s| s.to_string_lossy().to_string());
    let record = header
        .as_ref()
        .and_then(|h| EpisodeLog::read(&run.join(EPISODES_FILE), h).ok())
        .and_then(|log| {
            log.records.into_iter().find(|r| {
                stem.as_deref() == Some(&format!("{}-{}-{}", r.task, r.sequence_id, r.setting))
            })
        });
    TraceContext { header, record }
}

/// Rounds for the page: 0.1 mm and 1e-4 in quaternions are below what a screen shows,
/// and keep a 30 s episode's page a few megabytes.
fn r4(x: f64) -> f64 {
    (x * 1e4).round() / 1e4
}

fn pose7(p: &Isometry3<f64>) -> [f64; 7] {
    let t = p.translation.vector;
    let q = p.rotation;
    [t.x, t.y, t.z, q.i, q.j, q.k, q.w].map(r4)
}

fn isometry(pos: [f64; 3], wxyz: [f64; 4]) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(pos[0], pos[1], pos[2]),
        UnitQuaternion::from_quaternion(Quaternion::new(wxyz[0], wxyz[1], wxyz[2], wxyz[3])),
    )
}

fn shape_view(s: &crate::sim::robot::Shape) -> ShapeView {
    let (kind, size) = match s.geometry {
        Geometry::Box { half_extents } => ("box", half_extents),
        Geometry::Sphere { radius } => ("sphere", [radius, 0.0, 0.0]),
        Geometry::Capsule {
            radius,
            half_length,
        } => ("capsule", [radius, half_length, 0.0]),
        Geometry::Cylinder {
            radius,
            half_length,
        } => ("cylinder", [radius, half_length, 0.0]),
    };
    let p = pose7(&s.body_from_shape);
    ShapeView {
        kind,
        size,
        pos: [p[0], p[1], p[2]],
        quat_xyzw: [p[3], p[4], p[5], p[6]],
        sole: s.is_sole,
    }
}

/// Builds the viewer's scene from a trace: body poses of the robot (root pose and q of
/// each step) and of the reference (its root pose and joints, when the trace has them),
/// hand force arrows at the hands' force points, keypoints and the error series.
pub fn view_scene(
    robot: &RobotModel,
    trace: &[TraceStep],
    trace_path: &Path,
    context: &TraceContext,
) -> Result<ViewScene, ReportError> {
    let bad = |reason: String| ReportError::BadTrace {
        path: trace_path.to_path_buf(),
        reason,
    };
    if trace.is_empty() {
        return Err(bad("no step recorded".into()));
    }
    let n = robot.n_joints();
    if let Some((k, s)) = trace
        .iter()
        .enumerate()
        .find(|(_, s)| s.q.len() != n || s.reference_q.as_ref().is_some_and(|q| q.len() != n))
    {
        return Err(bad(format!(
            "step {k} has {} joint angles, robot {} has {n} (a trace of another robot?)",
            s.q.len(),
            robot.name
        )));
    }
    let with_reference = trace.iter().all(|s| {
        s.reference_q.is_some()
            && s.reference_root_pos.is_some()
            && s.reference_root_quat_wxyz.is_some()
    });
    let posed = pose_trace(robot, trace, with_reference);
    let round3 = |v: &[f64; 3]| v.map(r4);
    let points = |v: &[[f64; 3]]| v.iter().map(round3).collect::<Vec<_>>();
    let stem = trace_path
        .file_stem()
        .map_or_else(|| "trace".to_string(), |s| s.to_string_lossy().to_string());
    let info = scene_info(robot, trace, context, with_reference);
    Ok(ViewScene {
        title: format!("ThorArena replay — {stem}"),
        info,
        robot: robot.name.clone(),
        bodies: robot
            .bodies
            .iter()
            .map(|b| BodyShapes {
                name: b.name.clone(),
                shapes: b.shapes.iter().map(shape_view).collect(),
            })
            .collect(),
        time_s: trace.iter().map(|s| r4(s.time_s)).collect(),
        robot_poses: posed.robot,
        reference_poses: with_reference.then_some(posed.reference),
        anchor: with_reference.then_some(posed.anchor),
        hand_points_w: posed.hand_points_w,
        hand_force_w: trace
            .iter()
            .map(|s| s.hand_force_w.map(|f| f.map(r4)))
            .collect(),
        keypoints_w: trace.iter().map(|s| points(&s.keypoints_w)).collect(),
        reference_keypoints_w: trace
            .iter()
            .map(|s| points(&s.reference_keypoints_w))
            .collect(),
        kp_err_mm: trace
            .iter()
            .map(|s| (s.kp_err_m * 1e5).round() / 1e2)
            .collect(),
        feet: feet_view(trace),
    })
}

/// A trace's bodies posed by forward kinematics, step by step.
struct PosedTrace {
    /// The robot's body poses (7 numbers each: position, quaternion).
    robot: Vec<Vec<f64>>,
    /// The hands' force points, world frame, m.
    hand_points_w: Vec<[[f64; 3]; 2]>,
    /// The reference's body poses (empty without reference joints).
    reference: Vec<Vec<f64>>,
    /// Robot root from reference root (empty without reference joints).
    anchor: Vec<[f64; 7]>,
}

fn pose_trace(robot: &RobotModel, trace: &[TraceStep], with_reference: bool) -> PosedTrace {
    let mut poses = Vec::new();
    let mut robot_poses = Vec::with_capacity(trace.len());
    let mut hand_points_w = Vec::with_capacity(trace.len());
    let mut reference_poses = Vec::new();
    let mut anchor = Vec::new();
    for s in trace {
        let root = isometry(s.root_pos, s.root_quat_wxyz);
        forward_kinematics(robot, &root, &s.q, &mut poses);
        robot_poses.push(poses.iter().flat_map(pose7).collect());
        hand_points_w.push(robot.hands.clone().map(|h| {
            let p = frame_pose(robot, &poses, h.frame) * h.point_hand;
            [p.x, p.y, p.z].map(r4)
        }));
        if with_reference {
            let (pos, quat, q) = (
                s.reference_root_pos.expect("checked"),
                s.reference_root_quat_wxyz.expect("checked"),
                s.reference_q.as_ref().expect("checked"),
            );
            let ref_root = isometry(pos, quat);
            forward_kinematics(robot, &ref_root, q, &mut poses);
            reference_poses.push(poses.iter().flat_map(pose7).collect());
            anchor.push(pose7(&(root * ref_root.inverse())));
        }
    }
    PosedTrace {
        robot: robot_poses,
        hand_points_w,
        reference: reference_poses,
        anchor,
    }
}

/// The replay's side panel: the run, the episode and how it ended.
fn scene_info(
    robot: &RobotModel,
    trace: &[TraceStep],
    context: &TraceContext,
    with_reference: bool,
) -> Vec<(String, String)> {
    let mut info = Vec::new();
    if let Some(h) = &context.header {
        info.push(("policy".to_string(), h.policy.clone()));
        info.push(("profile".to_string(), h.profile.clone()));
        info.push(("engine".to_string(), h.engine_label()));
        info.push(("dataset".to_string(), h.dataset.clone()));
    }
    if let Some(r) = &context.record {
        info.push(("task".into(), r.task.clone()));
        info.push(("sequence".into(), r.sequence_id.clone()));
        info.push((
            "setting".into(),
            format!("{} (force ×{})", r.setting, r.coefficient),
        ));
        let ended = match r.termination {
            Some(t) => format!(
                "terminated ({}) after {} of {} steps",
                serde_json::to_value(t)
                    .ok()
                    .and_then(|v| v.as_str().map(str::to_string))
                    .unwrap_or_default(),
                r.series.kp_err_m.len(),
                r.series.steps_ref
            ),
            None => format!("completed all {} steps", r.series.steps_ref),
        };
        info.push(("episode".into(), ended));
    }
    info.push(("robot".into(), robot.name.clone()));
    info.push(("steps".into(), trace.len().to_string()));
    let mean_err = trace.iter().map(|s| s.kp_err_m).sum::<f64>() / trace.len() as f64;
    info.push((
        "mean keypoint error".into(),
        format!("{:.1} mm", mean_err * 1e3),
    ));
    if !with_reference {
        info.push((
            "reference".into(),
            "keypoints only (trace written before traces carried reference joints)".into(),
        ));
    }
    info
}

/// A written replay page.
#[derive(Debug)]
pub struct WrittenView {
    /// Steps of the trace.
    pub steps: usize,
    /// Whether the reference shows as a ghost robot (else as keypoints: the trace has no
    /// reference joints).
    pub reference_ghost: bool,
}

/// Writes the replay page of trace `trace_path` for `robot` to `out` (never over the
/// trace, nor, unless `overwrite`, over a run's or a dataset's file), with `bundle`'s
/// script.
pub fn write_view(
    trace_path: &Path,
    robot: &RobotModel,
    bundle: &super::WebBundle,
    out: &Path,
    overwrite: bool,
) -> Result<WrittenView, ReportError> {
    crate::eval::results::check_file(out, overwrite, &[trace_path.to_path_buf()])?;
    let trace = load_trace(trace_path)?;
    let scene = view_scene(robot, &trace, trace_path, &trace_context(trace_path))?;
    let html = super::view_html(&scene, &bundle.script(super::Page::View)?);
    super::write_page(out, &html)?;
    Ok(WrittenView {
        steps: trace.len(),
        reference_ghost: scene.reference_poses.is_some(),
    })
}
