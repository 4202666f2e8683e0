//! Tests of the GMR / TWIST / TWIST2 / GMT motion-pickle importer. The importer reads
//! pickles without Python, so the tests use Python (when python3 and numpy are installed)
//! as the independent oracle: it loads each pickle with `pickle.load` and prints the arrays'
//! exact f64 bit patterns, which must equal what the importer returns. Real TWIST2 motions
//! from `../shared/reference/` are checked when that folder exists; small handmade pickles
//! cover the layout variants (numpy/float/int `fps`, GMT 23-DoF, Fortran order, float32,
//! protocol 5); bad and damaged inputs must give errors naming the file, never panics.
//! Tests that need something absent print `SKIPPED: <reason>` and pass.

use std::path::{Path, PathBuf};
use std::process::Command;

use thorarena::sim::motion::import::twist_pkl::read_twist_pkl;
use thorarena::sim::motion::import::{ImportError, RawMotion};

mod prereq;

/// Loads a pickle in Python and prints fps and the three arrays as f64 bit patterns.
const ORACLE: &str = r#"
import json, pickle, sys
import numpy as np
with open(sys.argv[1], 'rb') as f:
    d = pickle.load(f)
def bits(a):
    return np.ascontiguousarray(np.asarray(a, dtype='<f8')).view('<u8').ravel().tolist()
out = {'fps': bits([float(d['fps'])])[0], 'has_local': 'local_body_pos' in d}
for k in ('root_pos', 'root_rot', 'dof_pos'):
    out[k] = bits(d[k])
    out[k + '_shape'] = list(np.shape(d[k]))
print(json.dumps(out))
"#;

/// Writes the handmade pickles into the directory given as argv[1].
const MAKE_FIXTURES: &str = r#"
import os, pickle, sys
import numpy as np
out, T = sys.argv[1], 5
def base(n, fps):
    rot = np.tile(np.array([0.1, 0.2, 0.3, 0.9]), (T, 1))
    rot[:, 0] += np.arange(T) * 0.01
    return {'fps': fps,
            'root_pos': np.arange(T * 3, dtype=np.float64).reshape(T, 3) * 0.1 + 0.05,
            'root_rot': rot,
            'dof_pos': (np.arange(T * n, dtype=np.float64).reshape(T, n) - 7) / 8.0}
def dump(name, d, protocol=4):
    with open(os.path.join(out, name), 'wb') as f:
        pickle.dump(d, f, protocol=protocol)
d = base(29, np.float64(50.0))
d['local_body_pos'] = np.zeros((T, 38, 3))
d['link_body_list'] = ['body_%d' % i for i in range(38)]
dump('g1_29.pkl', d)
dump('gmt_23.pkl', base(23, 30.0))
dump('int_fps.pkl', base(29, 30))
d = base(29, np.float64(30.0))
for k in ('root_rot', 'dof_pos'):
    d[k] = np.asfortranarray(d[k])
assert not d['dof_pos'].flags.c_contiguous
dump('fortran.pkl', d)
dump('protocol5.pkl', d, protocol=5)
d = base(29, np.float32(25.0))
for k in ('root_pos', 'root_rot', 'dof_pos'):
    d[k] = d[k].astype(np.float32)
dump('float32.pkl', d)
d = base(29, 30.0); d['dof_pos'] = d['dof_pos'].astype('>f8'); dump('big_endian.pkl', d)
dump('list.pkl', [1.0, 2.0, 3.0])
d = base(29, 30.0); del d['dof_pos']; dump('no_dof_pos.pkl', d)
d = base(29, 30.0); d['dof_pos'] = d['dof_pos'][:4]; dump('t_mismatch.pkl', d)
dump('cols_25.pkl', base(25, 30.0))
d = base(29, 30.0); d['root_pos'] = d['root_pos'].ravel(); dump('root_pos_1d.pkl', d)
class ShortBuffer:  # pickles like a [5, 29] float64 array whose buffer lost its tail
    def __reduce__(self):
        rebuild, args, _ = np.zeros(1).__reduce__()
        return rebuild, args, (1, (5, 29), np.dtype('f8'), False, b'\0' * 100)
d = base(29, 30.0); d['dof_pos'] = ShortBuffer(); dump('short_buffer.pkl', d)
"#;

