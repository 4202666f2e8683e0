//! Teleoperation glitches on import: root jumps faster than a human moves are refused
//! unless `--trim-glitches` is given, leading and trailing ones are then trimmed exactly,
//! interior ones never, an import is all or nothing, and `data info` reports glitches in
//! existing datasets.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use thorarena::sim::motion::import::twist_pkl::read_twist_pkl;
use thorarena::sim::motion::import::SourceFormat;
use thorarena::sim::motion::{scan_root_glitches, Dataset, DatasetWriter, Sequence, MANIFEST};

mod common;
#[path = "common/in_process.rs"]
mod in_process;
mod prereq;
use common::{g1, sample_sequence};

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The TWIST2 walks of the reference artifacts, or `None` after a recorded skip.
fn twist2_walks(test: &str) -> Option<Vec<PathBuf>> {
    let dir = prereq::reference(test, "twist2/motions")?;
    let files: Vec<PathBuf> = (1..=3)
        .map(|i| dir.join(format!("0807_yanjie_walk_00{i}.pkl")))
        .collect();
    if files.iter().all(|f| f.is_file()) {
        Some(files)
    } else {
        prereq::skip(
            test,
            &format!("TWIST2 walks not found in {}", dir.display()),
        );
        None
    }
}

/// `data import --format twist-pkl FILES --task walk --ground-correct [--trim-glitches]`
/// into `out`, in process: what it reports of trimming, or its error.
fn import_pkl(files: &[&Path], out: &Path, trim_glitches: bool) -> Result<String, String> {
    in_process::import(SourceFormat::TwistPkl, files, out, trim_glitches, true)
}

/// Largest root speed between consecutive frames, m/s.
fn max_root_speed_m_per_s(root_pos: &[[f64; 3]], fps: f64) -> f64 {
    root_pos
        .windows(2)
        .map(|w| {
            let d: f64 = (0..3).map(|i| (w[1][i] - w[0][i]).powi(2)).sum();
            d.sqrt() * fps
        })
        .fold(0.0, f64::max)
}

#[test]
fn the_released_twist2_walks_have_no_glitch_and_import_without_the_flag() {
    let Some(files) = twist2_walks(
        "import_glitches::the_released_twist2_walks_have_no_glitch_and_import_without_the_flag",
    ) else {
        return;
    };
    for f in &files {
        let raw = read_twist_pkl(f).unwrap();
        let speed = max_root_speed_m_per_s(&raw.root_pos, raw.fps);
        eprintln!(
            "{}: {} frames at {} fps, max root speed {speed:.2} m/s",
            f.display(),
            raw.root_pos.len(),
            raw.fps
        );
        assert!(scan_root_glitches(&raw.root_pos, raw.fps).is_clean());
    }
    let dir = tempfile::tempdir().unwrap();
    let paths: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    let o = import_pkl(&paths, dir.path(), false);
    let log = o.unwrap();
    assert!(!log.contains("trimmed"), "{log}");
    let ds = Dataset::open(dir.path(), &g1()).unwrap();
    for (i, f) in files.iter().enumerate() {
        let seq = ds.load(i).unwrap();
        assert_eq!(seq.n_frames(), read_twist_pkl(f).unwrap().root_pos.len());
        assert!(seq.provenance.get("trimmed_glitch_frames").is_none());
    }
}

