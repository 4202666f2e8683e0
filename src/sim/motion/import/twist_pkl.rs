//! Reader for GMR / TWIST / TWIST2 / GMT motion pickles, without Python.
//!
//! The files are a pickled dict: `fps`, `root_pos` `[T,3]` (m), `root_rot` `[T,4]` (xyzw),
//! `dof_pos` `[T,29]` (GMT: `[T,23]`) rad, optionally `local_body_pos` `[T,38,3]` and
//! `link_body_list`. They are decoded with `serde-pickle`, which never executes pickled code.
//!
//! # How numpy objects survive `serde-pickle`
//!
//! We use `DeOptions::new().replace_unresolved_globals().keep_restore_state()`:
//!
//! - An ndarray is `_reconstruct(ndarray, (0,), b'b')` followed by BUILD with its
//!   `__setstate__` tuple `(version, shape, dtype, is_fortran, raw_bytes)`; serde-pickle's
//!   BUILD replaces the object by that tuple, so it arrives as a 5-tuple. Pickle protocol 5
//!   instead writes `_frombuffer(buffer, dtype, shape, order)`; with `keep_restore_state`
//!   the call's arguments are kept, so it arrives as that 4-tuple. Both are accepted.
//! - A numpy scalar (`fps` as `np.float64`) is `scalar(dtype, raw_bytes)`. Without
//!   `keep_restore_state` serde-pickle turns the unknown call into `None` and the value is
//!   lost; with it, the call's arguments are kept, so it arrives as `(dtype, raw_bytes)` and
//!   is decoded like a one-element array. No opcode scanning is needed.
//! - A dtype is `dtype('f8', False, True)` + BUILD `(3, '<', ...)`. Its first occurrence is
//!   replaced by the state tuple (byte order only); later references come from the pickle
//!   memo, which serde-pickle stores *before* BUILD, so they read `('f8', False, True)` and
//!   carry the type. We use whichever is present; when the type is unknown the element size
//!   is inferred from `raw bytes / element count` (8 → f64, 4 → f32). Big-endian → error.
//!   (An integer array first seen as a state tuple would be read as floats; these files
//!   hold none.)
//!
//! Values are passed through as stored (non-finite values included): the canonical loader
//! validates them. Structural problems (wrong shape, short buffer, T mismatch) are errors.

use std::collections::BTreeMap;
use std::path::Path;

use serde_json::{json, Map};
use serde_pickle::{DeOptions, HashableValue, Value};

use super::{ImportError, RawMotion};

const FORMAT: &str = "twist-pkl";

/// GMR/TWIST write `dof_pos` columns in the canonical order; GMT's 23-DoF files use the
/// same order without the six `*_wrist_*` joints.
const G1_29: [&str; 29] = super::G1_CANONICAL_JOINTS;

fn is_wrist(name: &&str) -> bool {
    name.contains("_wrist_")
}