/// Runs a Python snippet; `Err` carries the reason to skip (no python3, no numpy).
fn python(script: &str, args: &[&str]) -> Result<String, String> {
    let probe = Command::new("python3")
        .args(["-c", "import numpy"])
        .output()
        .map_err(|e| format!("python3 not runnable: {e}"))?;
    if !probe.status.success() {
        return Err("python3 has no numpy".into());
    }
    let out = Command::new("python3")
        .arg("-c")
        .arg(script)
        .args(args)
        .output()
        .map_err(|e| format!("python3 not runnable: {e}"))?;
    assert!(
        out.status.success(),
        "python snippet failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
}

/// The handmade pickles, or the reason they could not be made.
fn fixtures() -> Result<(tempfile::TempDir, PathBuf), String> {
    let dir = tempfile::tempdir().map_err(|e| format!("no temp dir: {e}"))?;
    let path = dir.path().to_path_buf();
    python(MAKE_FIXTURES, &[path.to_str().ok_or("non-UTF-8 temp dir")?])?;
    Ok((dir, path))
}

fn reference_motions() -> Result<Vec<PathBuf>, String> {
    let dir = prereq::reference_dir().join("twist2/motions");
    let entries = std::fs::read_dir(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let mut files: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "pkl"))
        .collect();
    files.sort();
    if files.is_empty() {
        return Err(format!("no .pkl files in {}", dir.display()));
    }
    Ok(files)
}

fn u64s(v: &serde_json::Value) -> Vec<u64> {
    v.as_array()
        .expect("oracle array")
        .iter()
        .map(|x| x.as_u64().expect("oracle bit pattern"))
        .collect()
}

/// Asserts the import equals Python's reading bit for bit (quaternion back in xyzw).
fn assert_matches_oracle(path: &Path, m: &RawMotion) {
    let json = python(ORACLE, &[path.to_str().expect("UTF-8 path")]).expect("python available");
    let want: serde_json::Value = serde_json::from_str(&json).expect("oracle JSON");
    let name = path.display();
    assert_eq!(
        m.fps.to_bits(),
        want["fps"].as_u64().expect("fps"),
        "{name}: fps"
    );
    let frames = m.root_pos.len();
    let cols = m.joint_names.len();
    assert_eq!(u64s(&want["root_pos_shape"]), [frames as u64, 3], "{name}");
    assert_eq!(
        u64s(&want["dof_pos_shape"]),
        [frames as u64, cols as u64],
        "{name}"
    );
    let bits = |v: Vec<f64>| v.into_iter().map(f64::to_bits).collect::<Vec<u64>>();
    let pos = bits(m.root_pos.iter().flatten().copied().collect());
    let xyzw = bits(
        m.root_quat_wxyz
            .iter()
            .flat_map(|q| [q[1], q[2], q[3], q[0]])
            .collect(),
    );
    let dof = bits(m.joint_pos.iter().flatten().copied().collect());
    assert_eq!(pos, u64s(&want["root_pos"]), "{name}: root_pos");
    assert_eq!(xyzw, u64s(&want["root_rot"]), "{name}: root_rot");
    assert_eq!(dof, u64s(&want["dof_pos"]), "{name}: dof_pos");
    assert_eq!(
        m.provenance["has_local_body_pos"], want["has_local"],
        "{name}"
    );
    assert_eq!(m.provenance["frames"], frames, "{name}");
}

#[test]
fn real_twist2_motions_import_exactly_as_python_reads_them() {
    let files = match reference_motions() {
        Ok(f) => f,
        Err(reason) => {
            return prereq::skip(
                "import_twist_pkl::real_twist2_motions_import_exactly_as_python_reads_them",
                &reason,
            )
        }
    };
    if let Err(reason) = python("", &[]) {
        return prereq::skip(
            "import_twist_pkl::real_twist2_motions_import_exactly_as_python_reads_them",
            &reason,
        );
    }
    for path in files {
        let m = read_twist_pkl(&path).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(m.joint_names.len(), 29);
        assert!(m.joint_vel.is_none());
        assert_eq!(m.provenance["format"], "twist-pkl");
        assert_eq!(m.provenance["fps_decoded_from"], "numpy_scalar");
        assert_eq!(m.provenance["has_local_body_pos"], true);
        let file_name = path.file_name().and_then(|n| n.to_str()).expect("name");
        assert_eq!(m.provenance["source_file"], file_name);
        assert!((20.0..=120.0).contains(&m.fps), "implausible fps {}", m.fps);
        assert_matches_oracle(&path, &m);
        println!("{file_name}: {} frames at {} fps", m.root_pos.len(), m.fps);
    }
}