/// Copies `walk` to `dir` (same file name) with the root of frames 0 and 1 teleported
/// metres away, by overwriting those six float64s inside the pickled `root_pos` buffer.
fn teleported_copy(walk: &Path, dir: &Path) -> PathBuf {
    let mut bytes = std::fs::read(walk).unwrap();
    let raw = read_twist_pkl(walk).unwrap();
    let le = |rows: &[[f64; 3]]| -> Vec<u8> {
        rows.iter()
            .flatten()
            .flat_map(|v| v.to_le_bytes())
            .collect()
    };
    // Frames 0 and 1 as stored (float64, C order): the pattern occurs exactly once.
    let pattern = le(&raw.root_pos[..2]);
    let hits: Vec<usize> = bytes
        .windows(pattern.len())
        .enumerate()
        .filter(|(_, w)| *w == pattern.as_slice())
        .map(|(i, _)| i)
        .collect();
    assert_eq!(
        hits.len(),
        1,
        "root_pos frames 0-1 as float64 in {}",
        walk.display()
    );
    let p2 = raw.root_pos[2];
    let teleported = [
        [p2[0] + 2.5, p2[1] + 1.0, p2[2]],
        [p2[0] - 1.5, p2[1] + 2.0, p2[2] + 0.3],
    ];
    bytes[hits[0]..hits[0] + pattern.len()].copy_from_slice(&le(&teleported));
    let out = dir.join(walk.file_name().unwrap());
    std::fs::write(&out, bytes).unwrap();
    // The reader sees exactly that change and nothing else.
    let glitched = read_twist_pkl(&out).unwrap();
    assert_eq!(glitched.root_pos[..2], teleported);
    assert_eq!(glitched.root_pos[2..], raw.root_pos[2..]);
    assert_eq!(glitched.joint_pos, raw.joint_pos);
    assert_eq!(glitched.root_quat_wxyz, raw.root_quat_wxyz);
    out
}

#[test]
fn a_walk_with_two_teleported_leading_frames_is_refused_then_trimmed_to_the_clean_walk() {
    let Some(files) = twist2_walks("import_glitches::a_walk_with_two_teleported_leading_frames_is_refused_then_trimmed_to_the_clean_walk") else { return };
    let walk = &files[0];
    let dir = tempfile::tempdir().unwrap();
    let fixture_dir = dir.path().join("fixture");
    std::fs::create_dir(&fixture_dir).unwrap();
    let fixture = teleported_copy(walk, &fixture_dir);
    let fixture_raw = read_twist_pkl(&fixture).unwrap();
    eprintln!(
        "fixture: max root speed {:.1} m/s",
        max_root_speed_m_per_s(&fixture_raw.root_pos, fixture_raw.fps)
    );

    // Refused without the flag, together with a clean walk: nothing is written.
    let refused = dir.path().join("refused");
    let o = import_pkl(&[&files[1], &fixture], &refused, false);
    let err = o.unwrap_err();
    eprintln!("{err}");
    for needle in [
        "0807_yanjie_walk_001.pkl",
        "frame 0→1",
        "frame 1→2",
        "m/s",
        "`option.trim_glitches`",
        "drop 2 leading",
    ] {
        assert!(err.contains(needle), "`{needle}` missing from: {err}");
    }
    assert!(!refused.join(MANIFEST).exists());
    assert!(!refused.join("walk").exists(), "no sequence file written");

    // Accepted with it; the sequence is the clean walk without its first two frames.
    let trimmed_dir = dir.path().join("trimmed");
    let o = import_pkl(&[&fixture], &trimmed_dir, true);
    let log = o.unwrap();
    eprintln!("{log}");
    assert!(log.contains("trimmed glitch frames: 2 leading, 0 trailing"));
    let clean_dir = dir.path().join("clean");
    let o = import_pkl(&[walk], &clean_dir, false);
    o.unwrap();
    let trimmed = Dataset::open(&trimmed_dir, &g1()).unwrap().load(0).unwrap();
    let clean = Dataset::open(&clean_dir, &g1()).unwrap().load(0).unwrap();
    assert_eq!(trimmed.n_frames(), clean.n_frames() - 2);
    assert_eq!(trimmed.joint_pos, clean.joint_pos[2..]);
    assert_eq!(trimmed.root_quat_wxyz, clean.root_quat_wxyz[2..]);
    assert_eq!(trimmed.force_sensor[0], clean.force_sensor[0][2..]);
    // The ground correction (median lowest sole point) is computed on the frames kept, so
    // dropping two frames may move it; compare heights with each file's own shift undone.
    let shift = |s: &Sequence| s.provenance["ground_shift_m"].as_f64().unwrap();
    eprintln!(
        "ground shift: clean {:+.6} m, trimmed {:+.6} m",
        shift(&clean),
        shift(&trimmed)
    );
    assert!((shift(&clean) - shift(&trimmed)).abs() < 1e-4);
    for (a, b) in trimmed.root_pos.iter().zip(&clean.root_pos[2..]) {
        assert_eq!(a[..2], b[..2]);
        let (za, zb) = (a[2] - shift(&trimmed), b[2] - shift(&clean));
        assert!((za - zb).abs() < 1e-6, "{za} vs {zb}");
    }
    let p = &trimmed.provenance["trimmed_glitch_frames"];
    assert_eq!((&p["leading"], &p["trailing"]), (&2.into(), &0.into()));

    // `data info` finds nothing left to report.
    let info = in_process::data_info(&trimmed_dir);
    assert!(info.contains("between consecutive frames): none"), "{info}");
}

