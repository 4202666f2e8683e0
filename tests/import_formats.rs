//! The format readers: a BeyondMimic/mjlab `.npz`, a Unitree LAFAN1 CSV and a
//! force/torque-sensor CSV each become the numbers they hold, in the documented units,
//! quaternion order and joint order; every malformed file is a typed error whose message
//! names the file and the field at fault; and no input, however garbled, makes a reader
//! panic. All inputs are written here, into a temporary directory: npz files with
//! npyz's own writer (so the tests always run) and, when Python and numpy are present,
//! once with numpy itself to pin compatibility with real `np.savez_compressed` output.

use std::path::{Path, PathBuf};

use npyz::npz::NpzWriter;
use npyz::zip::write::FileOptions;
use npyz::zip::CompressionMethod;
use npyz::{AutoSerialize, WriterBuilder};
use thorarena::sim::motion::import::force_csv::{read_force_csv, ForceLog};
use thorarena::sim::motion::import::lafan_csv::read_lafan_csv;
use thorarena::sim::motion::import::npz::{read_beyondmimic_npz, ISAACLAB_G1_JOINT_ORDER};
use thorarena::sim::motion::import::ImportError;
use thorarena::sim::motion::import::G1_CANONICAL_JOINTS;

mod prereq;

const T: usize = 3;
const B: usize = 2;
const J: usize = 29;

/// Appends one array to an npz under construction.
fn put<Tv: AutoSerialize + Copy>(
    w: &mut NpzWriter<std::io::BufWriter<std::fs::File>>,
    name: &str,
    shape: &[u64],
    data: &[Tv],
) {
    let opts = FileOptions::default().compression_method(CompressionMethod::Stored);
    let mut a = w
        .array::<Tv>(name, opts)
        .expect("start member")
        .default_dtype()
        .shape(shape)
        .begin_nd()
        .expect("begin member");
    a.extend(data.iter().copied()).expect("write member");
    a.finish().expect("finish member");
}

/// Distinct, recognisable values: joint (t, j) = t·100 + j; body b of frame t sits at
/// (t + 10b, 1 + t, 2 + t) with orientation (w, x, y, z) = (1, 0.1t, 0.2, 0.3b).
fn motion() -> [Vec<f64>; 4] {
    let jp = (0..T * J).map(|i| ((i / J) * 100 + i % J) as f64).collect();
    let jv = (0..T * J).map(|i| -(i as f64)).collect();
    let mut bp = Vec::new();
    let mut bq = Vec::new();
    for t in 0..T {
        for b in 0..B {
            let (t, b) = (t as f64, b as f64);
            bp.extend([t + 10.0 * b, 1.0 + t, 2.0 + t]);
            bq.extend([1.0, 0.1 * t, 0.2, 0.3 * b]);
        }
    }
    [jp, jv, bp, bq]
}

fn shapes() -> [Vec<u64>; 4] {
    let (t, b, j) = (T as u64, B as u64, J as u64);
    [vec![t, j], vec![t, j], vec![t, b, 3], vec![t, b, 4]]
}

/// One npz member: name, shape, float64 data.
type Member<'a> = (&'a str, &'a [u64], &'a [f64]);

const NAMES: [&str; 4] = ["joint_pos", "joint_vel", "body_pos_w", "body_quat_w"];

/// A well-formed motion npz in float64 with `fps` = [50.0], minus `skip`, with
/// `replace` swapping one member for another shape/data (float64).
fn write_f64_npz(path: &Path, skip: Option<&str>, replace: Option<Member>) {
    let mut w = NpzWriter::create(path).expect("create npz");
    write_members(&mut w, skip, replace);
    w.zip_writer().finish().expect("finish npz");
}

