//! Turning an importer's [`RawMotion`] into a canonical [`Sequence`]: joints mapped by name
//! into the robot's order, forces resampled onto the motion clock, explicit repairs only.
//!
//! The repairs are renormalising root quaternions and trimming teleoperation glitches
//! (see [`crate::sim::motion::scan_root_glitches`] for the rule); each is applied only when its
//! option is set and recorded in the provenance when it changed anything.

use super::force_csv::ForceLog;
use super::{ImportError, RawMotion};
use crate::sim::motion::{GlitchScan, Sequence, TrimmedGlitches, LEFT, QUAT_NORM_TOLERANCE, RIGHT};
use crate::sim::robot::RobotModel;
use serde_json::{json, Map, Value};
use std::path::Path;

/// How to import one motion.
#[derive(Debug, Clone)]
pub struct ImportOptions {
    /// Task name of the sequence.
    pub task: String,
    /// Sequence identifier (by default the input file's stem).
    pub sequence_id: String,
    /// Renormalise root quaternions that are off unit norm (otherwise such a file is
    /// rejected). Recorded in the provenance when it changes anything.
    pub renormalize_quaternions: bool,
    /// Drop leading and trailing teleoperation-glitch frames (root jumps faster than a
    /// human moves; otherwise such a file is rejected). Interior jumps are always rejected.
    /// Recorded in the provenance when it changes anything.
    pub trim_glitches: bool,
    /// Left and right force logs (sensor frame), if recorded.
    pub forces: Option<[ForceLog; 2]>,
    /// Force log time = motion time + this offset, s.
    pub force_offset_s: f64,
    /// Multiplies the logged forces: −1 when the sensor reports the force the hand exerts
    /// on the environment (ThorArena stores the force the environment exerts on the hand).
    pub force_sign: f64,
}

/// Builds the canonical sequence for `robot` from a raw motion read from `source`.
///
/// The phases run in this order, so the first error a broken file reports stays the same
/// however it is broken: frame counts, root glitches, joint columns, root quaternions,
/// forces, and the finished sequence's own validation.
pub fn to_sequence(
    raw: RawMotion,
    robot: &RobotModel,
    opts: &ImportOptions,
    source: &Path,
) -> Result<Sequence, ImportError> {
    let bad = |field: &str, reason: String| bad_field(source, field, reason);
    let mut raw = raw;
    check_frame_counts(&raw, source)?;
    let glitches = trim_root_glitches(&mut raw, opts, source)?;
    // Source frame of the sequence's frame 0: forces are resampled on the source clock.
    let first_frame = glitches.leading_frames;
    let t = raw.root_pos.len();
    let column_of = joint_columns(&raw, robot, source)?;
    let missing: Vec<&str> = robot
        .joints
        .iter()
        .zip(&column_of)
        .filter(|(_, c)| c.is_none())
        .map(|(j, _)| j.name.as_str())
        .collect();
    let remap = |rows: &[Vec<f64>]| -> Vec<Vec<f64>> {
        rows.iter()
            .map(|r| {
                column_of
                    .iter()
                    .map(|c| c.map_or(0.0, |c| r.get(c).copied().unwrap_or(f64::NAN)))
                    .collect()
            })
            .collect()
    };
    let mut provenance = raw.provenance.clone();
    if !glitches.is_clean() {
        record_trimmed_glitches(&glitches, &mut provenance);
    }
    if !missing.is_empty() {
        provenance.insert("missing_joints_set_to_zero".into(), json!(missing));
    }
    let quats = root_quaternions(&raw.root_quat_wxyz, opts, &mut provenance, source)?;
    let times: Vec<f64> = (0..t).map(|k| (first_frame + k) as f64 / raw.fps).collect();
    let (force_sensor, forces_recorded) = sensor_forces(opts, &times, &mut provenance, source)?;
    let hand_quat = |side: usize| {
        let q = robot.hands[side].hand_from_sensor;
        [q.w, q.i, q.j, q.k]
    };
    let point = |side: usize| {
        let p = robot.hands[side].point_hand;
        [p.x, p.y, p.z]
    };
    let seq = Sequence {
        task: opts.task.clone(),
        sequence_id: opts.sequence_id.clone(),
        fps: raw.fps,
        joint_names: robot.joints.iter().map(|j| j.name.clone()).collect(),
        root_pos: raw.root_pos,
        root_quat_wxyz: quats,
        joint_pos: remap(&raw.joint_pos),
        joint_vel: raw.joint_vel.as_deref().map(remap),
        force_sensor,
        hand_from_sensor_wxyz: [hand_quat(LEFT), hand_quat(RIGHT)],
        force_point_hand: [point(LEFT), point(RIGHT)],
        forces_recorded,
        force_frame: Default::default(),
        provenance: Value::Object(provenance),
    };
    seq.validate(source)
        .map_err(|e| bad("(sequence)", e.to_string()))?;
    Ok(seq)
}

