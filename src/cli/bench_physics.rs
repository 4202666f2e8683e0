//! `thorarena bench physics`: cost of one physics step of the standing G1, and MuJoCo's
//! cost on the reference model measured in the same run when the `mujoco` Python package
//! is installed.

use anyhow::Context;
use std::sync::Arc;
use std::time::Instant;
use thorarena::physics::{standing_default_pose, Physics, PhysicsSettings, RapierPhysics};

/// Arguments of `bench physics`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Bundled robot name or robot directory.
    #[arg(long, default_value = "g1_29dof")]
    pub robot: String,
    /// Physics time step, s.
    #[arg(long, default_value_t = PhysicsSettings::default().dt_s)]
    pub dt: f64,
    /// Solver iterations per physics step.
    #[arg(long, default_value_t = PhysicsSettings::default().solver_iterations)]
    pub iterations: usize,
    /// Timed physics steps per repeat (after a 1 s settle that is not timed).
    #[arg(long, default_value_t = 2000)]
    pub steps: usize,
    /// Repeats; the median is reported.
    #[arg(long, default_value_t = 5)]
    pub repeats: usize,
    /// Skip the MuJoCo baseline even if it is available.
    #[arg(long)]
    pub no_mujoco: bool,
    /// Python interpreter for the MuJoCo baseline.
    #[arg(long, default_value = "python3")]
    pub python: String,
    /// The reference MJCF for the MuJoCo baseline [default:
    /// $THORARENA_REFERENCE/g1/g1_sim2sim_29dof.xml, THORARENA_REFERENCE defaulting to
    /// ../shared/reference beside the checkout].
    #[arg(long)]
    pub mjcf: Option<String>,
}

pub(super) fn run(args: &Args) -> anyhow::Result<()> {
    anyhow::ensure!(
        args.steps > 0 && args.repeats > 0,
        "--steps and --repeats must be positive"
    );
    anyhow::ensure!(
        args.dt > 0.0 && args.dt <= 0.05,
        "--dt must be in (0, 0.05] s"
    );
    let model = Arc::new(super::load_robot(&args.robot)?);
    let settings = PhysicsSettings {
        dt_s: args.dt,
        solver_iterations: args.iterations,
        ..Default::default()
    };
    let gains = thorarena::physics::standing_gains(&model);
    let gains_for_mujoco = gains.clone();
    let mut physics = RapierPhysics::new(model.clone(), settings, gains);
    let start = standing_default_pose(&model);
    let mut per_repeat_us = Vec::new();
    let mut z_end = 0.0;
    let mut contacts = 0;
    for _ in 0..args.repeats {
        physics.reset(&start);
        physics.set_targets(&start.q);
        let settle = (1.0 / args.dt).round() as usize;
        for _ in 0..settle {
            physics.step();
        }
        let t0 = Instant::now();
        for _ in 0..args.steps {
            physics.step();
        }
        per_repeat_us.push(t0.elapsed().as_secs_f64() * 1e6 / args.steps as f64);
        let mut state = thorarena::physics::PhysicsState::default();
        physics.read_state(&mut state);
        z_end = state
            .root
            .as_ref()
            .map_or(0.0, |r| r.world_from_root.translation.z);
        contacts = physics.contact_count();
    }
    let ours_us = median(&mut per_repeat_us);
    let ours_rtf = args.dt / (ours_us * 1e-6);
    println!(
        "rapier  : {ours_us:8.1} µs per {:.1} ms step (median of {} × {} steps; repeats {:?} µs)",
        args.dt * 1e3,
        args.repeats,
        args.steps,
        per_repeat_us
            .iter()
            .map(|x| (x * 10.0).round() / 10.0)
            .collect::<Vec<_>>()
    );
    println!("          {} solver iteration(s), {contacts} active contacts, pelvis z at end {z_end:.3} m, {ours_rtf:.1}× real time per core",
        args.iterations);
    if args.no_mujoco {
        return Ok(());
    }
    let gains_json = serde_json::json!({
        "joint_names": model.joints.iter().map(|j| j.name.as_str()).collect::<Vec<_>>(),
        "kp": gains_for_mujoco.kp,
        "kd": gains_for_mujoco.kd,
    })
    .to_string();
    match mujoco_baseline(args, &gains_json) {
        Ok(Some((mj_us, mj_dt, mj_z))) => {
            let mj_rtf = mj_dt / (mj_us * 1e-6);
            println!(
                "mujoco  : {mj_us:8.1} µs per {:.1} ms step (reference MJCF at its own dt, same gains), pelvis z at end {mj_z:.3} m, {mj_rtf:.1}× real time per core",
                mj_dt * 1e3
            );
            println!("ratio   : rapier simulates {:.2}× as many seconds per wall second as MuJoCo (goal ≥ 2)", ours_rtf / mj_rtf);
        }
        Ok(None) => println!(
            "mujoco  : skipped (python package `mujoco` or the reference MJCF not available)"
        ),
        Err(e) => println!("mujoco  : failed: {e:#}"),
    }
    Ok(())
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Runs `tools/mujoco_step_bench.py` with our gains; returns µs per step, its dt and the
/// final pelvis height, or `None` when MuJoCo or the model is not available.
fn mujoco_baseline(args: &Args, gains_json: &str) -> anyhow::Result<Option<(f64, f64, f64)>> {
    let script =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/mujoco_step_bench.py");
    let has_mujoco = std::process::Command::new(&args.python)
        .args(["-c", "import mujoco"])
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false);
    let mjcf = args.mjcf.clone().unwrap_or_else(|| {
        thorarena::reference_dir()
            .join("g1/g1_sim2sim_29dof.xml")
            .display()
            .to_string()
    });
    if !has_mujoco || !std::path::Path::new(&mjcf).is_file() {
        return Ok(None);
    }
    let out = std::process::Command::new(&args.python)
        .arg(&script)
        .args([
            "--mjcf",
            &mjcf,
            "--repeats",
            &args.repeats.to_string(),
            "--gains-json",
            gains_json,
        ])
        .output()
        .with_context(|| format!("running {}", script.display()))?;
    anyhow::ensure!(
        out.status.success(),
        "{} failed: {}",
        script.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value =
        serde_json::from_slice(&out.stdout).context("parsing the MuJoCo benchmark's JSON")?;
    if v.get("skipped").is_some() {
        return Ok(None);
    }
    let us = v["median_us_per_step"]
        .as_f64()
        .context("no median_us_per_step in MuJoCo benchmark output")?;
    let dt = v["dt_s"]
        .as_f64()
        .context("no dt_s in MuJoCo benchmark output")?;
    let z = v["pelvis_z_end_m"].as_f64().unwrap_or(f64::NAN);
    Ok(Some((us, dt, z)))
}
