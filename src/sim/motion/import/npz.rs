//! BeyondMimic / mjlab motion archives (`.npz`).
//!
//! These files hold the simulator's own view of a motion: `fps`, `joint_pos` and
//! `joint_vel` `[T, J]` in the simulator's joint order, and per-body world poses
//! `body_pos_w` `[T, B, 3]`, `body_quat_w` `[T, B, 4]` (**wxyz**). Which joint each column
//! is: the file's own `joint_names` member where it has one (wbc-mjlab's clips: a numpy
//! object array, i.e. a pickled list of strings, or a fixed-width unicode array), else the
//! caller's list, else [`ISAACLAB_G1_JOINT_ORDER`] (BeyondMimic's IsaacLab files store no
//! names); mjlab runs MuJoCo, whose joint order follows the MJCF tree (for the Unitree G1
//! model, [`super::G1_CANONICAL_JOINTS`]), so pass that list for mjlab files without
//! names. A caller's list that contradicts the file's names is an error, never a silent
//! reordering. Body 0 is the pelvis, which becomes the root.
//! `body_lin_vel_w` / `body_ang_vel_w` are ignored: velocities are re-derived downstream.
//!
//! npz members are zip entries at arbitrary offsets (often deflated), so every array is
//! decoded into an owned `Vec<f64>` rather than memory-mapped.

use std::io::{self, BufReader};
use std::path::Path;

use npyz::npz::NpzArchive;
use npyz::{NpyFile, Order};
use serde_json::Value;

use super::{ImportError, RawMotion};

/// The joint order of IsaacLab-trained G1 policies (breadth-first over the kinematic tree).
///
/// IsaacLab enumerates articulation joints level by level, so left leg, right leg and
/// waist interleave. Verified against `unitreerobotics/unitree_rl_lab`,
/// `deploy/robots/g1_29dof/config/policy/physhsi/v1/params/deploy.yaml` (commit 1a762ac): its
/// `joint_ids_map` `[0, 6, 12, 1, 7, 13, 2, 8, 14, 3, 9, 15, 22, 4, 10, 16, 23, 5, 11, 17,
/// 24, 18, 25, 19, 26, 20, 27, 21, 28]` maps each policy (IsaacLab) index to the Unitree SDK
/// motor index, and the SDK order is the canonical one
/// ([`super::G1_CANONICAL_JOINTS`]); the same list appears verbatim in several
/// public BeyondMimic / SONIC deployment scripts.
#[rustfmt::skip]
pub const ISAACLAB_G1_JOINT_ORDER: [&str; 29] = [
    "left_hip_pitch_joint", "right_hip_pitch_joint", "waist_yaw_joint",
    "left_hip_roll_joint", "right_hip_roll_joint", "waist_roll_joint",
    "left_hip_yaw_joint", "right_hip_yaw_joint", "waist_pitch_joint",
    "left_knee_joint", "right_knee_joint",
    "left_shoulder_pitch_joint", "right_shoulder_pitch_joint",
    "left_ankle_pitch_joint", "right_ankle_pitch_joint",
    "left_shoulder_roll_joint", "right_shoulder_roll_joint",
    "left_ankle_roll_joint", "right_ankle_roll_joint",
    "left_shoulder_yaw_joint", "right_shoulder_yaw_joint",
    "left_elbow_joint", "right_elbow_joint",
    "left_wrist_roll_joint", "right_wrist_roll_joint",
    "left_wrist_pitch_joint", "right_wrist_pitch_joint",
    "left_wrist_yaw_joint", "right_wrist_yaw_joint",
];

/// One decoded member: its shape and its elements in C (row-major) order.
struct Array {
    shape: Vec<usize>,
    data: Vec<f64>,
}

