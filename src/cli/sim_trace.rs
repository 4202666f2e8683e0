//! `thorarena sim trace`: run an open-loop scenario and print it as JSON.

use super::choices::ScenarioArg;
use std::io::Write;
use std::sync::Arc;
use thorarena::physics::{PdForm, PhysicsSettings};
use thorarena::scenario::run_scenario;

/// Arguments of `sim trace`.
#[derive(Debug, clap::Args)]
pub struct Args {
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

/// PD form on the command line.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum PdFormArg {
    /// Explicit clamped kp torque, kd as implicit joint damping.
    Hybrid,
    /// Explicit clamped PD torque.
    Explicit,
}

pub(super) fn run(args: &Args) -> anyhow::Result<()> {
    anyhow::ensure!(
        args.dt > 0.0 && args.dt <= 0.05,
        "--dt must be in (0, 0.05] s, got {}",
        args.dt
    );
    anyhow::ensure!(args.iterations >= 1, "--iterations must be at least 1");
    let model = Arc::new(thorarena::registry::robot(&args.robot)?);
    let settings = PhysicsSettings {
        dt_s: args.dt,
        solver_iterations: args.iterations,
        pd_form: match args.pd {
            PdFormArg::Hybrid => PdForm::Hybrid,
            PdFormArg::Explicit => PdForm::Explicit,
        },
        ..PhysicsSettings::default()
    };
    let trace = run_scenario(model, args.scenario.into(), settings);
    let mut out = std::io::stdout().lock();
    serde_json::to_writer(&mut out, &trace)?;
    writeln!(out)?;
    Ok(())
}