/// The members of [`write_f64_npz`], into `w`.
fn write_members(
    w: &mut NpzWriter<std::io::BufWriter<std::fs::File>>,
    skip: Option<&str>,
    replace: Option<Member>,
) {
    let members = [("fps", vec![1u64], vec![50.0])].into_iter().chain(
        NAMES
            .iter()
            .zip(shapes())
            .zip(motion())
            .map(|((n, s), d)| (*n, s, d)),
    );
    for (name, shape, data) in members {
        if Some(name) == skip {
            continue;
        }
        match replace {
            Some((r, s, d)) if r == name => put(w, name, s, d),
            _ => put(w, name, &shape, &data),
        }
    }
}

fn dir() -> tempfile::TempDir {
    tempfile::tempdir().expect("tempdir")
}

/// The error is a BadField for `path` whose field contains `field`, and says both.
fn assert_bad_field(result: Result<impl std::fmt::Debug, ImportError>, path: &Path, field: &str) {
    let err = result.expect_err("expected an error");
    let msg = err.to_string();
    match &err {
        ImportError::BadField {
            path: p, field: f, ..
        } => {
            assert_eq!(p, path, "{msg}");
            assert!(
                f.contains(field),
                "field {f:?} should name {field:?}: {msg}"
            );
        }
        other => panic!("expected BadField naming {field}, got {other:?}"),
    }
    assert!(msg.contains(&path.display().to_string()), "{msg}");
    assert!(msg.contains(field), "{msg}");
}

// ---------------------------------------------------------------- npz

#[test]
fn a_float64_npz_gives_fps_root_from_body_0_and_columns_in_isaaclab_order() {
    let d = dir();
    let path = d.path().join("walk.npz");
    write_f64_npz(&path, None, None);
    let m = read_beyondmimic_npz(&path, None).expect("reads");
    assert_eq!(m.fps, 50.0);
    assert_eq!(
        m.joint_names,
        ISAACLAB_G1_JOINT_ORDER.map(String::from).to_vec()
    );
    assert_eq!(m.joint_pos.len(), T);
    assert_eq!(m.joint_pos[2][9], 209.0, "frame 2, column 9");
    assert_eq!(m.joint_vel.as_ref().map(|v| v[1][0]), Some(-29.0));
    // Body 0, not body 1 (which sits 10 m further along x), and wxyz kept as is.
    assert_eq!(
        m.root_pos,
        vec![[0.0, 1.0, 2.0], [1.0, 2.0, 3.0], [2.0, 3.0, 4.0]]
    );
    assert_eq!(m.root_quat_wxyz[1], [1.0, 0.1, 0.2, 0.0]);
    let p = &m.provenance;
    assert_eq!(p["format"], "beyondmimic-npz");
    assert_eq!(p["source_file"], path.display().to_string());
    assert_eq!(
        (p["frames"].as_u64(), p["source_fps"].as_f64()),
        (Some(3), Some(50.0))
    );
    assert_eq!(p["joint_order"], "isaaclab");
}

#[test]
fn a_float32_npz_with_an_integer_scalar_fps_reads_the_same_numbers() {
    let d = dir();
    let path = d.path().join("walk32.npz");
    let mut w = NpzWriter::create(&path).expect("create");
    put(&mut w, "fps", &[], &[30i64]);
    for ((name, shape), data) in NAMES.iter().zip(shapes()).zip(motion()) {
        let data32: Vec<f32> = data.iter().map(|&v| v as f32).collect();
        put(&mut w, name, &shape, &data32);
    }
    w.zip_writer().finish().expect("finish");
    let m = read_beyondmimic_npz(&path, None).expect("reads");
    assert_eq!(m.fps, 30.0);
    assert_eq!(m.joint_pos[2][28], 228.0);
    assert_eq!(m.root_pos[2], [2.0, 3.0, 4.0]);
    assert_eq!(
        m.root_quat_wxyz[1][1],
        f64::from(0.1f32),
        "f32 widened exactly"
    );
}

