//! Networks that lie: a BeyondMimic policy whose `actions` output has the wrong
//! width, whose joint order names a joint twice, or whose action scale is zero is refused
//! at load, naming the file — not scored as a network answering zeros; an onnx-motion file
//! declaring a huge observation input is refused before any allocation, and one whose
//! motion outputs are not finite says so; the profile follows the policy family. The
//! networks are written by the test (`common/onnx_model.rs`).

use std::path::Path;
use std::process::{Command, Output};

#[path = "common/onnx_model.rs"]
mod onnx_model;
use onnx_model::Network;

const BIN: &str = env!("CARGO_BIN_EXE_thorarena");
const SAMPLE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/sample");

fn thorarena(args: &[&str]) -> Output {
    Command::new(BIN).args(args).output().unwrap()
}

fn error_of(o: &Output) -> String {
    let e = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(!o.status.success(), "expected an error: {e}");
    assert!(!e.contains("panicked"), "a panic: {e}");
    e
}

/// The G1's 29 joints in canonical order (`thorarena robot info`'s).
fn g1_joints() -> Vec<String> {
    let robot = thorarena::sim::robot::load_bundled("g1_29dof").unwrap();
    robot.joints.iter().map(|j| j.name.clone()).collect()
}

/// A BeyondMimic-style policy: 160 observations (the known layout for 29 joints),
/// `actions` of `width`, metadata as given.
fn beyondmimic(dir: &Path, name: &str, width: i64, metadata: Vec<(&str, String)>) -> String {
    let path = dir.join(name);
    let net = Network {
        inputs: vec![("obs", vec![1, 160])],
        outputs: vec![("actions", "obs", width, 0.0)],
        metadata,
    };
    std::fs::write(&path, net.bytes()).unwrap();
    format!("beyondmimic:{}", path.display())
}

/// `eval` of a zero-weight network (it cannot stand, so `--unchecked`: these tests are
/// about loading, not tracking).
fn eval(dir: &Path, policy: &str) -> Output {
    thorarena(&[
        "eval",
        "--unchecked",
        "--dataset",
        SAMPLE,
        "--policy",
        policy,
        "--profile",
        "beyondmimic",
        "--settings",
        "no-force",
        "--shard",
        "0/6",
        "--out",
        dir.join("run").to_str().unwrap(),
        "--overwrite",
    ])
}

#[test]
fn a_beyondmimic_network_that_cannot_act_is_refused_at_load() {
    let dir = tempfile::tempdir().unwrap();
    let names = g1_joints();
    let quoted = |v: &[String]| {
        format!(
            "[{}]",
            v.iter()
                .map(|n| format!("\"{n}\""))
                .collect::<Vec<_>>()
                .join(", ")
        )
    };
    // The fixture is sound: the right width loads and runs.
    let good = beyondmimic(
        dir.path(),
        "good.onnx",
        29,
        vec![("dof_names", quoted(&names))],
    );
    let o = eval(dir.path(), &good);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));

    let mut twice = names.clone();
    twice[1] = twice[0].clone();
    for (file, width, metadata, why) in [
        ("narrow.onnx", 28, vec![], "the `actions` output has shape"),
        ("wide.onnx", 30, vec![], "the `actions` output has shape"),
        (
            "twice.onnx",
            29,
            vec![("dof_names", quoted(&twice))],
            "named twice",
        ),
        (
            "zero.onnx",
            29,
            vec![("action_scale", "0".to_string())],
            "must be finite and non-zero",
        ),
    ] {
        let policy = beyondmimic(dir.path(), file, width, metadata);
        let e = error_of(&eval(dir.path(), &policy));
        assert!(e.contains(file) && e.contains(why), "{file}: {e}");
    }
}

/// An onnx-motion network: `time_step` [1, 1] and `obs` of `obs_dims`; the four motion
/// outputs from the time step, weights `fill`.
fn onnx_motion(dir: &Path, name: &str, obs_dims: Vec<i64>, fill: f32) -> std::path::PathBuf {
    let path = dir.join(name);
    let net = Network {
        inputs: vec![("time_step", vec![1, 1]), ("obs", obs_dims)],
        outputs: vec![
            ("joint_pos", "time_step", 29, fill),
            ("joint_vel", "time_step", 29, fill),
            ("ref_pos_xyz", "time_step", 3, fill),
            ("ref_quat_xyzw", "time_step", 4, fill),
        ],
        metadata: vec![],
    };
    std::fs::write(&path, net.bytes()).unwrap();
    path
}