/// Reads a GMR/TWIST/TWIST2/GMT motion pickle.
pub fn read_twist_pkl(path: &std::path::Path) -> Result<super::RawMotion, super::ImportError> {
    let bytes = crate::files::bounded_read::read(path, "motion file", super::MAX_IMPORT_BYTES)
        .map_err(|source| ImportError::Io {
            path: path.to_path_buf(),
            source,
        })?;
    let format_err = |reason: String| ImportError::Format {
        path: path.to_path_buf(),
        format: FORMAT,
        reason,
    };
    let options = DeOptions::new()
        .replace_unresolved_globals()
        .keep_restore_state();
    // Decoding recurses once per level of nesting: bound it first (a hostile 20 KB pickle
    // of nested lists would otherwise overflow the stack).
    super::pickle_depth::check_nesting(&bytes, super::pickle_depth::MAX_NESTING)
        .map_err(|e| format_err(format!("not a motion pickle: {e}")))?;
    let value = serde_pickle::value_from_slice(&bytes, options)
        .map_err(|e| format_err(format!("pickle decoding failed: {e}")))?;
    let Value::Dict(dict) = value else {
        return Err(format_err(format!(
            "top-level object is {}, not a dict",
            kind_of(&value)
        )));
    };
    let r = Reader { path, dict: &dict };

    let (fps, fps_from) = r.fps()?;
    let root_pos = r.matrix("root_pos", &[3])?;
    let root_rot = r.matrix("root_rot", &[4])?;
    let dof_pos = r.matrix("dof_pos", &[29, 23])?;
    let frames = root_pos.rows;
    for m in [&root_rot, &dof_pos] {
        if m.rows != frames {
            return Err(r.bad(
                m.field,
                format!("{} frames, but `root_pos` has {frames}", m.rows),
            ));
        }
    }
    if frames == 0 {
        return Err(r.bad("root_pos", "the motion has no frames".into()));
    }
    let has_local_body_pos = r.check_local_body_pos(frames)?;

    let file_name = path.file_name().map(|n| n.to_string_lossy().into_owned());
    let mut provenance: Map<String, serde_json::Value> = [
        ("format", json!(FORMAT)),
        ("source_file", json!(file_name)),
        ("frames", json!(frames)),
        ("source_fps", json!(fps)),
        ("has_local_body_pos", json!(has_local_body_pos)),
        ("fps_decoded_from", json!(fps_from)),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v))
    .collect();
    let gmt = dof_pos.cols != G1_29.len();
    let joint_names: Vec<String> = G1_29
        .iter()
        .filter(|n| !(gmt && is_wrist(n)))
        .map(|s| s.to_string())
        .collect();
    if gmt {
        let wrists: Vec<&str> = G1_29.iter().copied().filter(is_wrist).collect();
        provenance.insert("missing_joints".into(), json!(wrists));
        let note = "GMT 23-DoF file: the six wrist joints are absent; the importer leaves them \
                    to the canonical mapping, which sets them to 0";
        provenance.insert("note".into(), json!(note));
    }

    Ok(RawMotion {
        fps,
        root_pos: rows::<3>(&root_pos.data),
        // The file stores xyzw; RawMotion wants wxyz.
        root_quat_wxyz: rows::<4>(&root_rot.data)
            .into_iter()
            .map(|[x, y, z, w]| [w, x, y, z])
            .collect(),
        joint_names,
        joint_pos: dof_pos
            .data
            .chunks_exact(dof_pos.cols)
            .map(<[f64]>::to_vec)
            .collect(),
        joint_vel: None,
        provenance,
    })
}

/// A 2-D numeric array in row-major order.
struct Matrix {
    field: &'static str,
    rows: usize,
    cols: usize,
    data: Vec<f64>,
}

/// The pieces of a pickled ndarray or numpy scalar, borrowed from the value tree.
struct ArrayParts<'v> {
    shape: &'v [Value],
    dtype: &'v Value,
    fortran: bool,
    raw: &'v [u8],
}

/// What is known of a dtype: kind and size when the descriptor survived, byte order.
#[derive(Default)]
struct Dtype {
    kind: Option<char>,
    size: Option<usize>,
    big_endian: bool,
}

/// The top-level dict plus the file, so every error can name both.
struct Reader<'a> {
    path: &'a Path,
    dict: &'a BTreeMap<HashableValue, Value>,
}

