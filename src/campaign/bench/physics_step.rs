//! One physics step of the standing G1: its cost per engine and step size, and MuJoCo's
//! own cost on the reference MJCF through its Python package.

use super::{median, PerfError};
use crate::sim::physics::{standing_default_pose, Physics, PhysicsState};
use serde::Deserialize;
use std::path::Path;
use std::process::Command;
use std::time::Instant;

/// One engine at one step size.
#[derive(Debug, Clone, PartialEq)]
pub struct StepTiming {
    /// Median over the repeats, µs per step.
    pub median_us: f64,
    /// Each repeat, µs per step.
    pub repeats_us: Vec<f64>,
    /// Pelvis height at the end of the last repeat, m (a standing robot stays near
    /// 0.75 m: a fallen one means the timing is of the wrong motion).
    pub pelvis_z_end_m: f64,
    /// Contacts at the end of the last repeat.
    pub contacts: usize,
}

/// Times `steps` steps of `physics` holding the standing pose, `repeats` times, each
/// after an untimed 1 s settle from the same start.
pub fn time_physics_steps(
    physics: &mut dyn Physics,
    dt_s: f64,
    steps: usize,
    repeats: usize,
) -> StepTiming {
    let model = physics.model().clone();
    let start = standing_default_pose(&model);
    let mut repeats_us = Vec::with_capacity(repeats);
    let (mut pelvis_z_end_m, mut contacts) = (0.0, 0);
    for _ in 0..repeats {
        physics.reset(&start);
        physics.set_targets(&start.q);
        for _ in 0..(1.0 / dt_s).round() as usize {
            physics.step();
        }
        let t0 = Instant::now();
        for _ in 0..steps {
            physics.step();
        }
        repeats_us.push(t0.elapsed().as_secs_f64() * 1e6 / steps.max(1) as f64);
        let mut state = PhysicsState::default();
        physics.read_state(&mut state);
        pelvis_z_end_m = state
            .root
            .as_ref()
            .map_or(0.0, |r| r.world_from_root.translation.z);
        contacts = physics.contact_count();
    }
    StepTiming {
        median_us: median(&mut repeats_us.clone()),
        repeats_us,
        pelvis_z_end_m,
        contacts,
    }
}

/// What `tools/mujoco_step_bench.py` reports.
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct PythonMujocoTiming {
    /// Median µs per step.
    #[serde(rename = "median_us_per_step")]
    pub median_us: f64,
    /// The MJCF's own step, s.
    pub dt_s: f64,
    /// Pelvis height at the end, m.
    #[serde(rename = "pelvis_z_end_m", default = "nan")]
    pub pelvis_z_end_m: f64,
}

fn nan() -> f64 {
    f64::NAN
}

/// MuJoCo's step on `mjcf` through `python`'s `mujoco` package with our gains
/// (`gains_json`: joint names, kp, kd), or `None` when the package or the file is not
/// there.
pub fn python_mujoco_step(
    python: &str,
    mjcf: &Path,
    repeats: usize,
    gains_json: &str,
) -> Result<Option<PythonMujocoTiming>, PerfError> {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/mujoco_step_bench.py");
    let has_mujoco = Command::new(python)
        .args(["-c", "import mujoco"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !has_mujoco || !mjcf.is_file() {
        return Ok(None);
    }
    let out = Command::new(python)
        .arg(&script)
        .arg("--mjcf")
        .arg(mjcf)
        .args([
            "--repeats",
            &repeats.to_string(),
            "--gains-json",
            gains_json,
        ])
        .output()
        .map_err(PerfError::io(format!("running {}", script.display())))?;
    let failed = |message: String| PerfError::Baseline {
        script: script.clone(),
        message,
    };
    if !out.status.success() {
        return Err(failed(format!(
            "failed: {}",
            String::from_utf8_lossy(&out.stderr)
        )));
    }
    let v: serde_json::Value = serde_json::from_slice(&out.stdout)
        .map_err(|e| failed(format!("unreadable output: {e}")))?;
    if v.get("skipped").is_some() {
        return Ok(None);
    }
    serde_json::from_value(v)
        .map(Some)
        .map_err(|e| failed(format!("unexpected output: {e}")))
}