#[test]
fn the_isaaclab_order_maps_by_name_onto_unitree_motor_indices() {
    // unitree_rl_lab deploy.yaml `joint_ids_map`: IsaacLab column i is motor (canonical) index.
    let ids_map = [
        0, 6, 12, 1, 7, 13, 2, 8, 14, 3, 9, 15, 22, 4, 10, 16, 23, 5, 11, 17, 24, 18, 25, 19, 26,
        20, 27, 21, 28,
    ];
    let by_name: Vec<usize> = ISAACLAB_G1_JOINT_ORDER
        .iter()
        .map(|n| {
            G1_CANONICAL_JOINTS
                .iter()
                .position(|c| c == n)
                .expect("same joint set")
        })
        .collect();
    assert_eq!(by_name, ids_map);
    // And a file read in IsaacLab order lands on the right canonical joints by name.
    let d = dir();
    let path = d.path().join("walk.npz");
    write_f64_npz(&path, None, None);
    let m = read_beyondmimic_npz(&path, None).expect("reads");
    let col = |n: &str| m.joint_names.iter().position(|c| c == n).expect("named");
    assert_eq!(m.joint_pos[0][col("left_knee_joint")], 9.0);
    assert_eq!(m.joint_pos[0][col("waist_yaw_joint")], 2.0);
    assert_eq!(m.joint_pos[0][col("right_wrist_yaw_joint")], 28.0);
}

#[test]
fn given_joint_names_are_used_and_a_wrong_count_names_joint_names() {
    let d = dir();
    let path = d.path().join("walk.npz");
    write_f64_npz(&path, None, None);
    let canonical: Vec<String> = G1_CANONICAL_JOINTS.map(String::from).to_vec();
    let m = read_beyondmimic_npz(&path, Some(&canonical)).expect("reads");
    assert_eq!(m.joint_names, canonical);
    assert_eq!(m.provenance["joint_order"], "given");
    assert_bad_field(
        read_beyondmimic_npz(&path, Some(&canonical[..28])),
        &path,
        "joint_names",
    );
    let mut dup = canonical.clone();
    dup[1] = dup[0].clone();
    assert_bad_field(
        read_beyondmimic_npz(&path, Some(&dup)),
        &path,
        "joint_names",
    );
}

#[test]
fn wrong_shapes_missing_arrays_and_bad_values_name_the_array() {
    let d = dir();
    let path = d.path().join("bad.npz");
    let flat: Vec<f64> = vec![0.0; T * J];
    let quat3: Vec<f64> = vec![0.0; T * B * 3];
    let nan: Vec<f64> = (0..T * B * 3)
        .map(|i| if i == 4 { f64::NAN } else { 0.0 })
        .collect();
    let cases: [(&str, Option<&str>, Option<Member>); 9] = [
        (
            "joint_pos",
            None,
            Some(("joint_pos", &[(T * J) as u64], &flat)),
        ),
        (
            "joint_pos",
            None,
            Some(("joint_pos", &[T as u64, 29, 1], &flat)),
        ),
        (
            "joint_vel",
            None,
            Some(("joint_vel", &[1, (T * J) as u64], &flat)),
        ),
        (
            "body_quat_w",
            None,
            Some(("body_quat_w", &[T as u64, B as u64, 3], &quat3)),
        ),
        (
            "body_pos_w",
            None,
            Some(("body_pos_w", &[T as u64, 3, B as u64], &quat3)),
        ),
        (
            "body_pos_w",
            None,
            Some(("body_pos_w", &[T as u64, B as u64, 3], &nan)),
        ),
        ("fps", None, Some(("fps", &[2], &[50.0, 50.0]))),
        ("fps", None, Some(("fps", &[1], &[0.0]))),
        ("body_quat_w", Some("body_quat_w"), None),
    ];
    for (field, skip, replace) in cases {
        write_f64_npz(&path, skip, replace);
        assert_bad_field(read_beyondmimic_npz(&path, None), &path, field);
    }
    // joint_vel is optional.
    write_f64_npz(&path, Some("joint_vel"), None);
    let m = read_beyondmimic_npz(&path, None).expect("reads without joint_vel");
    assert!(m.joint_vel.is_none());
}