impl Reader<'_> {
    fn bad(&self, field: &str, reason: String) -> ImportError {
        ImportError::BadField {
            path: self.path.to_path_buf(),
            field: field.to_string(),
            reason,
        }
    }

    /// Looks a key up as a str (Python 3) or bytes (Python 2 `str`) key.
    fn get(&self, key: &str) -> Option<&Value> {
        self.dict
            .get(&HashableValue::String(key.to_string()))
            .or_else(|| {
                self.dict
                    .get(&HashableValue::Bytes(key.as_bytes().to_vec()))
            })
    }

    /// Reads `fps` from a numpy scalar, a 1-element ndarray, a float or an int; it must be
    /// finite and positive, since every time axis downstream divides by it.
    fn fps(&self) -> Result<(f64, &'static str), ImportError> {
        let v = self
            .get("fps")
            .ok_or_else(|| self.bad("fps", "missing".into()))?;
        let (fps, from) = match v {
            Value::F64(f) => (*f, "float"),
            Value::I64(i) => (*i as f64, "int"),
            other => {
                if let Some(parts) = scalar_parts(other) {
                    (self.one_value("fps", &parts)?, "numpy_scalar")
                } else if let Some(parts) = array_parts(other) {
                    (self.one_value("fps", &parts)?, "numpy_array")
                } else {
                    return Err(self.bad(
                        "fps",
                        format!("expected a number, found {}", kind_of(other)),
                    ));
                }
            }
        };
        if !(fps.is_finite() && fps > 0.0) {
            return Err(self.bad("fps", format!("{fps} is not a positive frame rate")));
        }
        Ok((fps, from))
    }

    fn one_value(&self, field: &str, parts: &ArrayParts) -> Result<f64, ImportError> {
        let (_, data) = self.decode(field, parts)?;
        match data.as_slice() {
            [x] => Ok(*x),
            _ => Err(self.bad(field, format!("{} values, expected one", data.len()))),
        }
    }

    /// Reads a required [T, C] array whose column count is one of `allowed_cols`.
    fn matrix(&self, field: &'static str, allowed_cols: &[usize]) -> Result<Matrix, ImportError> {
        let v = self
            .get(field)
            .ok_or_else(|| self.bad(field, "missing".into()))?;
        let (shape, data) = self.array(field, v)?;
        match shape.as_slice() {
            [rows, cols] if allowed_cols.contains(cols) => Ok(Matrix {
                field,
                rows: *rows,
                cols: *cols,
                data,
            }),
            _ => Err(self.bad(
                field,
                format!("shape {shape:?}, expected [T, C] with C in {allowed_cols:?}"),
            )),
        }
    }

    /// Checks the optional `local_body_pos` ([T, bodies, 3]) so a corrupt one is reported;
    /// its values are not imported (the canonical format recomputes bodies by FK).
    fn check_local_body_pos(&self, frames: usize) -> Result<bool, ImportError> {
        const FIELD: &str = "local_body_pos";
        let Some(v) = self.get(FIELD) else {
            return Ok(false);
        };
        let (shape, _) = self.array(FIELD, v)?;
        match shape.as_slice() {
            [t, _, 3] if *t == frames => Ok(true),
            _ => Err(self.bad(
                FIELD,
                format!("shape {shape:?}, expected [{frames}, bodies, 3]"),
            )),
        }
    }

    /// Decodes `v`, which must be a numeric ndarray.
    fn array(&self, field: &str, v: &Value) -> Result<(Vec<usize>, Vec<f64>), ImportError> {
        let parts = array_parts(v).ok_or_else(|| {
            let found = kind_of(v);
            self.bad(
                field,
                format!("expected a numeric numpy array, found {found}"),
            )
        })?;
        self.decode(field, &parts)
    }

    /// Decodes a numeric buffer into f64 values in C order, with its shape.
    fn decode(&self, field: &str, p: &ArrayParts) -> Result<(Vec<usize>, Vec<f64>), ImportError> {
        let shape = p
            .shape
            .iter()
            .map(|d| match d {
                Value::I64(n) => usize::try_from(*n).ok(),
                _ => None,
            })
            .collect::<Option<Vec<usize>>>()
            .ok_or_else(|| self.bad(field, "shape is not a tuple of non-negative ints".into()))?;
        let count = shape
            .iter()
            .try_fold(1usize, |acc, &d| acc.checked_mul(d))
            .ok_or_else(|| self.bad(field, format!("shape {shape:?} overflows")))?;
        let dtype = dtype_of(p.dtype);
        if dtype.big_endian {
            return Err(self.bad(field, "big-endian arrays are not supported".into()));
        }
        let size = match dtype.size {
            Some(size) => size,
            None if count > 0 && p.raw.len().is_multiple_of(count) => p.raw.len() / count,
            None => {
                return Err(self.bad(
                    field,
                    format!(
                        "buffer of {} bytes does not hold {count} elements (truncated?)",
                        p.raw.len()
                    ),
                ))
            }
        };
        if count.checked_mul(size) != Some(p.raw.len()) {
            return Err(self.bad(
                field,
                format!(
                    "buffer has {} bytes, shape {shape:?} of {size}-byte elements needs {} \
                     (truncated?)",
                    p.raw.len(),
                    count.saturating_mul(size)
                ),
            ));
        }
        let data: Vec<f64> = match (dtype.kind.unwrap_or('f'), size) {
            ('f', 8) => each(p.raw, f64::from_le_bytes),
            ('f', 4) => each(p.raw, |b| f64::from(f32::from_le_bytes(b))),
            ('i', 8) => each(p.raw, |b| i64::from_le_bytes(b) as f64),
            ('i', 4) => each(p.raw, |b| f64::from(i32::from_le_bytes(b))),
            (kind, size) => {
                return Err(self.bad(field, format!("unsupported dtype `{kind}{size}`")))
            }
        };
        let data = if p.fortran && shape.len() > 1 {
            fortran_to_c(&shape, &data)
        } else {
            data
        };
        Ok((shape, data))
    }
}