/// A LAFAN-style CSV of 45 frames at 30 fps walking +x, root of frame `glitch` (if any)
/// teleported 3 m sideways.
fn write_lafan(path: &Path, glitch: Option<usize>) {
    let q0 = g1().default_pose();
    let text: String = (0..45)
        .map(|k| {
            let y = if Some(k) == glitch { 3.0 } else { 0.0 };
            let mut row = vec![0.04 * k as f64, y, 0.78, 0.0, 0.0, 0.0, 1.0];
            row.extend(&q0);
            let cells: Vec<String> = row.iter().map(|v| v.to_string()).collect();
            cells.join(",") + "\n"
        })
        .collect();
    std::fs::write(path, text).unwrap();
}

/// `data import --format lafan-csv FILES --task walk [--trim-glitches]` into `out`, in
/// process.
fn import_csv(files: &[&Path], out: &Path, trim_glitches: bool) -> Result<String, String> {
    in_process::import(
        SourceFormat::LafanCsv { fps: 30.0 },
        files,
        out,
        trim_glitches,
        false,
    )
}

#[test]
fn an_interior_glitch_is_refused_even_with_the_flag_and_nothing_is_imported() {
    let dir = tempfile::tempdir().unwrap();
    let (clean, interior) = (dir.path().join("clean.csv"), dir.path().join("mid.csv"));
    write_lafan(&clean, None);
    write_lafan(&interior, Some(22));
    let out = dir.path().join("ds");
    let o = import_csv(&[&clean, &interior], &out, true);
    let err = o.unwrap_err();
    for needle in [
        "mid.csv",
        "frame 21→22: 3.00 m (90.0 m/s)",
        "inside the motion",
        "not imported even with it",
    ] {
        assert!(err.contains(needle), "`{needle}` missing from: {err}");
    }
    assert!(!out.join(MANIFEST).exists() && !out.join("walk").exists());
}

#[test]
fn a_trailing_glitch_in_a_csv_is_trimmed_with_the_flag() {
    let dir = tempfile::tempdir().unwrap();
    let motion = dir.path().join("tail.csv");
    write_lafan(&motion, Some(44));
    let out = dir.path().join("ds");
    let o = import_csv(&[&motion], &out, false);
    let err = o.unwrap_err();
    assert!(
        err.contains("`option.trim_glitches` to drop 0 leading and 1 trailing"),
        "{err}"
    );
    let o = import_csv(&[&motion], &out, true);
    o.unwrap();
    let seq = Dataset::open(&out, &g1()).unwrap().load(0).unwrap();
    assert_eq!(seq.n_frames(), 44);
    assert_eq!(seq.provenance["trimmed_glitch_frames"]["trailing"], 1);
}