#[test]
fn an_unsupported_dtype_names_the_array() {
    let d = dir();
    let path = d.path().join("u8.npz");
    let mut w = NpzWriter::create(&path).expect("create");
    put(&mut w, "fps", &[1], &[50u8]);
    w.zip_writer().finish().expect("finish");
    assert_bad_field(read_beyondmimic_npz(&path, None), &path, "fps");
}

#[test]
fn an_npz_written_by_numpy_reads_including_fortran_order_and_compression() {
    let d = dir();
    let path = d.path().join("numpy.npz");
    let script = r#"
import sys, numpy as np
T, B, J = 3, 2, 29
jp = (np.arange(T)[:, None] * 100 + np.arange(J)[None, :]).astype(np.float32)
bp = np.zeros((T, B, 3)); bp[:, 0, 0] = np.arange(T); bp[:, 1, 0] = 10
bq = np.zeros((T, B, 4)); bq[..., 0] = 1.0; bq[:, 0, 3] = 0.5
np.savez_compressed(sys.argv[1], fps=np.array([50]), joint_pos=np.asfortranarray(jp),
    joint_vel=np.zeros((T, J)), body_pos_w=bp, body_quat_w=bq,
    body_lin_vel_w=np.zeros((T, B, 3)), body_ang_vel_w=np.zeros((T, B, 3)))
"#;
    let ran = std::process::Command::new("python3")
        .args(["-c", script])
        .arg(&path)
        .output();
    match ran {
        Ok(out) if out.status.success() => {}
        Ok(out) => {
            let why = String::from_utf8_lossy(&out.stderr);
            let reason = format!("python3 with numpy unavailable: {}", why.trim());
            return prereq::skip("import_formats::numpy_written_npz", &reason);
        }
        Err(e) => {
            let reason = format!("python3 not runnable: {e}");
            return prereq::skip("import_formats::numpy_written_npz", &reason);
        }
    }
    let m = read_beyondmimic_npz(&path, None).expect("reads numpy output");
    assert_eq!(m.fps, 50.0);
    assert_eq!(m.joint_pos[1][2], 102.0, "Fortran-order data reordered");
    assert_eq!(m.joint_pos[2][28], 228.0);
    assert_eq!(m.root_pos[2], [2.0, 0.0, 0.0]);
    assert_eq!(m.root_quat_wxyz[0], [1.0, 0.0, 0.0, 0.5]);
}

// ---------------------------------------------------------------- LAFAN1 CSV

fn lafan_row(t: usize) -> String {
    let t = t as f64;
    let mut v = vec![t, 0.5, 0.79, 0.1, 0.2, 0.3, 0.9];
    v.extend((0..J).map(|j| t + j as f64 / 100.0));
    v.iter().map(f64::to_string).collect::<Vec<_>>().join(",")
}

fn write(dir: &Path, name: &str, text: impl AsRef<[u8]>) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).expect("write file");
    p
}

#[test]
fn a_three_row_lafan_csv_reorders_xyzw_to_wxyz_in_canonical_joint_order() {
    let d = dir();
    let rows: Vec<String> = (0..3).map(lafan_row).collect();
    let path = write(d.path(), "dance.csv", rows.join("\n") + "\n");
    let m = read_lafan_csv(&path, 30.0).expect("reads");
    assert_eq!(m.fps, 30.0);
    assert_eq!(m.root_pos[2], [2.0, 0.5, 0.79]);
    assert_eq!(m.root_quat_wxyz[0], [0.9, 0.1, 0.2, 0.3]);
    assert_eq!(
        m.joint_names,
        G1_CANONICAL_JOINTS.map(String::from).to_vec()
    );
    assert_eq!(m.joint_pos[1][3], 1.03, "row 2, left knee");
    assert!(m.joint_vel.is_none());
    assert_eq!(m.provenance["frames"], 3);
    assert_eq!(m.provenance["source_file"], path.display().to_string());
}

#[test]
fn a_lafan_row_with_the_wrong_column_count_names_its_row() {
    let d = dir();
    let short = lafan_row(1)
        .rsplit_once(',')
        .map(|(a, _)| a.to_string())
        .expect("comma");
    let path = write(
        d.path(),
        "short.csv",
        format!("{}\n{short}\n", lafan_row(0)),
    );
    assert_bad_field(read_lafan_csv(&path, 30.0), &path, "row 2");
}

