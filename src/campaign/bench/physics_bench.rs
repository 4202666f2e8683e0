//! `thorarena bench physics` as one call: one physics step of the standing robot on each
//! engine of this build (rapier; MuJoCo on the MJCF generated from the robot model, with
//! the `mujoco` feature) at each step size, with the ratio to rapier at the same step; then
//! MuJoCo's own step on the reference MJCF through its Python package, when installed.

use super::{python_mujoco_step, time_physics_steps, BenchLine, PerfError};
use crate::sim::physics::{make_physics, standing_gains, Engine, PdGains, PhysicsSettings};
use crate::sim::robot::RobotModel;
use std::path::PathBuf;
use std::sync::Arc;

/// The longest physics step timed, s: a coarser one is not a step an evaluation takes.
const MAX_DT_S: f64 = 0.05;

/// `bench physics` as asked for.
#[derive(Debug, Clone)]
pub struct PhysicsBench {
    /// Bundled robot name or robot directory.
    pub robot: String,
    /// Physics time steps, s.
    pub dt_s: Vec<f64>,
    /// Solver iterations per physics step (rapier).
    pub iterations: usize,
    /// Timed physics steps per repeat (after an untimed 1 s settle).
    pub steps: usize,
    /// Repeats; the median is reported.
    pub repeats: usize,
    /// Skip the Python MuJoCo baseline even if it is available.
    pub no_mujoco: bool,
    /// Python interpreter for the MuJoCo baseline.
    pub python: String,
    /// The reference MJCF for the Python baseline (`None`:
    /// `g1/g1_sim2sim_29dof.xml` under [`crate::reference_dir`]).
    pub mjcf: Option<PathBuf>,
}

impl PhysicsBench {
    /// Checks the request, then times each engine at each step size, handing each line to
    /// `say` as it is measured.
    pub fn run(&self, say: &mut dyn FnMut(BenchLine)) -> Result<(), PerfError> {
        if self.steps == 0 || self.repeats == 0 {
            return Err(PerfError::Precondition(
                "`option.steps` and `option.repeats` must be positive".into(),
            ));
        }
        if self.dt_s.is_empty() || !self.dt_s.iter().all(|&dt| dt > 0.0 && dt <= MAX_DT_S) {
            return Err(PerfError::Precondition(format!(
                "`option.dt` must be in (0, {MAX_DT_S}] s"
            )));
        }
        let model = Arc::new(crate::policy::registry::robot(&self.robot)?);
        let gains = standing_gains(&model);
        let mut engines = vec![Engine::Rapier];
        if cfg!(feature = "mujoco") {
            engines.push(Engine::mujoco_on(None)?);
        } else {
            say(BenchLine::Figure(
                "(this build has no MuJoCo backend: `--features mujoco` adds it to the table)"
                    .into(),
            ));
        }
        for &dt in &self.dt_s {
            self.time_engines(&model, &gains, &engines, dt, say)?;
        }
        if !self.no_mujoco {
            say(BenchLine::Figure(self.python_mujoco(&model, &gains)));
        }
        Ok(())
    }

    /// One line per engine at step `dt` s, the later ones with their cost over rapier's.
    fn time_engines(
        &self,
        model: &Arc<RobotModel>,
        gains: &PdGains,
        engines: &[Engine],
        dt: f64,
        say: &mut dyn FnMut(BenchLine),
    ) -> Result<(), PerfError> {
        let settings = PhysicsSettings {
            dt_s: dt,
            solver_iterations: self.iterations,
            ..Default::default()
        };
        let mut rapier_us = None;
        for engine in engines {
            let mut physics = make_physics(engine, model.clone(), settings.clone(), gains.clone())?;
            let t = time_physics_steps(physics.as_mut(), dt, self.steps, self.repeats);
            let ratio = match rapier_us {
                None => {
                    rapier_us = Some(t.median_us);
                    String::new()
                }
                Some(r) => format!(", {:.2}× rapier's cost", t.median_us / r),
            };
            say(BenchLine::Figure(format!(
                "{:<7} @ {:.1} ms: {:8.1} µs per step, {:.1}× real time per core{ratio} (median of {} × {} steps; repeats {:?} µs); {} contacts, pelvis z at end {:.3} m",
                engine.name(),
                dt * 1e3,
                t.median_us,
                dt / (t.median_us * 1e-6),
                self.repeats,
                self.steps,
                t.repeats_us.iter().map(|x| (x * 10.0).round() / 10.0).collect::<Vec<_>>(),
                t.contacts,
                t.pelvis_z_end_m,
            )));
        }
        Ok(())
    }

    /// MuJoCo's own step on the reference MJCF with our `gains`, or why not: a failed
    /// baseline is a line of the output, not the benchmark's failure.
    fn python_mujoco(&self, model: &RobotModel, gains: &PdGains) -> String {
        let gains_json = serde_json::json!({
            "joint_names": model.joints.iter().map(|j| j.name.as_str()).collect::<Vec<_>>(),
            "kp": gains.kp,
            "kd": gains.kd,
        })
        .to_string();
        let mjcf = self
            .mjcf
            .clone()
            .unwrap_or_else(|| crate::reference_dir().join("g1/g1_sim2sim_29dof.xml"));
        match python_mujoco_step(&self.python, &mjcf, self.repeats, &gains_json) {
            Ok(Some(mj)) => format!(
                "python mujoco on the reference MJCF: {:8.1} µs per {:.1} ms step (its own dt, same gains), pelvis z at end {:.3} m, {:.1}× real time per core",
                mj.median_us,
                mj.dt_s * 1e3,
                mj.pelvis_z_end_m,
                mj.dt_s / (mj.median_us * 1e-6)
            ),
            Ok(None) => "python mujoco: skipped (python package `mujoco` or the reference MJCF not available)".into(),
            Err(e) => format!("python mujoco: failed: {e}"),
        }
    }
}