/// A bad field of the motion read from `source`.
fn bad_field(source: &Path, field: &str, reason: String) -> ImportError {
    ImportError::BadField {
        path: source.to_path_buf(),
        field: field.into(),
        reason,
    }
}

/// Every per-frame array must have as many frames as `root_pos`, and the frame rate must
/// be positive: the phases after this index them together.
fn check_frame_counts(raw: &RawMotion, source: &Path) -> Result<(), ImportError> {
    let t = raw.root_pos.len();
    if raw.root_quat_wxyz.len() != t || raw.joint_pos.len() != t {
        return Err(bad_field(
            source,
            "frames",
            format!(
                "root_pos {t}, root orientation {}, joint angles {} frames",
                raw.root_quat_wxyz.len(),
                raw.joint_pos.len()
            ),
        ));
    }
    if let Some(problem) = crate::sim::motion::fps_problem(raw.fps) {
        return Err(bad_field(source, "fps", problem));
    }
    if let Some(v) = &raw.joint_vel {
        if v.len() != t {
            return Err(bad_field(
                source,
                "joint_vel",
                format!("{} frames, but root_pos has {t}", v.len()),
            ));
        }
    }
    Ok(())
}

/// Scans the root for teleoperation glitches: a clean motion passes; leading and trailing
/// glitch frames are cut off when `opts.trim_glitches` asks for it; anything else is an
/// error. Returns the scan (what was cut, for the provenance and the force clock).
fn trim_root_glitches(
    raw: &mut RawMotion,
    opts: &ImportOptions,
    source: &Path,
) -> Result<GlitchScan, ImportError> {
    let t = raw.root_pos.len();
    let glitches = crate::sim::motion::scan_root_glitches(&raw.root_pos, raw.fps);
    let repairable = opts.trim_glitches && glitches.is_trimmable();
    if !(glitches.is_clean() || repairable) {
        return Err(ImportError::RootGlitch {
            path: source.to_path_buf(),
            sequence_id: opts.sequence_id.clone(),
            scan: glitches,
            trim_requested: opts.trim_glitches,
        });
    }
    if !glitches.is_clean() {
        let keep = glitches.leading_frames..t - glitches.trailing_frames;
        raw.root_pos = raw.root_pos[keep.clone()].to_vec();
        raw.root_quat_wxyz = raw.root_quat_wxyz[keep.clone()].to_vec();
        raw.joint_pos = raw.joint_pos[keep.clone()].to_vec();
        raw.joint_vel = raw.joint_vel.take().map(|v| v[keep].to_vec());
    }
    Ok(glitches)
}

pub use super::bounds::JOINT_LIMIT_MARGIN_RAD;