fn import(dir: &Path, file: &Path) -> Output {
    thorarena(&[
        "data",
        "import",
        "--format",
        "onnx-motion",
        file.to_str().unwrap(),
        "--task",
        "dance",
        "--out",
        dir.join("ds").to_str().unwrap(),
    ])
}

#[test]
fn an_onnx_motion_file_with_a_huge_input_or_non_finite_motion_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    for dims in [vec![100_000, 100_000], vec![i64::from(i32::MAX), 4, 4]] {
        let huge = onnx_motion(dir.path(), "huge.onnx", dims.clone(), 0.0);
        let start = std::time::Instant::now();
        let e = error_of(&import(dir.path(), &huge));
        assert!(
            e.contains("huge.onnx") && e.contains("not a policy's observation"),
            "{dims:?}: {e}"
        );
        assert!(
            start.elapsed().as_secs() < 30,
            "it took {:?}",
            start.elapsed()
        );
    }
    let nan = onnx_motion(dir.path(), "nan.onnx", vec![1, 8], f32::NAN);
    let e = error_of(&import(dir.path(), &nan));
    assert!(
        e.contains("nan.onnx") && e.contains("is not finite at step 0"),
        "{e}"
    );
}

#[test]
fn the_profile_follows_the_policy_family_and_a_contradiction_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let names = g1_joints();
    let quoted = format!(
        "[{}]",
        names
            .iter()
            .map(|n| format!("\"{n}\""))
            .collect::<Vec<_>>()
            .join(", ")
    );
    let policy = beyondmimic(dir.path(), "bm.onnx", 29, vec![("dof_names", quoted)]);
    let run = dir.path().join("run");
    let eval = |extra: &[&str]| {
        let mut a = vec![
            "eval",
            "--unchecked",
            "--dataset",
            SAMPLE,
            "--policy",
            &policy,
            "--settings",
            "no-force",
            "--shard",
            "0/6",
            "--out",
            run.to_str().unwrap(),
            "--overwrite",
        ];
        a.extend(extra);
        thorarena(&a)
    };
    let header = || -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("run/run.json")).unwrap())
            .unwrap()
    };
    // No --profile: the family's.
    let o = eval(&[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(header()["profile"], "beyondmimic");
    // Scored without its sanity check, and run.json says so.
    assert_eq!(header()["sanity"]["status"], "unchecked");
    assert!(header().get("profile_mismatch_ok").is_none());
    // A profile the family was not trained with: refused, unless asked for (recorded).
    let e = error_of(&eval(&["--profile", "default"]));
    assert!(
        e.contains("is neither") && e.contains("--profile-mismatch-ok"),
        "{e}"
    );
    let o = eval(&["--profile", "default", "--profile-mismatch-ok"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(header()["profile"], "default");
    assert_eq!(header()["profile_mismatch_ok"], true);
    // TWIST2 files: the twist2 profile or nothing (the file need not load to be refused).
    let e = error_of(&thorarena(&[
        "eval",
        "--dataset",
        SAMPLE,
        "--policy",
        "twist2:absent.onnx",
        "--profile",
        "default",
    ]));
    assert!(e.contains("trained for the `twist2` profile"), "{e}");
}

/// Issue 42: `policy check` never said that a network's actions were not finite (NaN
/// weights here): the robot just fell, and the report read like a bad tracker's. Now
/// every check that ran on such actions fails saying so.
#[test]
fn policy_check_says_when_a_networks_actions_are_not_finite() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("nan.onnx");
    let net = Network {
        inputs: vec![("obs", vec![1, 160])],
        outputs: vec![("actions", "obs", 29, f32::NAN)],
        metadata: vec![],
    };
    std::fs::write(&path, net.bytes()).unwrap();
    let o = thorarena(&[
        "policy",
        "check",
        "--profile",
        "beyondmimic",
        &format!("beyondmimic:{}", path.display()),
    ]);
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(!o.status.success(), "{text}");
    assert!(
        text.contains("actions were not finite on") && text.contains("first at step 0"),
        "{text}"
    );
    // And it said what it was doing while it did it.
    assert!(text.contains("policy check: track"), "{text}");
}