#[test]
fn an_unparsable_lafan_number_names_its_row_and_column() {
    let d = dir();
    let bad = lafan_row(2).replacen("0.79", "abc", 1);
    let text = format!("{}\n{}\n{bad}\n", lafan_row(0), lafan_row(1));
    let path = write(d.path(), "bad.csv", text);
    assert_bad_field(read_lafan_csv(&path, 30.0), &path, "row 3, column 3");
    let path = write(d.path(), "inf.csv", lafan_row(0).replacen("0.5", "inf", 1));
    assert_bad_field(read_lafan_csv(&path, 30.0), &path, "row 1, column 2");
}

#[test]
fn an_empty_lafan_file_a_bad_fps_and_a_missing_file_are_errors_naming_the_file() {
    let d = dir();
    let empty = write(d.path(), "empty.csv", "");
    let err = read_lafan_csv(&empty, 30.0).expect_err("empty");
    assert!(matches!(err, ImportError::Format { .. }), "{err:?}");
    assert!(err.to_string().contains(&empty.display().to_string()));
    let ok = write(d.path(), "ok.csv", lafan_row(0));
    assert_bad_field(read_lafan_csv(&ok, 0.0), &ok, "fps");
    let missing = d.path().join("missing.csv");
    let err = read_lafan_csv(&missing, 30.0).expect_err("missing");
    assert!(matches!(err, ImportError::Io { .. }), "{err:?}");
    assert!(err.to_string().contains(&missing.display().to_string()));
}

// ---------------------------------------------------------------- force CSV

#[test]
fn a_force_log_reads_the_same_with_or_without_a_header_and_ignores_torques() {
    let d = dir();
    let body = "0.00,1,2,3\n0.01,4,5,6\n0.02,7,8,9\n";
    let bare = read_force_csv(&write(d.path(), "bare.csv", body)).expect("no header");
    let with = read_force_csv(&write(d.path(), "h.csv", format!("time,fx,fy,fz\n{body}")));
    assert_eq!(with.expect("header"), bare);
    let torques =
        "timestamp,fx,fy,fz,tx,ty,tz\n0.00,1,2,3,9,9,9\n0.01,4,5,6,9,9,9\n0.02,7,8,9,9,9,9\n";
    let ts = read_force_csv(&write(d.path(), "ft.csv", torques)).expect("with torques");
    assert_eq!(ts.time_s, bare.time_s);
    assert_eq!(ts.force_n, bare.force_n);
    assert_eq!(bare.time_s, vec![0.0, 0.01, 0.02]);
    assert_eq!(bare.force_n[1], [4.0, 5.0, 6.0]);
}

#[test]
fn a_force_log_whose_time_does_not_increase_names_the_row() {
    let d = dir();
    let path = write(
        d.path(),
        "back.csv",
        "time,fx,fy,fz\n0.0,1,2,3\n0.1,1,2,3\n0.1,1,2,3\n",
    );
    assert_bad_field(read_force_csv(&path), &path, "row 4, column 1");
    let path = write(d.path(), "down.csv", "0.5,1,2,3\n0.2,1,2,3\n");
    assert_bad_field(read_force_csv(&path), &path, "row 2");
}

#[test]
fn malformed_force_rows_name_row_and_column() {
    let d = dir();
    let path = write(d.path(), "cols.csv", "0.0,1,2,3\n0.1,1,2\n");
    assert_bad_field(read_force_csv(&path), &path, "row 2");
    let path = write(d.path(), "num.csv", "t,fx,fy,fz\n0.0,1,2,3\n0.1,1,x,3\n");
    assert_bad_field(read_force_csv(&path), &path, "row 3, column 3");
    let path = write(d.path(), "hdr.csv", "time,fx\n0.0,1\n");
    assert_bad_field(read_force_csv(&path), &path, "row 1");
    let header_only = write(d.path(), "only.csv", "time,fx,fy,fz\n");
    let err = read_force_csv(&header_only).expect_err("no data");
    assert!(
        err.to_string().contains(&header_only.display().to_string()),
        "{err}"
    );
}

