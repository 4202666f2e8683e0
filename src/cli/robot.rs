//! The robot model's commands: `robot info` (a human-readable dump), `robot mjcf` (the
//! MJCF `eval --engine mujoco` simulates without `--mjcf`) and `sim trace` (an open-loop
//! scenario printed as JSON, for the MuJoCo cross-check).

use super::choices::{PdFormArg, ScenarioArg};
use std::io::Write;
use std::sync::Arc;
use thorarena::sim::physics::PhysicsSettings;
use thorarena::sim::scenario::run_scenario;

/// Arguments of `robot info`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Bundled robot name (under data/robots/) or a robot directory.
    #[arg(long, default_value = "g1_29dof")]
    pub robot: String,
}

/// Arguments of `robot mjcf`.
#[derive(Debug, clap::Args)]
pub struct MjcfArgs {
    /// Bundled robot name (under data/robots/) or a robot directory.
    #[arg(long, default_value = "g1_29dof")]
    pub robot: String,
    /// Physics step written into the MJCF's `<option timestep>`, s (eval sets its own).
    #[arg(long, default_value_t = thorarena::sim::physics::PhysicsSettings::default().dt_s)]
    pub physics_dt: f64,
}

/// `robot mjcf`: the generated MJCF on stdout.
pub(super) fn mjcf(args: &MjcfArgs) -> anyhow::Result<()> {
    let model = thorarena::policy::registry::robot(&args.robot)?;
    let settings = thorarena::sim::physics::PhysicsSettings {
        dt_s: args.physics_dt,
        ..Default::default()
    };
    print!("{}", thorarena::sim::physics::mjcf_of(&model, &settings));
    Ok(())
}

pub(super) fn run(args: &Args) -> anyhow::Result<()> {
    let model = thorarena::policy::registry::robot(&args.robot)?;
    print!("{}", thorarena::sim::robot::describe(&model));
    Ok(())
}

/// Arguments of `sim trace`.
#[derive(Debug, clap::Args)]
pub struct TraceArgs {
    /// Which scenario.
    #[arg(long, value_enum)]
    pub scenario: ScenarioArg,
    /// Bundled robot name or robot directory.
    #[arg(long, default_value = "g1_29dof")]
    pub robot: String,
    /// Physics time step, s.
    #[arg(long, default_value_t = PhysicsSettings::default().dt_s)]
    pub dt: f64,
    /// Solver iterations per physics step.
    #[arg(long, default_value_t = PhysicsSettings::default().solver_iterations)]
    pub iterations: usize,
    /// PD form.
    #[arg(long, value_enum, default_value = "hybrid")]
    pub pd: PdFormArg,
}

/// `sim trace`: the scenario run open loop, printed as one JSON object.
pub(super) fn trace(args: &TraceArgs) -> anyhow::Result<()> {
    let model = Arc::new(thorarena::policy::registry::robot(&args.robot)?);
    let settings = PhysicsSettings {
        dt_s: args.dt,
        solver_iterations: args.iterations,
        pd_form: args.pd.into(),
        ..PhysicsSettings::default()
    };
    let trace = run_scenario(model, args.scenario.into(), settings)
        .map_err(|e| anyhow::anyhow!(super::flags::as_flags(&e.to_string())))?;
    let mut out = std::io::stdout().lock();
    serde_json::to_writer(&mut out, &trace)?;
    writeln!(out)?;
    Ok(())
}
