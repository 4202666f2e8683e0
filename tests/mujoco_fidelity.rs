//! Fidelity against MuJoCo: runs `tools/mujoco_crosscheck.py` on our binary and requires
//! the fixed-base open-loop joint trajectories to stay within 0.005 rad RMS of MuJoCo on
//! the reference MJCF. Skips, saying why (and fails in CI), when Python's `mujoco` package
//! or the reference artifacts are missing.

use std::path::Path;
use std::process::Command;

mod prereq;

#[test]
fn rapier_tracks_mujoco_on_the_open_loop_scenarios() {
    const TEST: &str = "mujoco_fidelity";
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let Some(mjcf) = prereq::reference(TEST, "g1/g1_sim2sim_29dof.xml") else {
        return;
    };
    if !prereq::python_modules(
        TEST,
        &["mujoco", "numpy"],
        "pip install -r tools/requirements.txt",
    ) {
        return;
    }
    let out = Command::new("python3")
        .arg(root.join("tools/mujoco_crosscheck.py"))
        .args([
            "--enforce",
            "--thorarena",
            env!("CARGO_BIN_EXE_thorarena"),
            "--mjcf",
        ])
        .arg(&mjcf)
        .output()
        .expect("run the cross-check");
    let stdout = String::from_utf8_lossy(&out.stdout);
    eprintln!("{stdout}");
    let report: serde_json::Value = serde_json::from_str(&stdout).unwrap_or_else(|e| {
        panic!(
            "cross-check printed no JSON ({e}); stderr:\n{}",
            String::from_utf8_lossy(&out.stderr)
        )
    });
    let rms = report["fixed_base_rms_rad"]
        .as_f64()
        .expect("fixed_base_rms_rad");
    assert!(
        rms <= 0.005,
        "fixed-base joint RMS {rms} rad exceeds the 0.005 rad goal"
    );
    assert!(
        out.status.success(),
        "cross-check failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    // Floating base: both engines see the same pelvis trajectory (the robot, with no
    // policy, tips over after ~1.2 s in both) to within centimetres.
    let z = report["floating_pelvis_z_rms_m"]
        .as_f64()
        .expect("floating_pelvis_z_rms_m");
    let xy = report["floating_pelvis_xy_rms_m"]
        .as_f64()
        .expect("floating_pelvis_xy_rms_m");
    assert!(
        z < 0.02 && xy < 0.05,
        "floating pelvis RMS z {z} m, xy {xy} m"
    );
}