#[test]
fn handmade_pickles_of_every_layout_import_exactly() {
    let (_keep, dir) = match fixtures() {
        Ok(f) => f,
        Err(reason) => {
            return prereq::skip(
                "import_twist_pkl::handmade_pickles_of_every_layout_import_exactly",
                &reason,
            )
        }
    };
    for (file, fps_from) in [
        ("g1_29.pkl", "numpy_scalar"),
        ("gmt_23.pkl", "float"),
        ("int_fps.pkl", "int"),
        ("fortran.pkl", "numpy_scalar"),
        ("protocol5.pkl", "numpy_scalar"),
        ("float32.pkl", "numpy_scalar"),
    ] {
        let path = dir.join(file);
        let m = read_twist_pkl(&path).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(m.provenance["fps_decoded_from"], fps_from, "{file}");
        assert_eq!(m.root_pos.len(), 5, "{file}");
        assert_matches_oracle(&path, &m);
    }
}

#[test]
fn quaternions_become_wxyz_and_layouts_agree_with_the_c_ordered_file() {
    let (_keep, dir) = match fixtures() {
        Ok(f) => f,
        Err(reason) => return prereq::skip(
            "import_twist_pkl::quaternions_become_wxyz_and_layouts_agree_with_the_c_ordered_file",
            &reason,
        ),
    };
    let read = |f: &str| read_twist_pkl(&dir.join(f)).unwrap_or_else(|e| panic!("{e}"));
    let c = read("g1_29.pkl");
    assert_eq!(c.fps, 50.0);
    // The fixture's xyzw row t is (0.1 + 0.01 t, 0.2, 0.3, 0.9).
    assert_eq!(c.root_quat_wxyz[2], [0.9, 0.1 + 2.0 * 0.01, 0.2, 0.3]);
    assert_eq!(
        c.root_pos[1],
        [3.0 * 0.1 + 0.05, 4.0 * 0.1 + 0.05, 5.0 * 0.1 + 0.05]
    );
    assert_eq!(c.joint_pos[1][3], (29.0 + 3.0 - 7.0) / 8.0);
    assert_eq!(c.joint_names[0], "left_hip_pitch_joint");
    assert_eq!(c.joint_names[28], "right_wrist_yaw_joint");
    for f in ["fortran.pkl", "protocol5.pkl"] {
        let m = read(f);
        assert_eq!(m.root_quat_wxyz, c.root_quat_wxyz, "{f}");
        assert_eq!(m.joint_pos, c.joint_pos, "{f}");
    }
    let f32 = read("float32.pkl");
    assert_eq!(f32.fps, 25.0);
    assert_eq!(
        f32.joint_pos[1][3],
        f64::from(((29.0 + 3.0 - 7.0) / 8.0) as f32)
    );
}