/// Reads a BeyondMimic/mjlab motion npz; `joint_names` names its joint columns (IsaacLab order when None).
pub fn read_beyondmimic_npz(
    path: &Path,
    joint_names: Option<&[String]>,
) -> Result<RawMotion, ImportError> {
    let bad = |field: &str, reason: String| ImportError::BadField {
        path: path.to_path_buf(),
        field: field.to_string(),
        reason,
    };
    // Checked as a bounded read (a regular file within the limit), then read by seeking.
    let file = crate::files::bounded_read::open(path, "motion file", super::MAX_IMPORT_BYTES)
        .map_err(|source| ImportError::Io {
            path: path.to_path_buf(),
            source,
        })?
        .into_inner();
    let mut archive = NpzArchive::new(BufReader::new(file)).map_err(|e| ImportError::Format {
        path: path.to_path_buf(),
        format: "npz",
        reason: e.to_string(),
    })?;

    let fps_arr = read_required(&mut archive, path, "fps")?;
    if fps_arr.data.len() != 1 {
        return Err(bad(
            "fps",
            format!("expected one value, shape {:?}", fps_arr.shape),
        ));
    }
    let fps = fps_arr.data[0];
    if !(fps.is_finite() && fps > 0.0) {
        return Err(bad("fps", format!("must be a positive number, got {fps}")));
    }

    let joint_pos = read_required(&mut archive, path, "joint_pos")?;
    let (frames, columns) = match joint_pos.shape[..] {
        [t, j] if t > 0 && j > 0 => (t, j),
        _ => {
            return Err(bad(
                "joint_pos",
                shape_reason("[T>0, J>0]", &joint_pos.shape),
            ))
        }
    };
    let in_file = read_names(&mut archive, path, "joint_names")?;
    let (names, order) = column_names(path, joint_names, in_file, columns)?;

    let joint_vel = match read_optional(&mut archive, path, "joint_vel")? {
        Some(v) if v.shape == joint_pos.shape => Some(rows(&v.data, columns)),
        Some(v) => {
            let want = format!("[{frames}, {columns}] like joint_pos");
            return Err(bad("joint_vel", shape_reason(&want, &v.shape)));
        }
        None => None,
    };
    let body_pos = read_required(&mut archive, path, "body_pos_w")?;
    let bodies = match body_pos.shape[..] {
        [t, b, 3] if t == frames && b > 0 => b,
        _ => {
            let want = format!("[{frames}, B>0, 3]");
            return Err(bad("body_pos_w", shape_reason(&want, &body_pos.shape)));
        }
    };
    let body_quat = read_required(&mut archive, path, "body_quat_w")?;
    if body_quat.shape[..] != [frames, bodies, 4] {
        let want = format!("[{frames}, {bodies}, 4] like body_pos_w");
        return Err(bad("body_quat_w", shape_reason(&want, &body_quat.shape)));
    }

    // Body 0 (the pelvis) of each frame is the root.
    let root_pos = (0..frames)
        .map(|t| {
            let o = t * bodies * 3;
            [body_pos.data[o], body_pos.data[o + 1], body_pos.data[o + 2]]
        })
        .collect();
    let root_quat_wxyz = (0..frames)
        .map(|t| {
            let o = t * bodies * 4;
            let q = &body_quat.data[o..o + 4];
            [q[0], q[1], q[2], q[3]]
        })
        .collect();

    let mut provenance = serde_json::Map::new();
    provenance.insert("format".into(), Value::from("beyondmimic-npz"));
    provenance.insert(
        "source_file".into(),
        Value::from(path.display().to_string()),
    );
    provenance.insert("frames".into(), Value::from(frames));
    provenance.insert("source_fps".into(), Value::from(fps));
    provenance.insert("joint_order".into(), Value::from(order));
    provenance.insert("bodies".into(), Value::from(bodies));

    Ok(RawMotion {
        fps,
        root_pos,
        root_quat_wxyz,
        joint_names: names,
        joint_pos: rows(&joint_pos.data, columns),
        joint_vel,
        provenance,
    })
}

/// The names of `columns` joint columns: the file's own, else those given, else IsaacLab's
/// order (and which of the three); a file's names that contradict the given ones, a count
/// that is not the columns' or a name given twice are refused.
fn column_names(
    path: &Path,
    given: Option<&[String]>,
    in_file: Option<Vec<String>>,
    columns: usize,
) -> Result<(Vec<String>, &'static str), ImportError> {
    let bad = |field: &str, reason: String| ImportError::BadField {
        path: path.to_path_buf(),
        field: field.to_string(),
        reason,
    };
    let (names, order) = match (given, in_file) {
        (Some(given), Some(file)) if given != file.as_slice() => {
            return Err(bad(
                "joint_names",
                format!(
                    "the file names its joints [{}], which contradicts the order given [{}]",
                    file.join(", "),
                    given.join(", ")
                ),
            ))
        }
        (_, Some(file)) => (file, "file"),
        (Some(given), None) => (given.to_vec(), "given"),
        (None, None) => (
            ISAACLAB_G1_JOINT_ORDER.map(String::from).to_vec(),
            "isaaclab",
        ),
    };
    if names.len() != columns {
        return Err(bad(
            "joint_names",
            format!("{} names for {columns} joint_pos columns", names.len()),
        ));
    }
    if let Some(dup) = names
        .iter()
        .enumerate()
        .find(|(i, n)| names[..*i].contains(n))
    {
        return Err(bad("joint_names", format!("`{}` appears twice", dup.1)));
    }
    Ok((names, order))
}

