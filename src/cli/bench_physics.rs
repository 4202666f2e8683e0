//! `thorarena bench physics`: cost of one physics step of the standing G1 on each engine of
//! this build (rapier; MuJoCo on the MJCF generated from the robot model, with the `mujoco`
//! feature) at each step size, timed in the same run, with the ratio to rapier at the same
//! step; and MuJoCo's cost on the reference MJCF through its Python package, when
//! installed.

use std::path::PathBuf;
use std::sync::Arc;
use thorarena::perf::{python_mujoco_step, time_physics_steps};
use thorarena::physics::{make_physics, Engine, PhysicsSettings};

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
            let t = time_physics_steps(physics.as_mut(), dt, args.steps, args.repeats);
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
                t.pelvis_z_end_m,
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
    let mjcf = args.mjcf.clone().map_or_else(
        || thorarena::reference_dir().join("g1/g1_sim2sim_29dof.xml"),
        PathBuf::from,
    );
    match python_mujoco_step(&args.python, &mjcf, args.repeats, &gains_json) {
        Ok(Some(mj)) => {
            println!(
                "python mujoco on the reference MJCF: {:8.1} µs per {:.1} ms step (its own dt, same gains), pelvis z at end {:.3} m, {:.1}× real time per core",
                mj.median_us,
                mj.dt_s * 1e3,
                mj.pelvis_z_end_m,
                mj.dt_s / (mj.median_us * 1e-6)
            );
        }
        Ok(None) => println!(
            "python mujoco: skipped (python package `mujoco` or the reference MJCF not available)"
        ),
        Err(e) => println!("python mujoco: failed: {e}"),
    }
    Ok(())
}