fn log() -> ForceLog {
    ForceLog {
        time_s: vec![1.0, 2.0, 4.0],
        force_n: vec![[0.0, 10.0, -2.0], [10.0, 10.0, 0.0], [30.0, 0.0, 4.0]],
    }
}

#[test]
fn resampling_hits_exact_samples_and_interpolates_midpoints() {
    let (f, outside) = log().resample(&[1.0, 2.0, 4.0, 1.5, 3.0, 3.5], 0.0);
    assert_eq!(outside, 0);
    assert_eq!(
        f[..3],
        [[0.0, 10.0, -2.0], [10.0, 10.0, 0.0], [30.0, 0.0, 4.0]]
    );
    assert_eq!(f[3], [5.0, 10.0, -1.0]);
    assert_eq!(f[4], [20.0, 5.0, 2.0]);
    assert_eq!(f[5], [25.0, 2.5, 3.0]);
}

#[test]
fn resampling_is_zero_and_counted_outside_the_recorded_span() {
    let (f, outside) = log().resample(&[0.0, 0.999, 1.0, 4.0, 4.001, 100.0, f64::NAN], 0.0);
    assert_eq!(outside, 5);
    assert_eq!(f[0], [0.0; 3]);
    assert_eq!(f[1], [0.0; 3]);
    assert_eq!(f[2], [0.0, 10.0, -2.0]);
    assert_eq!(f[3], [30.0, 0.0, 4.0]);
    assert_eq!(f[4], [0.0; 3]);
    let (empty, n) = ForceLog {
        time_s: vec![],
        force_n: vec![],
    }
    .resample(&[0.0], 0.0);
    assert_eq!((empty, n), (vec![[0.0; 3]], 1));
}

#[test]
fn resampling_applies_the_offset_as_log_time_equals_motion_time_plus_offset() {
    // Motion t = 0 is log t = 1 (the first sample); motion t = 2 is log t = 3.
    let (f, outside) = log().resample(&[0.0, 0.5, 2.0, 3.0, 3.5], 1.0);
    assert_eq!(
        f[..4],
        [
            [0.0, 10.0, -2.0],
            [5.0, 10.0, -1.0],
            [20.0, 5.0, 2.0],
            [30.0, 0.0, 4.0]
        ]
    );
    assert_eq!((f[4], outside), ([0.0; 3], 1));
    // A negative offset: motion t = 3 is log t = 2.
    let (f, outside) = log().resample(&[1.5, 3.0], -1.0);
    assert_eq!((f, outside), (vec![[0.0; 3], [10.0, 10.0, 0.0]], 1));
}

// ---------------------------------------------------------------- garbage

/// Deterministic pseudo-random bytes (xorshift64*).
fn noise(seed: u64, len: usize) -> Vec<u8> {
    let mut s = seed.max(1);
    (0..len)
        .map(|_| {
            s ^= s >> 12;
            s ^= s << 25;
            s ^= s >> 27;
            (s.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 56) as u8
        })
        .collect()
}

#[test]
fn garbage_input_is_an_error_naming_the_file_never_a_panic() {
    let d = dir();
    let mut inputs: Vec<Vec<u8>> = (1..=24).map(|s| noise(s, 16 << (s % 8))).collect();
    // A real npz cut short, and one with a corrupted middle.
    let good = d.path().join("good.npz");
    write_f64_npz(&good, None, None);
    let bytes = std::fs::read(&good).expect("read npz");
    inputs.push(bytes[..bytes.len() / 2].to_vec());
    let mut corrupt = bytes.clone();
    let mid = corrupt.len() / 2;
    corrupt[mid..mid + 64].copy_from_slice(&noise(99, 64));
    inputs.push(corrupt);
    inputs.push(Vec::new());
    for (i, data) in inputs.iter().enumerate() {
        let path = write(d.path(), &format!("garbage{i}"), data);
        let name = path.display().to_string();
        if let Err(e) = read_beyondmimic_npz(&path, None) {
            assert!(e.to_string().contains(&name), "{e}");
        }
        if let Err(e) = read_lafan_csv(&path, 30.0) {
            assert!(e.to_string().contains(&name), "{e}");
        }
        if let Err(e) = read_force_csv(&path) {
            assert!(e.to_string().contains(&name), "{e}");
        }
    }
}