fn shape_reason(want: &str, got: &[usize]) -> String {
    format!("expected shape {want}, got {got:?}")
}

/// Splits a C-order `[T, J]` buffer into per-frame rows (`columns` > 0).
fn rows(data: &[f64], columns: usize) -> Vec<Vec<f64>> {
    data.chunks(columns).map(<[f64]>::to_vec).collect()
}

fn read_required<R: io::Read + io::Seek>(
    archive: &mut NpzArchive<R>,
    path: &Path,
    name: &str,
) -> Result<Array, ImportError> {
    read_optional(archive, path, name)?.ok_or_else(|| ImportError::BadField {
        path: path.to_path_buf(),
        field: name.to_string(),
        reason: "missing from the archive".into(),
    })
}

/// Member `name` of the archive, if it has one; the reason when it cannot be opened.
fn member<'a, R: io::Read + io::Seek>(
    archive: &'a mut NpzArchive<R>,
    name: &str,
) -> Result<Option<NpyFile<npyz::zip::read::ZipFile<'a>>>, String> {
    archive
        .by_name(name)
        .map_err(|e| format!("unreadable array: {e}"))
}

/// Member `name` as a list of strings, if the archive has it: a numpy object array (the
/// pickle numpy writes for `np.array([...], dtype=object)`, decoded without executing
/// anything) or a fixed-width unicode array (`<U…`, UTF-32).
fn read_names<R: io::Read + io::Seek>(
    archive: &mut NpzArchive<R>,
    path: &Path,
    name: &str,
) -> Result<Option<Vec<String>>, ImportError> {
    let bad = |reason: String| ImportError::BadField {
        path: path.to_path_buf(),
        field: name.to_string(),
        reason,
    };
    let Some(npy) = member(archive, name).map_err(bad)? else {
        return Ok(None);
    };
    let count = usize::try_from(npy.len()).map_err(|_| bad("too many names".into()))?;
    let descr = npy.dtype().descr();
    let pickled = npy.uses_pickled_array();
    // Joint names are a few hundred bytes; a member far larger is not a list of names.
    let mut raw = Vec::new();
    io::Read::read_to_end(&mut io::Read::take(npy.into_inner(), 1 << 20), &mut raw)
        .map_err(|e| bad(format!("unreadable array: {e}")))?;
    let names = if pickled {
        names_from_pickle(&raw).map_err(bad)?
    } else if let Some(width) = unicode_width(&descr) {
        names_from_utf32(&raw, width, count).map_err(bad)?
    } else {
        return Err(bad(format!(
            "dtype {descr} is not a list of names (an object or unicode array)"
        )));
    };
    if names.len() != count {
        return Err(bad(format!("{} names for shape [{count}]", names.len())));
    }
    Ok(Some(names))
}

/// The strings of the one list of strings in a pickled numpy object array.
fn names_from_pickle(raw: &[u8]) -> Result<Vec<String>, String> {
    use serde_pickle::{DeOptions, Value as P};
    super::pickle_depth::check_nesting(raw, super::pickle_depth::MAX_NESTING)
        .map_err(|e| format!("not a pickled array: {e}"))?;
    let options = DeOptions::new()
        .replace_unresolved_globals()
        .keep_restore_state();
    let value = serde_pickle::value_from_slice(raw, options)
        .map_err(|e| format!("not a pickled array: {e}"))?;
    fn strings(v: &P) -> Option<Vec<String>> {
        match v {
            P::List(items) if items.iter().all(|i| matches!(i, P::String(_))) => Some(
                items
                    .iter()
                    .filter_map(|i| match i {
                        P::String(s) => Some(s.clone()),
                        _ => None,
                    })
                    .collect(),
            ),
            P::List(items) | P::Tuple(items) => items.iter().find_map(strings),
            _ => None,
        }
    }
    strings(&value).ok_or_else(|| "the pickled array holds no list of strings".into())
}

