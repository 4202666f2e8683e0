//! `thorarena bench physics`: cost of one physics step of the standing G1 on each engine of
//! this build (rapier; MuJoCo on the MJCF generated from the robot model, with the `mujoco`
//! feature) at each step size, timed in the same run, with the ratio to rapier at the same
//! step; and MuJoCo's cost on the reference MJCF through its Python package, when
//! installed.

use anyhow::Context;
use std::sync::Arc;
use std::time::Instant;
use thorarena::physics::{
    make_physics, standing_default_pose, Engine, Physics, PhysicsSettings, PhysicsState,
};

/// Arguments of `bench physics`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Bundled robot name or robot directory.
    #[arg(long, default_value = "g1_29dof")]
    pub robot: String,
    /// Physics time steps, s, comma separated.
    #[arg(long, value_delimiter = ',', default_value = "0.001,0.005")]
    pub dt: Vec<f64>,
    /// Solver iterations per physics step (rapier).
    #[arg(long, default_value_t = PhysicsSettings::default().solver_iterations)]
    pub iterations: usize,
    /// Timed physics steps per repeat (after a 1 s settle that is not timed).
    #[arg(long, default_value_t = 2000)]
    pub steps: usize,
    /// Repeats; the median is reported.
    #[arg(long, default_value_t = 5)]
    pub repeats: usize,
    /// Skip the Python MuJoCo baseline even if it is available.
    #[arg(long)]
    pub no_mujoco: bool,
    /// Python interpreter for the MuJoCo baseline.
    #[arg(long, default_value = "python3")]
    pub python: String,
    /// The reference MJCF for the Python MuJoCo baseline [default:
    /// $THORARENA_REFERENCE/g1/g1_sim2sim_29dof.xml, THORARENA_REFERENCE defaulting to
    /// ../shared/reference beside the checkout].
    #[arg(long)]
    pub mjcf: Option<String>,
}

/// One engine at one step: median µs per step, the repeats, pelvis height and contacts at
/// the end of the last repeat.
struct Timing {
    median_us: f64,
    repeats_us: Vec<f64>,
    z_end: f64,
    contacts: usize,
}

fn time_physics(physics: &mut dyn Physics, dt: f64, args: &Args) -> Timing {
    let model = physics.model().clone();
    let start = standing_default_pose(&model);
    let mut repeats_us = Vec::new();
    let (mut z_end, mut contacts) = (0.0, 0);
    for _ in 0..args.repeats {
        physics.reset(&start);
        physics.set_targets(&start.q);
        for _ in 0..(1.0 / dt).round() as usize {
            physics.step();
        }
        let t0 = Instant::now();
        for _ in 0..args.steps {
            physics.step();
        }
        repeats_us.push(t0.elapsed().as_secs_f64() * 1e6 / args.steps as f64);
        let mut state = PhysicsState::default();
        physics.read_state(&mut state);
        z_end = state
            .root
            .as_ref()
            .map_or(0.0, |r| r.world_from_root.translation.z);
        contacts = physics.contact_count();
    }
    let mut sorted = repeats_us.clone();
    Timing {
        median_us: median(&mut sorted),
        repeats_us,
        z_end,
        contacts,
    }
}

pub(super) fn run(args: &Args) -> anyhow::Result<()> {
    anyhow::ensure!(
        args.steps > 0 && args.repeats > 0,
        "--steps and --repeats must be positive"
    );
    anyhow::ensure!(
        !args.dt.is_empty() && args.dt.iter().all(|&dt| dt > 0.0 && dt <= 0.05),
        "--dt must be in (0, 0.05] s"
    );
    let model = Arc::new(thorarena::registry::robot(&args.robot)?);
    let gains = thorarena::physics::standing_gains(&model);
    let mut engines = vec![Engine::Rapier];
    if cfg!(feature = "mujoco") {
        engines.push(Engine::mujoco_on(None)?);
    } else {
        println!("(this build has no MuJoCo backend: `--features mujoco` adds it to the table)");
    }
    for &dt in &args.dt {
        let settings = PhysicsSettings {
            dt_s: dt,
            solver_iterations: args.iterations,
            ..Default::default()
        };
        let mut rapier_us = None;
        for engine in &engines {
            let mut physics = make_physics(engine, model.clone(), settings.clone(), gains.clone())?;
            let t = time_physics(physics.as_mut(), dt, args);
            let ratio = match rapier_us {
                None => {
                    rapier_us = Some(t.median_us);
                    String::new()
                }
                Some(r) => format!(", {:.2}× rapier's cost", t.median_us / r),
            };
            println!(
                "{:<7} @ {:.1} ms: {:8.1} µs per step, {:.1}× real time per core{ratio} (median of {} × {} steps; repeats {:?} µs); {} contacts, pelvis z at end {:.3} m",
                engine.name(),
                dt * 1e3,
                t.median_us,
                dt / (t.median_us * 1e-6),
                args.repeats,
                args.steps,
                t.repeats_us.iter().map(|x| (x * 10.0).round() / 10.0).collect::<Vec<_>>(),
                t.contacts,
                t.z_end,
            );
        }
    }
    if args.no_mujoco {
        return Ok(());
    }
    let gains_json = serde_json::json!({
        "joint_names": model.joints.iter().map(|j| j.name.as_str()).collect::<Vec<_>>(),
        "kp": gains.kp,
        "kd": gains.kd,
    })
    .to_string();
    match mujoco_baseline(args, &gains_json) {
        Ok(Some((mj_us, mj_dt, mj_z))) => {
            println!(
                "python mujoco on the reference MJCF: {mj_us:8.1} µs per {:.1} ms step (its own dt, same gains), pelvis z at end {mj_z:.3} m, {:.1}× real time per core",
                mj_dt * 1e3,
                mj_dt / (mj_us * 1e-6)
            );
        }
        Ok(None) => println!(
            "python mujoco: skipped (python package `mujoco` or the reference MJCF not available)"
        ),
        Err(e) => println!("python mujoco: failed: {e:#}"),
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