/// For each robot joint, the file's column holding it (`None`: the file lacks it, and it
/// is set to 0). A joint name the robot lacks, or named twice, is an error, and so is a
/// frame whose joint angles do not match the names.
fn joint_columns(
    raw: &RawMotion,
    robot: &RobotModel,
    source: &Path,
) -> Result<Vec<Option<usize>>, ImportError> {
    let mut column_of = vec![None; robot.n_joints()];
    for (c, name) in raw.joint_names.iter().enumerate() {
        let j = robot.joint_index(name).ok_or_else(|| {
            bad_field(
                source,
                "joint_names",
                format!("unknown joint `{name}` for robot {}", robot.name),
            )
        })?;
        if column_of[j].replace(c).is_some() {
            return Err(bad_field(
                source,
                "joint_names",
                format!("`{name}` appears twice"),
            ));
        }
    }
    for (k, r) in raw.joint_pos.iter().enumerate() {
        if r.len() != raw.joint_names.len() {
            return Err(bad_field(
                source,
                "joint_pos",
                format!(
                    "frame {k} has {} values for {} joint names",
                    r.len(),
                    raw.joint_names.len()
                ),
            ));
        }
    }
    for (j, c) in column_of.iter().enumerate() {
        let Some(c) = *c else { continue };
        let joint = &robot.joints[j];
        if let Some((k, why)) =
            raw.joint_pos.iter().enumerate().find_map(|(k, r)| {
                super::bounds::joint_angle_problem(joint, r[c]).map(|why| (k, why))
            })
        {
            return Err(bad_field(
                source,
                "joint_pos",
                format!("frame {k}, column {c}: {why}"),
            ));
        }
    }
    Ok(column_of)
}

/// Records in the provenance which glitch frames were trimmed, and the jumps found.
fn record_trimmed_glitches(glitches: &GlitchScan, provenance: &mut Map<String, Value>) {
    provenance.insert(
        TrimmedGlitches::KEY.into(),
        serde_json::to_value(TrimmedGlitches::of(glitches)).expect("numbers and strings"),
    );
}

/// The root quaternions, checked: each must be a rotation; one off unit norm is an error
/// unless `opts.renormalize_quaternions`, in which case all are renormalised and the count
/// of those that were off is recorded in the provenance.
fn root_quaternions(
    root_quat_wxyz: &[[f64; 4]],
    opts: &ImportOptions,
    provenance: &mut Map<String, Value>,
    source: &Path,
) -> Result<Vec<[f64; 4]>, ImportError> {
    let mut quats = root_quat_wxyz.to_vec();
    let mut renormalized = 0usize;
    for (k, q) in quats.iter_mut().enumerate() {
        if let Some(why) = super::bounds::rotation_problem(q) {
            return Err(bad_field(
                source,
                "root orientation",
                format!("frame {k}: {why}"),
            ));
        }
        let n = q.iter().map(|x| x * x).sum::<f64>().sqrt();
        if (n - 1.0).abs() > QUAT_NORM_TOLERANCE {
            if !opts.renormalize_quaternions {
                return Err(bad_field(
                    source,
                    "root orientation",
                    format!("frame {k}: quaternion norm {n:.6} (give `option.renormalize_quaternions` to repair)"),
                ));
            }
            renormalized += 1;
        }
        if opts.renormalize_quaternions {
            q.iter_mut().for_each(|x| *x /= n);
        }
    }
    if renormalized > 0 {
        provenance.insert("renormalized_quaternion_frames".into(), json!(renormalized));
    }
    Ok(quats)
}

/// Left and right sensor-frame forces, one per motion frame, N.
type SensorForces = [Vec<[f64; 3]>; 2];