/// A `.npy` member written byte by byte: the version 1.0 header for `descr` and `shape`,
/// then `body`.
fn npy_bytes(descr: &str, shape: &str, body: &[u8]) -> Vec<u8> {
    let mut header = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend((header.len() as u16).to_le_bytes());
    out.extend(header.as_bytes());
    out.extend(body);
    out
}

/// The well-formed motion npz with a `joint_names` member of raw `.npy` bytes.
fn write_npz_with_names(path: &Path, names_npy: &[u8]) {
    use std::io::Write;
    let mut w = NpzWriter::create(path).expect("create npz");
    write_members(&mut w, None, None);
    let opts = FileOptions::default().compression_method(CompressionMethod::Stored);
    let zip = w.zip_writer();
    zip.start_file("joint_names.npy", opts)
        .expect("start member");
    zip.write_all(names_npy).expect("write member");
    zip.finish().expect("finish npz");
}

#[test]
fn an_npz_naming_its_joints_is_read_in_its_own_order_and_a_contradicting_list_is_refused() {
    let d = dir();
    // Fixed-width unicode (what np.savez writes for a list of str): canonical order.
    let width = 26;
    let mut utf32 = Vec::new();
    for name in G1_CANONICAL_JOINTS {
        let mut chars: Vec<u32> = name.chars().map(u32::from).collect();
        chars.resize(width, 0);
        chars.iter().for_each(|c| utf32.extend(c.to_le_bytes()));
    }
    let unicode = d.path().join("unicode.npz");
    write_npz_with_names(&unicode, &npy_bytes(&format!("<U{width}"), "(29,)", &utf32));
    // An object array (wbc-mjlab's clips): a pickle holding the list of names, here the
    // canonical order reversed (protocol 2: PROTO, EMPTY_LIST, MARK, BINUNICODE…, APPENDS).
    let mut pickle = b"\x80\x02](".to_vec();
    for name in G1_CANONICAL_JOINTS.iter().rev() {
        pickle.push(b'X');
        pickle.extend((name.len() as u32).to_le_bytes());
        pickle.extend(name.as_bytes());
    }
    pickle.extend(b"e.");
    let object = d.path().join("object.npz");
    write_npz_with_names(&object, &npy_bytes("|O", "(29,)", &pickle));

    let m = read_beyondmimic_npz(&unicode, None).expect("reads");
    assert_eq!(m.joint_names, G1_CANONICAL_JOINTS.map(String::from));
    assert_eq!(m.provenance["joint_order"], "file");
    let m = read_beyondmimic_npz(&object, None).expect("reads");
    let reversed: Vec<String> = G1_CANONICAL_JOINTS
        .iter()
        .rev()
        .map(|s| s.to_string())
        .collect();
    assert_eq!(m.joint_names, reversed);
    // Without its names this file would have been read in IsaacLab order: a different
    // joint in every column but the first. A caller's list that contradicts the file is
    // an error naming both, never a silent reordering.
    let isaac: Vec<String> = ISAACLAB_G1_JOINT_ORDER.map(String::from).to_vec();
    assert_bad_field(
        read_beyondmimic_npz(&unicode, Some(&isaac)),
        &unicode,
        "joint_names",
    );
    // The same list as the file's is fine.
    let canonical: Vec<String> = G1_CANONICAL_JOINTS.map(String::from).to_vec();
    assert!(read_beyondmimic_npz(&unicode, Some(&canonical)).is_ok());
}
