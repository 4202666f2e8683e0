//! The canonical dataset format: a sequence survives a write/read round trip, and the
//! loader rejects every kind of bad input with an error naming the file and the field —
//! lengths that disagree, NaN/Inf, non-unit quaternions, unknown or missing joints,
//! fps ≤ 0, a checksum mismatch, a truncated or foreign file, another schema version.

use serde_json::json;
use std::collections::HashMap;
use std::path::Path;
use thorarena::sim::motion::{self, DataError, Dataset, DatasetWriter, Sequence, MANIFEST};

mod common;
use common::{g1, sample_sequence};

fn write_dataset(dir: &Path, seqs: &[Sequence]) -> Dataset {
    let robot = g1();
    let mut w = DatasetWriter::create(dir, &robot).unwrap();
    for s in seqs {
        w.add(s).unwrap();
    }
    w.finish().unwrap()
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-6 * (1.0 + b.abs())
}

#[test]
fn a_sequence_survives_the_round_trip_at_float32_precision() {
    let robot = g1();
    let dir = tempfile::tempdir().unwrap();
    let seq = sample_sequence(&robot, "seq_000");
    let ds = write_dataset(dir.path(), std::slice::from_ref(&seq));
    let back = Dataset::open(dir.path(), &robot).unwrap().load(0).unwrap();
    assert_eq!(ds.len(), 1);
    assert_eq!(
        (back.task.as_str(), back.sequence_id.as_str(), back.fps),
        ("clean_table", "seq_000", 30.0)
    );
    assert_eq!(back.joint_names, seq.joint_names);
    assert_eq!(back.hand_from_sensor_wxyz, seq.hand_from_sensor_wxyz);
    assert_eq!(back.provenance, seq.provenance);
    for (a, b) in back
        .joint_pos
        .iter()
        .flatten()
        .zip(seq.joint_pos.iter().flatten())
    {
        assert!(close(*a, *b));
    }
    for (a, b) in back.force_sensor[0]
        .iter()
        .flatten()
        .zip(seq.force_sensor[0].iter().flatten())
    {
        assert!(close(*a, *b));
    }
}

#[test]
fn writing_the_same_data_twice_gives_identical_bytes() {
    let robot = g1();
    let seq = sample_sequence(&robot, "seq_000");
    let a = motion::encode_sequence(&seq, Path::new("a")).unwrap();
    let b = motion::encode_sequence(&seq, Path::new("b")).unwrap();
    assert_eq!(motion::sha256_hex(&a), motion::sha256_hex(&b));
}

/// Writes a one-sequence dataset whose sequence file is `bytes`, with a matching checksum.
fn dataset_with_file_bytes(dir: &Path, bytes: &[u8]) {
    write_dataset(dir, &[sample_sequence(&g1(), "seq_000")]);
    let file = dir.join("clean_table/seq_000.safetensors");
    std::fs::write(&file, bytes).unwrap();
    let manifest_path = dir.join(MANIFEST);
    let mut m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&manifest_path).unwrap()).unwrap();
    m["sequences"][0]["sha256"] = json!(motion::sha256_hex(bytes));
    std::fs::write(&manifest_path, serde_json::to_string(&m).unwrap()).unwrap();
}