/// The width in characters of a numpy unicode dtype (`<U22` → 22).
fn unicode_width(descr: &str) -> Option<usize> {
    descr
        .trim_matches('\'')
        .strip_prefix("<U")
        .or_else(|| descr.trim_matches('\'').strip_prefix("|U"))
        .and_then(|w| w.parse().ok())
}

/// `count` fixed-width UTF-32LE strings of `width` characters, NUL-padded.
fn names_from_utf32(raw: &[u8], width: usize, count: usize) -> Result<Vec<String>, String> {
    let item = width * 4;
    if item == 0 || raw.len() < item * count {
        return Err(format!(
            "{} bytes for {count} names of {width} characters",
            raw.len()
        ));
    }
    raw.chunks(item)
        .take(count)
        .map(|c| {
            c.chunks(4)
                .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .take_while(|&u| u != 0)
                .map(|u| char::from_u32(u).ok_or_else(|| format!("invalid character {u:#x}")))
                .collect::<Result<String, String>>()
        })
        .collect()
}

/// Decodes member `name` as f64 whatever its numeric dtype, in C order, all values finite.
fn read_optional<R: io::Read + io::Seek>(
    archive: &mut NpzArchive<R>,
    path: &Path,
    name: &str,
) -> Result<Option<Array>, ImportError> {
    let bad = |reason: String| ImportError::BadField {
        path: path.to_path_buf(),
        field: name.to_string(),
        reason,
    };
    let Some(npy) = member(archive, name).map_err(bad)? else {
        return Ok(None);
    };
    let shape: Vec<usize> = npy
        .shape()
        .iter()
        .map(|&d| usize::try_from(d).ok())
        .collect::<Option<_>>()
        .ok_or_else(|| bad("dimension too large".into()))?;
    let count = shape.iter().try_fold(1usize, |acc, &d| acc.checked_mul(d));
    let fortran = npy.order() == Order::Fortran;
    let data = decode_f64(npy).map_err(bad)?;
    if count != Some(data.len()) {
        return Err(bad(format!("{} values for shape {shape:?}", data.len())));
    }
    if let Some(i) = data.iter().position(|v| !v.is_finite()) {
        return Err(bad(format!("non-finite value at flat index {i}")));
    }
    let data = if fortran {
        fortran_to_c(&data, &shape)
    } else {
        data
    };
    Ok(Some(Array { shape, data }))
}

/// Tries each numeric dtype numpy commonly writes (float64/32, int64/32) in turn.
fn decode_f64<R: io::Read>(npy: NpyFile<R>) -> Result<Vec<f64>, String> {
    let io_err = |e: io::Error| format!("truncated or corrupt data: {e}");
    let npy = match npy.try_data::<f64>() {
        Ok(r) => return r.collect::<io::Result<_>>().map_err(io_err),
        Err(npy) => npy,
    };
    let npy = match npy.try_data::<f32>() {
        Ok(r) => {
            return r
                .map(|v| v.map(f64::from))
                .collect::<io::Result<_>>()
                .map_err(io_err)
        }
        Err(npy) => npy,
    };
    let npy = match npy.try_data::<i64>() {
        // Integers here are frame rates or counts, far below 2^53: the cast is exact.
        Ok(r) => {
            return r
                .map(|v| v.map(|x| x as f64))
                .collect::<io::Result<_>>()
                .map_err(io_err)
        }
        Err(npy) => npy,
    };
    match npy.try_data::<i32>() {
        Ok(r) => r
            .map(|v| v.map(f64::from))
            .collect::<io::Result<_>>()
            .map_err(io_err),
        Err(npy) => Err(format!("unsupported dtype {}", npy.dtype().descr())),
    }
}

/// Reorders a column-major buffer into row-major, so `np.asfortranarray` data reads right.
fn fortran_to_c(data: &[f64], shape: &[usize]) -> Vec<f64> {
    let mut out = Vec::with_capacity(data.len());
    let mut index = vec![0usize; shape.len()];
    for _ in 0..data.len() {
        // Fortran offset: the first axis varies fastest.
        let mut offset = 0;
        let mut stride = 1;
        for (i, &d) in index.iter().zip(shape) {
            offset += i * stride;
            stride *= d;
        }
        out.push(data[offset]);
        // Advance the C-order multi-index: the last axis varies fastest.
        for axis in (0..shape.len()).rev() {
            index[axis] += 1;
            if index[axis] < shape[axis] {
                break;
            }
            index[axis] = 0;
        }
    }
    out
}