#[test]
fn data_info_reports_a_glitch_in_a_dataset_written_without_import() {
    let robot = g1();
    let dir = tempfile::tempdir().unwrap();
    let mut clean = sample_sequence(&robot, "smooth");
    clean.task = "walk".into();
    let mut glitched = sample_sequence(&robot, "jumpy");
    glitched.task = "walk".into();
    glitched.root_pos[0] = [2.0, 0.0, 0.78];
    let mut writer = DatasetWriter::create(dir.path(), &robot).unwrap();
    writer.add(&clean).unwrap();
    writer.add(&glitched).unwrap();
    writer.finish().unwrap();
    let info = in_process::data_info(dir.path());
    eprintln!("{info}");
    assert!(
        info.contains("between consecutive frames): 1 sequence(s)"),
        "{info}"
    );
    assert!(
        info.contains("walk/jumpy: frame 0→1: 1.99 m (59.7 m/s); leading 1 and trailing 0"),
        "{info}"
    );
    assert!(!info.contains("walk/smooth:"), "{info}");
}

/// Writes a copy of the walk pickle `walk` to `dir` (same file name) with two frames
/// prepended: copies of frame 0 whose roots are teleported metres away (numpy, our own
/// trusted file).
fn prepended_copy(walk: &Path, dir: &Path) -> PathBuf {
    const SCRIPT: &str = r#"
import pickle, sys
import numpy as np
src, dst = sys.argv[1], sys.argv[2]
with open(src, "rb") as f:
    d = pickle.load(f)
T = len(d["root_pos"])
for k, v in list(d.items()):
    if isinstance(v, np.ndarray) and v.ndim >= 1 and v.shape[0] == T:
        head = np.repeat(v[:1], 2, axis=0)
        if k == "root_pos":
            head = head + np.array([[2.5, 1.0, 0.0], [-1.5, 2.0, 0.3]])
        d[k] = np.concatenate([head.astype(v.dtype), v], axis=0)
with open(dst, "wb") as f:
    pickle.dump(d, f)
"#;
    let out = dir.join(walk.file_name().unwrap());
    let o = Command::new("python3")
        .args(["-c", SCRIPT])
        .arg(walk)
        .arg(&out)
        .output()
        .expect("python3 runs");
    assert!(o.status.success(), "{}", stderr(&o));
    out
}

#[test]
fn two_teleported_frames_before_a_walk_are_trimmed_to_the_same_episode() {
    const TEST: &str =
        "import_glitches::two_teleported_frames_before_a_walk_are_trimmed_to_the_same_episode";
    let Some(files) = twist2_walks(TEST) else {
        return;
    };
    if !prereq::python_modules(TEST, &["numpy"], "pip install numpy") {
        return;
    }
    let walk = &files[1];
    let dir = tempfile::tempdir().unwrap();
    let fixture_dir = dir.path().join("fixture");
    std::fs::create_dir(&fixture_dir).unwrap();
    let fixture = prepended_copy(walk, &fixture_dir);

    let refused = import_pkl(&[&fixture], &dir.path().join("refused"), false);
    let refused = refused.unwrap_err();
    assert!(refused.contains("`option.trim_glitches`"), "{refused}");

    let (clean, trimmed) = (dir.path().join("clean"), dir.path().join("trimmed"));
    let o = import_pkl(&[walk], &clean, false);
    o.unwrap();
    let o = import_pkl(&[&fixture], &trimmed, true);
    o.unwrap();
    let a = Dataset::open(&clean, &g1()).unwrap().load(0).unwrap();
    let b = Dataset::open(&trimmed, &g1()).unwrap().load(0).unwrap();
    assert_eq!(
        a.root_pos, b.root_pos,
        "the ground correction sees the same frames"
    );
    assert_eq!(a.joint_pos, b.joint_pos);
    assert_eq!(a.root_quat_wxyz, b.root_quat_wxyz);

    // The same episode, record for record.
    let episodes = |dataset: &Path, out: &str| -> String {
        let out = dir.path().join(out);
        in_process::eval(dataset, "balance", None, &["no-force", "push:20"], &out);
        std::fs::read_to_string(out.join("episodes.jsonl")).unwrap()
    };
    let (ea, eb) = (
        episodes(&clean, "run-clean"),
        episodes(&trimmed, "run-trimmed"),
    );
    assert_eq!(ea.lines().count(), 2);
    assert_eq!(ea, eb);
}