/// A sequence file with arbitrary tensors, written with safetensors directly so it can
/// hold what our writer refuses to write.
fn raw_file(
    seq: &Sequence,
    edit: impl Fn(&mut HashMap<&'static str, (Vec<usize>, Vec<f32>)>, &mut serde_json::Value),
) -> Vec<u8> {
    let good = motion::encode_sequence(seq, Path::new("x")).unwrap();
    let st = safetensors::SafeTensors::deserialize(&good).unwrap();
    let (_, header) = safetensors::SafeTensors::read_metadata(&good).unwrap();
    let mut meta: serde_json::Value =
        serde_json::from_str(&header.metadata().as_ref().unwrap()["thorarena"]).unwrap();
    let mut tensors: HashMap<&'static str, (Vec<usize>, Vec<f32>)> = HashMap::new();
    for name in [
        "root_pos",
        "root_quat_wxyz",
        "joint_pos",
        "force_left_sensor",
        "force_right_sensor",
    ] {
        let v = st.tensor(name).unwrap();
        let values = v
            .data()
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        tensors.insert(name, (v.shape().to_vec(), values));
    }
    edit(&mut tensors, &mut meta);
    let owned: Vec<(String, Vec<usize>, Vec<u8>)> = tensors
        .into_iter()
        .map(|(n, (shape, v))| {
            (
                n.to_string(),
                shape,
                v.iter().flat_map(|x| x.to_le_bytes()).collect(),
            )
        })
        .collect();
    let views: Vec<(String, safetensors::tensor::TensorView)> = owned
        .iter()
        .map(|(n, s, b)| {
            (
                n.clone(),
                safetensors::tensor::TensorView::new(safetensors::Dtype::F32, s.clone(), b)
                    .unwrap(),
            )
        })
        .collect();
    safetensors::serialize(
        views,
        Some(HashMap::from([("thorarena".to_string(), meta.to_string())])),
    )
    .unwrap()
}

fn load_error(bytes: &[u8]) -> String {
    let dir = tempfile::tempdir().unwrap();
    dataset_with_file_bytes(dir.path(), bytes);
    let ds = Dataset::open(dir.path(), &g1()).unwrap();
    let err = ds.load(0).expect_err("must be rejected");
    let msg = err.to_string();
    assert!(
        msg.contains("clean_table/seq_000.safetensors"),
        "error does not name the file: {msg}"
    );
    msg
}

#[test]
fn lengths_that_disagree_are_rejected() {
    let seq = sample_sequence(&g1(), "seq_000");
    let msg = load_error(&raw_file(&seq, |t, _| {
        let f = t.get_mut("force_left_sensor").unwrap();
        f.0[0] -= 1;
        f.1.truncate(f.1.len() - 3);
    }));
    assert!(
        msg.contains("force_left_sensor") && msg.contains("39 frames, but root_pos has 40"),
        "{msg}"
    );
}

#[test]
fn nan_and_inf_are_rejected() {
    let seq = sample_sequence(&g1(), "seq_000");
    let msg = load_error(&raw_file(&seq, |t, _| {
        t.get_mut("joint_pos").unwrap().1[100] = f32::NAN
    }));
    assert!(
        msg.contains("joint_pos") && msg.contains("frame 3, column 13 is NaN"),
        "{msg}"
    );
    let msg = load_error(&raw_file(&seq, |t, _| {
        t.get_mut("root_pos").unwrap().1[5] = f32::INFINITY
    }));
    assert!(msg.contains("root_pos") && msg.contains("inf"), "{msg}");
}

#[test]
fn quaternions_off_unit_norm_are_rejected() {
    let seq = sample_sequence(&g1(), "seq_000");
    let msg = load_error(&raw_file(&seq, |t, _| {
        t.get_mut("root_quat_wxyz").unwrap().1[4 * 7] *= 1.01
    }));
    assert!(
        msg.contains("root_quat_wxyz") && msg.contains("frame 7"),
        "{msg}"
    );
}

#[test]
fn an_fps_outside_any_frame_rate_is_rejected() {
    // 1e-300 (issue 42) made a 6e301 s motion that no evaluation finishes.
    for fps in [0.0, -30.0, 1e-300, 0.5, 1e9] {
        let seq = sample_sequence(&g1(), "seq_000");
        let msg = load_error(&raw_file(&seq, |_, m| m["fps"] = json!(fps)));
        assert!(
            msg.contains("field `fps`") && msg.contains("must be a frame rate of 1 to 1000 Hz"),
            "{fps}: {msg}"
        );
    }
}

#[test]
fn unknown_or_missing_joints_in_the_manifest_are_rejected() {
    let robot = g1();
    let dir = tempfile::tempdir().unwrap();
    write_dataset(dir.path(), &[sample_sequence(&robot, "seq_000")]);
    let path = dir.path().join(MANIFEST);
    let original = std::fs::read_to_string(&path).unwrap();
    std::fs::write(
        &path,
        original.replacen("\"left_knee_joint\"", "\"left_kne_joint\"", 1),
    )
    .unwrap();
    let msg = Dataset::open(dir.path(), &robot).unwrap_err().to_string();
    assert!(
        msg.contains("manifest.json")
            && msg.contains("joint_names[3]")
            && msg.contains("left_kne_joint"),
        "{msg}"
    );
    std::fs::write(&path, original.replacen("\"left_knee_joint\",", "", 1)).unwrap();
    let msg = Dataset::open(dir.path(), &robot).unwrap_err().to_string();
    assert!(msg.contains("missing joints: left_knee_joint"), "{msg}");
}

#[test]
fn a_changed_file_fails_its_checksum() {
    let robot = g1();
    let dir = tempfile::tempdir().unwrap();
    write_dataset(dir.path(), &[sample_sequence(&robot, "seq_000")]);
    let file = dir.path().join("clean_table/seq_000.safetensors");
    let mut bytes = std::fs::read(&file).unwrap();
    let n = bytes.len();
    bytes[n - 10] ^= 0x01;
    std::fs::write(&file, bytes).unwrap();
    let err = Dataset::open(dir.path(), &robot)
        .unwrap()
        .load(0)
        .unwrap_err();
    assert!(matches!(err, DataError::Checksum { .. }), "{err}");
    assert!(err.to_string().contains("does not match the manifest"));
}

#[test]
fn truncated_and_foreign_files_are_rejected() {
    let seq = sample_sequence(&g1(), "seq_000");
    let good = motion::encode_sequence(&seq, Path::new("x")).unwrap();
    for bytes in [
        &good[..good.len() / 2],
        &good[..5],
        b"PK\x03\x04 this is a zip, not safetensors".as_slice(),
    ] {
        let msg = load_error(bytes);
        assert!(msg.contains("not a readable safetensors file"), "{msg}");
    }
}

#[test]
fn another_schema_version_is_rejected_for_manifest_and_file() {
    let robot = g1();
    let dir = tempfile::tempdir().unwrap();
    write_dataset(dir.path(), &[sample_sequence(&robot, "seq_000")]);
    let path = dir.path().join(MANIFEST);
    let text = std::fs::read_to_string(&path)
        .unwrap()
        .replace("\"schema_version\": 1", "\"schema_version\": 7");
    std::fs::write(&path, text).unwrap();
    let err = Dataset::open(dir.path(), &robot).unwrap_err();
    assert!(
        matches!(err, DataError::SchemaVersion { found: 7, .. }),
        "{err}"
    );
    let seq = sample_sequence(&robot, "seq_000");
    let msg = load_error(&raw_file(&seq, |_, m| m["schema_version"] = json!(2)));
    assert!(msg.contains("schema version 2"), "{msg}");
}

#[test]
fn writer_refuses_invalid_sequences_and_duplicates() {
    let robot = g1();
    let dir = tempfile::tempdir().unwrap();
    let mut w = DatasetWriter::create(dir.path(), &robot).unwrap();
    let mut bad = sample_sequence(&robot, "seq_000");
    bad.joint_pos[3][2] = f64::NAN;
    assert!(w.add(&bad).unwrap_err().to_string().contains("joint_pos"));
    let good = sample_sequence(&robot, "seq_000");
    w.add(&good).unwrap();
    assert!(w
        .add(&good)
        .unwrap_err()
        .to_string()
        .contains("already in the dataset"));
}
