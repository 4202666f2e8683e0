//! Issue 52, probe item 8: what a user reads when a value is wrong. A path that is no
//! file given as a network says so (it said "No such device (os error 19)"); a command
//! follower's check on a clip shorter than its velocity window says why it cannot judge
//! it (it failed on "root velocity error NaN"); an escape sequence in a value is shown,
//! never run by the terminal.

use std::path::{Path, PathBuf};
use std::process::Output;

mod common;

#[path = "common/onnx_model.rs"]
mod onnx_model;
use onnx_model::Network;

const SAMPLE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/sample");

fn thorarena(args: &[&str]) -> Output {
    // Elsewhere than the checkout: a run that is not refused writes nothing there.
    common::run_bin(&std::env::temp_dir(), args)
}

use common::failure as error_of;

/// A FALCON-shaped network ([1, 575] → [1, 29], weights `fill`) at `dir/falcon.onnx`.
fn falcon_network(dir: &Path) -> PathBuf {
    let path = dir.join("falcon.onnx");
    let net = Network {
        inputs: vec![("obs", vec![1, 575])],
        outputs: vec![("actions", "obs", 29, 0.0)],
        metadata: Vec::new(),
    };
    std::fs::write(&path, net.bytes()).unwrap();
    path
}

#[test]
fn a_network_path_that_is_no_file_says_what_it_is() {
    let tmp = tempfile::tempdir().unwrap();
    for (path, says) in [
        (tmp.path().to_str().unwrap(), "directory"),
        ("/dev/null", "device"),
    ] {
        let e = error_of(&thorarena(&["policy", "check", &format!("falcon:{path}")]));
        assert!(e.contains(path) && e.contains(says), "{path}: {e}");
        assert!(!e.contains("os error 19"), "{path}: {e}");
    }
}

#[test]
fn a_followers_check_on_a_clip_shorter_than_its_window_says_why() {
    let tmp = tempfile::tempdir().unwrap();
    let robot = thorarena::policy::registry::robot("g1_29dof").unwrap();
    let sample = thorarena::sim::motion::Dataset::open(Path::new(SAMPLE), &robot).unwrap();
    let seq = sample.load(0).unwrap();
    let clip = thorarena::sim::motion::force_graft::first_seconds(&seq, 0.5);
    let ds = tmp.path().join("short");
    let mut writer = thorarena::sim::motion::DatasetWriter::create(&ds, &robot).unwrap();
    writer.add(&clip).unwrap();
    writer.finish().unwrap();
    let net = falcon_network(tmp.path());
    let e = error_of(&thorarena(&[
        "policy",
        "check",
        &format!("falcon:{}", net.display()),
        "--dataset",
        ds.to_str().unwrap(),
    ]));
    assert!(
        e.contains("shorter than the 1 s window") && e.contains("--sequence"),
        "{e}"
    );
    assert!(!e.contains("NaN"), "{e}");
}

#[test]
fn an_escape_sequence_in_a_value_is_shown_not_run() {
    // ESC ]0;… retitles a terminal, ESC [2J clears it.
    let hostile = "hold\u{1b}]0;owned\u{7}\u{1b}[2J";
    // Refused by the argument parser (which strips the sequences), by the library (which
    // shows them escaped).
    for (args, escaped) in [
        (vec!["eval", "--policy", hostile], false),
        (
            vec!["eval", "--tasks", hostile, "--settings", "no-force"],
            true,
        ),
        (vec!["report", hostile], true),
    ] {
        let e = error_of(&thorarena(&args));
        assert!(
            !e.contains('\u{1b}') && !e.contains('\u{7}'),
            "{args:?}: {e:?}"
        );
        if escaped {
            assert!(
                e.contains("\\u{1b}"),
                "{args:?}: the value is not shown: {e}"
            );
        }
    }
}

/// Issue 67, item 10: numbers echoed short, settings named short, reasons said once, an
/// empty `THORARENA_DATA` taken as unset, and a file whose own name holds `@key=value`
/// still nameable.
#[test]
fn messages_echo_numbers_short_and_reasons_once() {
    let tmp = tempfile::tempdir().unwrap();
    // A huge parameter is echoed as 1e308, not in 309 digits.
    let e = error_of(&thorarena(&[
        "eval",
        "--policy",
        "falcon:F.onnx@yaw_ff=1e308",
    ]));
    assert!(e.contains("`yaw_ff` = 1e308 "), "{e}");
    assert!(!e.contains("00000000000"), "{e}");
    // A termination bound past any meaning is refused, its value short.
    let e = error_of(&thorarena(&[
        "eval",
        "--policy",
        "hold",
        "--max-torso-tilt-error",
        "1e300",
    ]));
    assert!(
        e.contains("--max-torso-tilt-error must be > 0 and at most 1000 rad")
            && e.contains("got 1e300"),
        "{e}"
    );
    // A setting whose name would be three hundred characters is refused.
    let e = error_of(&thorarena(&[
        "eval",
        "--policy",
        "hold",
        "--settings",
        "payload:1e-300",
    ]));
    assert!(
        e.contains("more digits than a setting's name carries"),
        "{e}"
    );
    // A reason is said once (anyhow's `{:#}` said it twice).
    let dir = tmp.path().to_str().unwrap();
    let e = error_of(&thorarena(&["eval", "--policy", &format!("twist2:{dir}")]));
    assert_eq!(e.matches("it is a directory, not a file").count(), 1, "{e}");
    // A file named `sm@stiffness=200.onnx` is that file, not `sm` with a parameter.
    let named = tmp.path().join("sm@stiffness=200.onnx");
    std::fs::write(&named, b"not a network").unwrap();
    let e = error_of(&thorarena(&[
        "policy",
        "check",
        &format!("softmimic:{}", named.display()),
    ]));
    assert!(e.contains(&named.display().to_string()), "{e}");
    assert!(!e.contains("parameter"), "{e}");
    // THORARENA_DATA= is unset, not the working directory.
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_thorarena"))
        .current_dir(tmp.path())
        .env("THORARENA_DATA", "")
        .args(["eval", "--dataset", SAMPLE, "--policy", "hold"])
        .args(["--settings", "no-force", "--sequences", "push_chair_000"])
        .arg("--out")
        .arg(tmp.path().join("run"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// A request file's bad setting is refused naming the reason once (the parse returns it;
/// nothing parses the text a second time to find it), and a push or coefficient with more
/// digits than a setting's name carries is refused as the force menu's numbers are.
#[test]
fn a_request_files_bad_setting_is_refused_with_its_reason_once() {
    let tmp = tempfile::tempdir().unwrap();
    for (setting, reason) in [
        (
            "event:20@0:hand=sideways",
            "hand `sideways` is not left, right or both",
        ),
        ("push:1e-300", "at most 12 characters a number"),
        ("0.1234567890123", "at most 12 characters a number"),
    ] {
        let request = tmp.path().join("request.json");
        std::fs::write(
            &request,
            format!(r#"{{"policy": "hold", "settings": ["no-force", "{setting}"]}}"#),
        )
        .unwrap();
        let e = error_of(&thorarena(&[
            "eval",
            "--request",
            request.to_str().unwrap(),
            "--out",
            tmp.path().join("run").to_str().unwrap(),
        ]));
        assert_eq!(e.matches(reason).count(), 1, "{setting}: {e}");
        assert!(e.contains(setting), "{setting}: {e}");
    }
}
