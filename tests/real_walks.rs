//! The real-motion set the binary carries: TWIST2's ten published walks (`--dataset
//! real-walks`, MIT). Its content is pinned by hash, its licence travels with it into
//! every copy the binary writes out, a run on it needs nothing but the binary (no
//! reference folder), and — where the published pickles are at hand — importing them as
//! `data/real-walks/README.md` says gives the same bytes.

mod prereq;

use std::path::Path;
use std::process::Command;
use thorarena::sim::motion::{dataset_arg, Dataset};

const BIN: &str = env!("CARGO_BIN_EXE_thorarena");
const ROOT: &str = env!("CARGO_MANIFEST_DIR");
/// `Dataset::content_hash` of `data/real-walks` as committed.
const REAL_WALKS_SHA256: &str = "2205a932af069f3571965f47122539c4209f1f942aeeca728d7f075e4d93dd3b";

fn robot() -> thorarena::sim::robot::RobotModel {
    thorarena::policy::registry::robot("g1_29dof").unwrap()
}

#[test]
fn the_bundled_walks_are_pinned_by_hash_and_carry_their_licence() {
    let dir = dataset_arg("real-walks").unwrap();
    let ds = Dataset::open(&dir, &robot()).unwrap();
    assert_eq!(ds.len(), 10);
    assert_eq!(ds.content_hash(), REAL_WALKS_SHA256);
    let licence = std::fs::read_to_string(dir.join("LICENSE.TWIST2")).unwrap();
    assert!(
        licence.starts_with("MIT License") && licence.contains("Copyright (c) 2025 Yanjie Ze"),
        "{licence}"
    );
    let readme = std::fs::read_to_string(dir.join("README.md")).unwrap();
    assert!(readme.contains("amazon-far/TWIST2") && readme.contains("LICENSE.TWIST2"));
    // The copy the binary extracted is the checkout's, licence included.
    let checkout = Path::new(ROOT).join("data/real-walks/LICENSE.TWIST2");
    assert_eq!(std::fs::read_to_string(checkout).unwrap(), licence);
}

#[test]
fn eval_runs_on_the_real_walks_by_name_without_any_reference_folder() {
    let out = tempfile::tempdir().unwrap();
    let run = out.path().join("run");
    let o = Command::new(BIN)
        .current_dir(out.path())
        .env("THORARENA_REFERENCE", "/nonexistent")
        .args(["eval", "--dataset", "real-walks", "--policy", "hold"])
        .args(["--sequences", "0807_yanjie_walk_010", "--workers", "1"])
        .args(["--out", run.to_str().unwrap()])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let header: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("run.json")).unwrap()).unwrap();
    assert_eq!(header["dataset_sha256"], REAL_WALKS_SHA256, "{header}");
    // No force logs: the run says it runs them without force.
    assert_eq!(header["settings"][0]["name"], "no-force", "{header}");
    assert_eq!(header["settings"].as_array().unwrap().len(), 1, "{header}");
}

#[test]
fn importing_the_published_walks_again_gives_the_bundled_bytes() {
    let walks = thorarena::reference_dir().join("twist2-walks");
    if !walks.join("0807_yanjie_walk_001.pkl").is_file() {
        return prereq::skip(
            "real_walks::importing_the_published_walks_again_gives_the_bundled_bytes",
            &format!("no published walks at {}", walks.display()),
        );
    }
    let out = tempfile::tempdir().unwrap();
    let dir = out.path().join("real-walks");
    let mut pickles: Vec<_> = std::fs::read_dir(&walks)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "pkl"))
        .collect();
    pickles.sort();
    let o = Command::new(BIN)
        .args(["data", "import", "--format", "twist-pkl"])
        .args(&pickles)
        .args([
            "--task",
            "twist2_walk",
            "--trim-glitches",
            "--ground-correct",
        ])
        .args(["--out", dir.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let bundled = Path::new(ROOT).join("data/real-walks");
    let ds = Dataset::open(&bundled, &robot()).unwrap();
    for entry in std::iter::once("manifest.json".to_string())
        .chain(ds.manifest.sequences.iter().map(|s| s.file.clone()))
    {
        assert_eq!(
            std::fs::read(dir.join(&entry)).unwrap(),
            std::fs::read(bundled.join(&entry)).unwrap(),
            "{entry}"
        );
    }
}

/// `data list` names the bundled datasets as `--dataset` takes them, each with its
/// content hash and what it is (the licence named for the real walks).
#[test]
fn data_list_names_the_bundled_datasets() {
    let o = std::process::Command::new(BIN)
        .args(["data", "list"])
        .current_dir(std::env::temp_dir())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    let walks = text
        .lines()
        .find(|l| l.starts_with("real-walks "))
        .unwrap_or_else(|| panic!("no real-walks line:\n{text}"));
    assert!(
        walks.contains("10 sequences")
            && walks.contains(&REAL_WALKS_SHA256[..16])
            && walks.contains("LICENSE.TWIST2"),
        "{walks}"
    );
    assert!(text.lines().any(|l| l.starts_with("sample ")), "{text}");
}