/// The left and right sensor forces at the motion's frame `times` (s, source clock), N:
/// the logs resampled, offset and signed as `opts` says, or zeros when none were recorded
/// (the `bool`: whether they were). What was done is recorded in the provenance.
///
/// A force log must cover at least half of the motion's frames once offset: one that
/// misses it (an offset of hours, a log of 0.02 s for a 5 s motion) would import as a
/// motion "with forces" that are all 0 N, and score as a force task it is not.
fn sensor_forces(
    opts: &ImportOptions,
    times: &[f64],
    provenance: &mut Map<String, Value>,
    source: &Path,
) -> Result<(SensorForces, bool), ImportError> {
    let Some(logs) = &opts.forces else {
        provenance.insert("forces".into(), json!("none recorded: zero forces"));
        let t = times.len();
        return Ok(([vec![[0.0; 3]; t], vec![[0.0; 3]; t]], false));
    };
    if !opts.force_offset_s.is_finite() {
        return Err(bad_field(
            source,
            "force offset",
            format!("{} s is not a time offset", opts.force_offset_s),
        ));
    }
    let mut out = [Vec::new(), Vec::new()];
    for side in [LEFT, RIGHT] {
        let (f, outside) = logs[side].resample(times, opts.force_offset_s);
        if 2 * outside > times.len() {
            let span = |t: &[f64]| match (t.first(), t.last()) {
                (Some(a), Some(b)) => format!("{a:.3}–{b:.3} s"),
                _ => "nothing".into(),
            };
            return Err(bad_field(
                source,
                if side == LEFT { "left force log" } else { "right force log" },
                format!(
                    "covers {} of the motion's {} frames: the log spans {} and the motion, offset by {} s, {}; check `option.force_offset` (the log's time = the motion's + the offset)",
                    times.len() - outside,
                    times.len(),
                    span(&logs[side].time_s),
                    opts.force_offset_s,
                    span(&times.iter().map(|t| t + opts.force_offset_s).collect::<Vec<_>>()),
                ),
            ));
        }
        out[side] = f
            .into_iter()
            .map(|v| v.map(|x| x * opts.force_sign))
            .collect();
        if outside > 0 {
            let key = if side == LEFT {
                "left_force_frames_outside_log"
            } else {
                "right_force_frames_outside_log"
            };
            provenance.insert(key.into(), json!(outside));
        }
    }
    provenance.insert("force_offset_s".into(), json!(opts.force_offset_s));
    provenance.insert("force_sign".into(), json!(opts.force_sign));
    Ok((out, true))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::motion::import::G1_CANONICAL_JOINTS;

    /// 45 frames at 30 fps walking +x at 1.2 m/s; joint j of frame k is
    /// `k / 100 + j / 10000` rad (within every joint's limits) and its velocity `-k`, so
    /// every frame's rows identify it.
    fn raw_walk() -> RawMotion {
        let t = 45;
        RawMotion {
            fps: 30.0,
            root_pos: (0..t).map(|k| [0.04 * k as f64, 0.0, 0.78]).collect(),
            root_quat_wxyz: vec![[1.0, 0.0, 0.0, 0.0]; t],
            joint_names: G1_CANONICAL_JOINTS.iter().map(|n| n.to_string()).collect(),
            joint_pos: (0..t)
                .map(|k| {
                    (0..29)
                        .map(|j| k as f64 / 100.0 + j as f64 / 10_000.0)
                        .collect()
                })
                .collect(),
            joint_vel: Some((0..t).map(|k| vec![-(k as f64); 29]).collect()),
            provenance: Default::default(),
        }
    }

    fn opts(trim_glitches: bool) -> ImportOptions {
        ImportOptions {
            task: "walk".into(),
            sequence_id: "w".into(),
            renormalize_quaternions: false,
            trim_glitches,
            forces: None,
            force_offset_s: 0.0,
            force_sign: 1.0,
        }
    }

    fn robot() -> RobotModel {
        crate::sim::robot::load_bundled("g1_29dof").unwrap()
    }

    fn import(raw: RawMotion, trim: bool) -> Result<Sequence, ImportError> {
        to_sequence(raw, &robot(), &opts(trim), Path::new("w.pkl"))
    }

    /// Source frame of a sequence frame, read back from its joint angles.
    fn source_frame(seq: &Sequence, k: usize) -> f64 {
        let j = robot().joint_index(G1_CANONICAL_JOINTS[0]).unwrap();
        (seq.joint_pos[k][j] * 100.0).round()
    }

    #[test]
    fn a_clean_motion_is_untouched() {
        let raw = raw_walk();
        let seq = import(raw.clone(), true).unwrap();
        assert_eq!(seq.root_pos, raw.root_pos);
        assert_eq!(seq.n_frames(), 45);
        assert!(seq.provenance.get("trimmed_glitch_frames").is_none());
    }

    #[test]
    fn two_leading_glitch_frames_are_refused_then_trimmed_exactly() {
        let mut raw = raw_walk();
        raw.root_pos[0] = [2.5, 1.5, 0.8];
        raw.root_pos[1] = [-1.0, -2.0, 0.8];
        let err = import(raw.clone(), false).unwrap_err().to_string();
        for needle in [
            "w.pkl",
            "`w`",
            "frame 0→1",
            "frame 1→2",
            "m/s",
            "`option.trim_glitches`",
            "2 leading",
        ] {
            assert!(err.contains(needle), "`{needle}` missing from: {err}");
        }
        let seq = import(raw.clone(), true).unwrap();
        assert_eq!(seq.n_frames(), 43);
        assert_eq!(seq.root_pos, raw.root_pos[2..]);
        assert_eq!(source_frame(&seq, 0), 2.0);
        assert_eq!(seq.joint_vel.as_ref().unwrap()[0][0], -2.0);
        let forces = &seq.force_sensor;
        assert!(forces[LEFT].len() == 43 && forces[RIGHT].len() == 43);
        let p = &seq.provenance["trimmed_glitch_frames"];
        assert_eq!(
            (p["leading"].clone(), p["trailing"].clone()),
            (json!(2), json!(0))
        );
        assert_eq!(p["root_jumps"].as_array().unwrap().len(), 2);
    }

    #[test]
    fn a_trailing_glitch_frame_is_trimmed() {
        let mut raw = raw_walk();
        raw.root_pos[44] = [0.0, 3.0, 0.8];
        let err = import(raw.clone(), false).unwrap_err().to_string();
        assert!(
            err.contains("frame 43→44") && err.contains("`option.trim_glitches`"),
            "{err}"
        );
        let seq = import(raw.clone(), true).unwrap();
        assert_eq!(seq.root_pos, raw.root_pos[..44]);
        assert_eq!(source_frame(&seq, 43), 43.0);
        assert_eq!(seq.provenance["trimmed_glitch_frames"]["trailing"], 1);
    }

    #[test]
    fn an_interior_glitch_stays_an_error_with_the_flag() {
        let mut raw = raw_walk();
        raw.root_pos[22] = [9.0, 0.0, 0.8];
        let err = import(raw, true).unwrap_err();
        assert!(matches!(err, ImportError::RootGlitch { .. }));
        let msg = err.to_string();
        for needle in [
            "frame 21→22",
            "frame 22→23",
            "inside the motion",
            "`option.trim_glitches` does not repair",
            "not imported even with it",
        ] {
            assert!(msg.contains(needle), "`{needle}` missing from: {msg}");
        }
    }

    #[test]
    fn forces_are_resampled_on_the_source_clock_after_trimming() {
        // fx = 100 · t on the source clock: trimmed frame 0 is source frame 2 (t = 2/30 s).
        let log = |scale: f64| ForceLog {
            time_s: (0..=200).map(|i| i as f64 * 0.01).collect(),
            force_n: (0..=200)
                .map(|i| [scale * i as f64 * 0.01, 0.0, 0.0])
                .collect(),
        };
        let mut raw = raw_walk();
        raw.root_pos[0] = [3.0, 0.0, 0.8];
        raw.root_pos[1] = [3.0, 0.0, 0.8];
        let mut o = opts(true);
        o.forces = Some([log(100.0), log(0.0)]);
        let seq = to_sequence(raw, &robot(), &o, Path::new("w.pkl")).unwrap();
        let fx0 = seq.force_sensor[LEFT][0][0];
        assert!((fx0 - 100.0 * 2.0 / 30.0).abs() < 1e-9, "{fx0}");
    }
}
