//! SoftMimic (arXiv:2510.17792, github.com/Improbable-AI/softmimic, MIT): its published
//! clips imported with `data import --format softmimic-csv`, and what is refused.
//! Skipped, saying so, when `../shared/reference` is absent; never in CI.

use std::path::{Path, PathBuf};
use std::process::Command;
use thorarena::motion::Dataset;

mod common;
mod prereq;

fn thorarena(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_thorarena"))
        .args(args)
        .output()
        .expect("run thorarena")
}

/// Every clip of `softmimic/motions/`, sorted.
fn clips(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "csv"))
        .collect();
    files.sort();
    files
}

/// `data import --format softmimic-csv FILES --out OUT --task TASK [EXTRA…]`.
fn import(files: &[&Path], out: &Path, task: &str, extra: &[&str]) -> std::process::Output {
    let mut args = vec!["data", "import", "--format", "softmimic-csv"];
    args.extend(extra);
    args.extend(files.iter().map(|f| f.to_str().unwrap()));
    args.extend(["--out", out.to_str().unwrap(), "--task", task]);
    thorarena(&args)
}

#[test]
fn every_published_clip_imports_with_its_frames_and_contacts() {
    const TEST: &str = "every_published_clip_imports_with_its_frames_and_contacts";
    let Some(dir) = prereq::reference(TEST, "softmimic/motions") else {
        return;
    };
    let files = clips(&dir);
    assert!(files.len() >= 7, "{files:?}");
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("ds");
    let refs: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    // The walking clips' quaternions are off unit norm (0.977–0.984, which SoftMimic's
    // motion library normalises as it interpolates): refused unless repair is asked for.
    let run = import(&refs, &out, "softmimic", &[]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success());
    assert!(
        stderr.contains("walk.csv") && stderr.contains("--renormalize-quaternions"),
        "{stderr}"
    );
    let run = import(&refs, &out, "softmimic", &["--renormalize-quaternions"]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let ds = Dataset::open(&out, &common::g1()).unwrap();
    assert_eq!(ds.len(), files.len());
    for (i, file) in files.iter().enumerate() {
        let text = std::fs::read_to_string(file).unwrap();
        let rows: Vec<Vec<f64>> = text
            .lines()
            .filter(|l| !l.trim().is_empty())
            .map(|l| l.split(',').map(|v| v.trim().parse().unwrap()).collect())
            .collect();
        let seq = ds.load(i).unwrap();
        assert_eq!(seq.sequence_id, file.file_stem().unwrap().to_str().unwrap());
        assert_eq!(seq.fps, 30.0);
        assert_eq!(seq.joint_pos.len(), rows.len(), "{}", file.display());
        // Joints in the file's (canonical) order; the quaternion x y z w → w x y z.
        let (first, last) = (&rows[0], &rows[rows.len() - 1]);
        for (j, q) in seq.joint_pos[0].iter().enumerate() {
            assert!(
                (q - first[7 + j]).abs() < 1e-6,
                "{} joint {j}",
                file.display()
            );
        }
        let w = seq.root_quat_wxyz[rows.len() - 1];
        let norm = (last[3..7].iter().map(|v| v * v).sum::<f64>()).sqrt();
        assert!((w[0] - last[6] / norm).abs() < 1e-6, "{}", file.display());
        let contacts = &seq.provenance["foot_contact_frames"];
        let left = rows.iter().filter(|r| r[36] >= 0.5).count();
        assert_eq!(contacts["left"], left, "{}", file.display());
        assert_eq!(seq.provenance["format"], "softmimic-csv");
    }
}

#[test]
fn a_truncated_clip_is_refused_naming_its_file_and_row() {
    const TEST: &str = "a_truncated_clip_is_refused_naming_its_file_and_row";
    let Some(stand) = prereq::reference(TEST, "softmimic/motions/stand.csv") else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(stand).unwrap();
    // Cut in the middle of row 11, as a copy interrupted mid-write leaves it.
    let cut: usize = text.lines().take(10).map(|l| l.len() + 1).sum::<usize>() + 40;
    let truncated = tmp.path().join("stand_cut.csv");
    std::fs::write(&truncated, &text[..cut]).unwrap();
    let out = tmp.path().join("ds");
    let run = import(&[&truncated], &out, "stand", &[]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success());
    assert!(stderr.contains("stand_cut.csv"), "{stderr}");
    assert!(stderr.contains("row 11"), "{stderr}");
    assert!(stderr.contains("truncated"), "{stderr}");
    assert!(!out.join("manifest.json").exists(), "nothing written");

    // A contact flag outside [0, 1], and too few frames.
    let mut rows: Vec<String> = text.lines().take(5).map(str::to_string).collect();
    rows[2] = rows[2].rsplit_once(',').unwrap().0.to_string() + ",1.5";
    let flag = tmp.path().join("flag.csv");
    std::fs::write(&flag, rows.join("\n")).unwrap();
    let run = import(&[&flag], &out, "stand", &[]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success());
    assert!(stderr.contains("row 3, column 38"), "{stderr}");
    let short = tmp.path().join("short.csv");
    std::fs::write(&short, text.lines().take(2).collect::<Vec<_>>().join("\n")).unwrap();
    let run = import(&[&short], &out, "stand", &[]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success());
    assert!(
        stderr.contains("short.csv") && stderr.contains("2 frame(s)"),
        "{stderr}"
    );
}
