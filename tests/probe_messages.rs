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