/// Copies a slice of exactly `N` items (guaranteed by `chunks_exact`) into an array.
fn arr<T: Copy + Default, const N: usize>(c: &[T]) -> [T; N] {
    let mut a = [T::default(); N];
    a.copy_from_slice(c);
    a
}

/// Splits row-major data into rows of `N`.
fn rows<const N: usize>(data: &[f64]) -> Vec<[f64; N]> {
    data.chunks_exact(N).map(arr).collect()
}

/// Decodes little-endian elements of `N` bytes with `f`.
fn each<const N: usize>(raw: &[u8], f: impl Fn([u8; N]) -> f64) -> Vec<f64> {
    raw.chunks_exact(N).map(|c| f(arr(c))).collect()
}

/// Reorders column-major `data` of `shape` into row-major order.
fn fortran_to_c(shape: &[usize], data: &[f64]) -> Vec<f64> {
    // Column-major strides: the first axis varies fastest.
    let mut strides = vec![1usize; shape.len()];
    for k in 1..shape.len() {
        strides[k] = strides[k - 1] * shape[k - 1];
    }
    let mut index = vec![0usize; shape.len()];
    let mut out = Vec::with_capacity(data.len());
    for _ in 0..data.len() {
        let offset: usize = index.iter().zip(&strides).map(|(i, s)| i * s).sum();
        out.push(data.get(offset).copied().unwrap_or(f64::NAN));
        // Advance the row-major multi-index (last axis fastest).
        for k in (0..shape.len()).rev() {
            index[k] += 1;
            if index[k] < shape[k] {
                break;
            }
            index[k] = 0;
        }
    }
    out
}

/// Recognises a numpy scalar, `scalar(dtype, raw_bytes)`, by its kept arguments.
fn scalar_parts(v: &Value) -> Option<ArrayParts<'_>> {
    let Value::Tuple(t) = v else { return None };
    match t.as_slice() {
        [dtype, Value::Bytes(raw)] => Some(ArrayParts {
            shape: &[],
            dtype,
            fortran: false,
            raw,
        }),
        _ => None,
    }
}

/// Recognises an ndarray as serde-pickle delivers it (see the module doc).
fn array_parts(v: &Value) -> Option<ArrayParts<'_>> {
    let Value::Tuple(t) = v else { return None };
    match t.as_slice() {
        // __setstate__ tuple, with or without the leading version.
        [Value::I64(_), Value::Tuple(shape), dtype, Value::Bool(fortran), Value::Bytes(raw)]
        | [Value::Tuple(shape), dtype, Value::Bool(fortran), Value::Bytes(raw)] => {
            Some(ArrayParts {
                shape,
                dtype,
                fortran: *fortran,
                raw,
            })
        }
        // Protocol 5: _frombuffer(buffer, dtype, shape, order).
        [Value::Bytes(raw), dtype, Value::Tuple(shape), Value::String(order)] => Some(ArrayParts {
            shape,
            dtype,
            fortran: order == "F",
            raw,
        }),
        _ => None,
    }
}

/// Reads what survives of a dtype: `('f8', False, True)` from the memo, or the BUILD state
/// `(3, '<', ...)`, or nothing.
fn dtype_of(v: &Value) -> Dtype {
    let Value::Tuple(t) = v else {
        return Dtype::default();
    };
    match t.as_slice() {
        [Value::String(descr), ..] => {
            let big_endian = descr.starts_with('>');
            let descr = descr.trim_start_matches(['<', '>', '=', '|']);
            let mut chars = descr.chars();
            Dtype {
                kind: chars.next(),
                size: chars.as_str().parse().ok(),
                big_endian,
            }
        }
        [Value::I64(_), Value::String(order), ..] => Dtype {
            big_endian: order == ">",
            ..Dtype::default()
        },
        _ => Dtype::default(),
    }
}

/// A short name of a value's Python type, for error messages.
fn kind_of(v: &Value) -> &'static str {
    match v {
        Value::None => "None (or an unsupported object)",
        Value::Bool(_) => "a bool",
        Value::I64(_) | Value::Int(_) => "an int",
        Value::F64(_) => "a float",
        Value::Bytes(_) => "bytes",
        Value::String(_) => "a str",
        Value::List(_) => "a list",
        Value::Tuple(_) => "a tuple",
        Value::Set(_) | Value::FrozenSet(_) => "a set",
        Value::Dict(_) => "a dict",
    }
}
