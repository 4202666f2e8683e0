//! wbc-mjlab's published general G1 tracker (`../shared/reference/wbc-mjlab/`:
//! `wbc_g1_policy.onnx` and five of the clips its deploy stack ships) end to end, in
//! process, no Python: the clips are imported in the joint order they name (a numpy object
//! array in each file), `--policy wbc-mjlab:FILE` runs under its own profile without one
//! being named, and it tracks every clip without force in rapier and in MuJoCo — survival
//! 1.0 each, keypoint errors of the two engines within 10 % of each other per clip, and
//! docs/policies.md's table of them is what was measured.
//! Skipped, saying so, when `../shared/reference` is absent or the build has no MuJoCo;
//! never in CI.

use std::path::{Path, PathBuf};
use thorarena::eval::EngineChoice;
use thorarena::policy::beyondmimic::LAYOUT_132_WBC;
use thorarena::policy::BeyondMimicPolicy;
use thorarena::sim::motion::import::SourceFormat;
use thorarena::sim::profile::ActionMode;

mod common;
#[path = "common/in_process.rs"]
mod in_process;
mod prereq;
mod readme;

const CLIPS: [&str; 5] = ["dance_01", "fight_combo_02", "idle_02", "run_01", "walk_01"];

fn onnx(test: &str) -> Option<PathBuf> {
    prereq::reference(test, "wbc-mjlab/wbc_g1_policy.onnx")
}

/// The five clips imported as task `walk` into `out`.
fn import_clips(out: &Path) {
    let dir = thorarena::reference_dir().join("wbc-mjlab/clips");
    let files: Vec<PathBuf> = CLIPS.iter().map(|c| dir.join(format!("{c}.npz"))).collect();
    let refs: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    in_process::import(
        SourceFormat::BeyondMimicNpz { joint_names: None },
        &refs,
        out,
        false,
        false,
    )
    .unwrap();
}

/// Per episode of a run: (sequence, survival, RMS keypoint error in mm), from
/// `episodes.csv` read by its header.
fn per_clip(run: &Path) -> Vec<(String, f64, f64)> {
    let text = std::fs::read_to_string(run.join("episodes.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (seq, surv, kp) = (col("sequence_id"), col("survival"), col("kp_error_rms_mm"));
    let mut rows: Vec<(String, f64, f64)> = lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (
                f[seq].to_string(),
                f[surv].parse().unwrap(),
                f[kp].parse().unwrap(),
            )
        })
        .collect();
    rows.sort_by(|a, b| a.0.cmp(&b.0));
    rows
}

#[test]
fn the_file_is_read_as_its_deploy_code_reads_it() {
    let Some(onnx) = onnx("wbc_mjlab_reference::file") else {
        return;
    };
    let robot = std::sync::Arc::new(common::g1());
    let profile = thorarena::policy::registry::profile("wbc-mjlab", &robot).unwrap();
    let policy = BeyondMimicPolicy::load(&onnx, robot, &profile).unwrap();
    assert_eq!(policy.terms(), LAYOUT_132_WBC);
    assert_eq!(policy.action_mode(), ActionMode::ReferenceResidual);
    // Its metadata (joint order, default pose, the action scale it writes five times over
    // at 3 decimals) agrees with the profile's numbers from its training config.
    assert_eq!(policy.disagreements(), [] as [String; 0]);
}

#[test]
fn wbc_mjlab_tracks_the_five_shared_clips_in_rapier_and_mujoco() {
    let Some(onnx) = onnx("wbc_mjlab_reference::tracks") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let clips = dir.path().join("clips");
    import_clips(&clips);
    // The joint order is the file's: idle_02's first frame, left leg, as its columns say
    // (hip pitch, roll, yaw, knee, ankle pitch, roll); IsaacLab's order would have put the
    // right hip pitch second.
    let robot = common::g1();
    let ds = thorarena::sim::motion::Dataset::open(&clips, &robot).unwrap();
    let idle = (0..ds.len())
        .map(|i| ds.load(i).unwrap())
        .find(|s| s.sequence_id == "idle_02")
        .unwrap();
    for (got, want) in idle.joint_pos[0][..6]
        .iter()
        .zip([0.025, 0.058, 0.167, 0.172, -0.257, -0.043])
    {
        assert!((got - want).abs() < 1e-3, "{:?}", &idle.joint_pos[0][..6]);
    }

    let policy = format!("wbc-mjlab:{}", onnx.display());
    let rapier = per_clip(&in_process::eval_on(
        EngineChoice::Rapier,
        &clips,
        &policy,
        None,
        &["no-force"],
        &dir.path().join("rapier"),
    ));
    assert_eq!(rapier.len(), CLIPS.len());
    for (clip, survival, kp) in &rapier {
        eprintln!("rapier {clip}: survival {survival:.3}, keypoint error {kp:.1} mm");
        assert_eq!(*survival, 1.0, "wbc-mjlab fell on {clip} in rapier");
    }
    if !cfg!(feature = "mujoco") {
        return prereq::skip(
            "wbc_mjlab_reference::tracks (MuJoCo half)",
            "built without the `mujoco` feature",
        );
    }
    let mujoco = per_clip(&in_process::eval_on(
        EngineChoice::Mujoco,
        &clips,
        &policy,
        None,
        &["no-force"],
        &dir.path().join("mujoco"),
    ));
    for ((clip, survival, kp), (_, _, kp_rapier)) in mujoco.iter().zip(&rapier) {
        eprintln!("mujoco {clip}: survival {survival:.3}, keypoint error {kp:.1} mm (rapier {kp_rapier:.1})");
        assert_eq!(*survival, 1.0, "wbc-mjlab fell on {clip} in MuJoCo");
        assert!(
            (kp - kp_rapier).abs() <= 0.1 * kp.max(*kp_rapier),
            "{clip}: keypoint error {kp_rapier:.1} mm in rapier, {kp:.1} mm in MuJoCo: not within 10 %"
        );
    }
    assert_eq!(readme::readme_table("wbc-mjlab-clips").len(), CLIPS.len());
    let measured: Vec<Vec<String>> = rapier
        .iter()
        .zip(&mujoco)
        .map(|(r, m)| {
            vec![
                r.0.clone(),
                format!("{:.2}", r.1),
                format!("{:.1}", r.2),
                format!("{:.2}", m.1),
                format!("{:.1}", m.2),
            ]
        })
        .collect();
    readme::assert_readme_table("wbc-mjlab-clips", &measured);
}