#[test]
fn gmt_files_get_23_names_without_wrists_and_say_so_in_provenance() {
    let (_keep, dir) =
        match fixtures() {
            Ok(f) => f,
            Err(reason) => return prereq::skip(
                "import_twist_pkl::gmt_files_get_23_names_without_wrists_and_say_so_in_provenance",
                &reason,
            ),
        };
    let m = read_twist_pkl(&dir.join("gmt_23.pkl")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(m.fps, 30.0);
    assert_eq!(m.joint_names.len(), 23);
    assert!(m.joint_pos.iter().all(|row| row.len() == 23));
    assert!(m.joint_names.iter().all(|n| !n.contains("wrist")));
    assert_eq!(m.joint_names[15], "left_shoulder_pitch_joint");
    assert_eq!(m.joint_names[18], "left_elbow_joint");
    assert_eq!(m.joint_names[19], "right_shoulder_pitch_joint");
    assert_eq!(m.joint_names[22], "right_elbow_joint");
    let missing = m.provenance["missing_joints"]
        .as_array()
        .expect("missing_joints");
    assert_eq!(missing.len(), 6);
    assert!(missing
        .iter()
        .all(|n| n.as_str().is_some_and(|n| n.contains("wrist"))));
    assert!(m.provenance["note"]
        .as_str()
        .is_some_and(|n| n.contains("canonical")));
    assert_eq!(m.provenance["has_local_body_pos"], false);
}

/// Asserts the error is `BadField` on `field` and its message names the file and field.
fn assert_bad_field(dir: &Path, file: &str, field: &str) {
    match read_twist_pkl(&dir.join(file)) {
        Err(e @ ImportError::BadField { .. }) => {
            let msg = e.to_string();
            assert!(msg.contains(file) && msg.contains(field), "{file}: {msg}");
            println!("{file}: {msg}");
        }
        other => panic!("{file}: expected BadField on {field}, got {other:?}"),
    }
}

#[test]
fn malformed_motion_dicts_are_rejected_naming_the_file_and_field() {
    let (_keep, dir) =
        match fixtures() {
            Ok(f) => f,
            Err(reason) => return prereq::skip(
                "import_twist_pkl::malformed_motion_dicts_are_rejected_naming_the_file_and_field",
                &reason,
            ),
        };
    assert_bad_field(&dir, "no_dof_pos.pkl", "dof_pos");
    assert_bad_field(&dir, "t_mismatch.pkl", "dof_pos");
    assert_bad_field(&dir, "cols_25.pkl", "dof_pos");
    assert_bad_field(&dir, "root_pos_1d.pkl", "root_pos");
    assert_bad_field(&dir, "big_endian.pkl", "dof_pos");
    assert_bad_field(&dir, "short_buffer.pkl", "dof_pos");
    match read_twist_pkl(&dir.join("list.pkl")) {
        Err(e @ ImportError::Format { .. }) => {
            assert!(e.to_string().contains("list.pkl") && e.to_string().contains("list"));
        }
        other => panic!("list.pkl: expected Format, got {other:?}"),
    }
}

#[test]
fn empty_random_and_missing_files_are_errors_not_panics() {
    let dir = tempfile::tempdir().expect("temp dir");
    let empty = dir.path().join("empty.pkl");
    std::fs::write(&empty, b"").expect("write");
    assert!(matches!(
        read_twist_pkl(&empty),
        Err(ImportError::Format { .. })
    ));
    // A protocol-2 pickle of an empty list, written by hand so no Python is needed.
    let list = dir.path().join("list.pkl");
    std::fs::write(&list, b"\x80\x02]q\x00.").expect("write");
    assert!(matches!(
        read_twist_pkl(&list),
        Err(ImportError::Format { .. })
    ));
    let mut seed = 0x9e37_79b9_7f4a_7c15_u64;
    for i in 0..50 {
        let len = 1 + i * 37;
        let bytes: Vec<u8> = (0..len)
            .map(|_| {
                seed = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
                (seed >> 56) as u8
            })
            .collect();
        let path = dir.path().join(format!("random_{i}.pkl"));
        std::fs::write(&path, &bytes).expect("write");
        let err = read_twist_pkl(&path).expect_err("random bytes must not import");
        assert!(
            err.to_string().contains(&format!("random_{i}.pkl")),
            "{err}"
        );
    }
    let missing = dir.path().join("absent.pkl");
    assert!(matches!(
        read_twist_pkl(&missing),
        Err(ImportError::Io { .. })
    ));
}

#[test]
fn truncated_and_corrupted_real_files_never_panic() {
    let files = match reference_motions() {
        Ok(f) => f,
        Err(reason) => {
            return prereq::skip(
                "import_twist_pkl::truncated_and_corrupted_real_files_never_panic",
                &reason,
            )
        }
    };
    let bytes = std::fs::read(&files[0]).expect("read reference motion");
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("damaged.pkl");
    let n = bytes.len();
    let cuts = (0..n).step_by(n / 150 + 1).chain([n - 2, n - 1]);
    for cut in cuts {
        std::fs::write(&path, &bytes[..cut]).expect("write");
        assert!(
            read_twist_pkl(&path).is_err(),
            "prefix of {cut} bytes imported"
        );
    }
    // Flipped bytes may or may not still decode; they must only never panic.
    for pos in (0..n).step_by(n / 300 + 1) {
        let mut damaged = bytes.clone();
        damaged[pos] ^= 0x5a;
        std::fs::write(&path, &damaged).expect("write");
        let _ = read_twist_pkl(&path);
    }
}
