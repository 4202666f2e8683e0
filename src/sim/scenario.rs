//! Open-loop physics scenarios: fixed joint-target trajectories with no policy in the loop,
//! shared by the MuJoCo cross-check (`tools/mujoco_crosscheck.py`), the physics benchmark
//! and the tests, so all three exercise exactly the same inputs.

use crate::sim::physics::{
    armature_derived_gains, legged_gym_gains, standing_default_pose, ContactMode, PdGains, Physics,
    PhysicsSettings, PhysicsState, RapierPhysics, ResetState, RootState,
};
use crate::sim::robot::RobotModel;
use nalgebra::Isometry3;
use serde::Serialize;
use std::sync::Arc;

/// Which open-loop scenario.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Scenario {
    /// Pelvis welded 1 m above the ground, gravity on, armature-derived gains, every joint
    /// sweeping `default + 0.3·sin(2πt + 0.7·i)` for 4 s.
    FixedBase,
    /// Free robot standing on flat ground, legged-gym gains, the same sweep at amplitude
    /// 0.1 rad on legs and waist and 0.3 rad on the arms, for 2 s.
    Floating,
}

/// Control period of the scenarios' target updates (targets are held in between), s.
pub const CONTROL_DT_S: f64 = 0.02;

/// The inputs of a scenario, fully resolved.
#[derive(Debug, Clone)]
pub struct ScenarioSetup {
    /// Physics settings (the defaults, plus the scenario's base and contact choices).
    pub settings: PhysicsSettings,
    /// PD gains.
    pub gains: PdGains,
    /// Initial state.
    pub initial: ResetState,
    /// Duration, s.
    pub duration_s: f64,
    /// Joint targets, one per control step.
    pub targets: Vec<Vec<f64>>,
}

impl Scenario {
    /// Resolves the scenario for a robot and physics time step.
    pub fn setup(self, model: &RobotModel, mut settings: PhysicsSettings) -> ScenarioSetup {
        let q0 = model.default_pose();
        let (gains, initial, duration_s) = match self {
            Scenario::FixedBase => {
                settings.fixed_base = true;
                settings.contacts = ContactMode::None;
                let root = RootState::at_rest(Isometry3::translation(0.0, 0.0, 1.0));
                let initial = ResetState {
                    root,
                    q: q0.clone(),
                    qd: vec![0.0; q0.len()],
                };
                (armature_derived_gains(model, 10.0, 2.0), initial, 4.0)
            }
            Scenario::Floating => {
                settings.fixed_base = false;
                (legged_gym_gains(model), standing_default_pose(model), 2.0)
            }
        };
        let n_control = (duration_s / CONTROL_DT_S).round() as usize;
        let targets = (0..n_control)
            .map(|k| {
                let t = k as f64 * CONTROL_DT_S;
                model
                    .joints
                    .iter()
                    .enumerate()
                    .map(|(i, j)| {
                        let amplitude = match self {
                            Scenario::FixedBase => 0.3,
                            Scenario::Floating if is_arm(&j.name) => 0.3,
                            Scenario::Floating => 0.1,
                        };
                        let target = q0[i]
                            + amplitude * (2.0 * std::f64::consts::PI * t + 0.7 * i as f64).sin();
                        target.clamp(j.lower_rad, j.upper_rad)
                    })
                    .collect()
            })
            .collect();
        ScenarioSetup {
            settings,
            gains,
            initial,
            duration_s,
            targets,
        }
    }
}

fn is_arm(joint: &str) -> bool {
    ["shoulder", "elbow", "wrist"]
        .iter()
        .any(|k| joint.contains(k))
}

/// What a scenario run produced, in the JSON shape `tools/mujoco_crosscheck.py` reads.
#[derive(Debug, Clone, Serialize)]
pub struct Trace {
    /// The scenario.
    pub scenario: Scenario,
    /// Physics step, s.
    pub physics_dt_s: f64,
    /// Target update period, s.
    pub control_dt_s: f64,
    /// Duration, s.
    pub duration_s: f64,
    /// Gravity, m/s².
    pub gravity: [f64; 3],
    /// Whether the root was welded.
    pub fixed_base: bool,
    /// Joint names, canonical order.
    pub joint_names: Vec<String>,
    /// Stiffness, N·m/rad.
    pub kp: Vec<f64>,
    /// Damping, N·m·s/rad.
    pub kd: Vec<f64>,
    /// Torque limits, N·m.
    pub effort_limit: Vec<f64>,
    /// Armature, kg·m².
    pub armature: Vec<f64>,
    /// PD form.
    pub pd_form: crate::sim::physics::PdForm,
    /// Ground friction.
    pub friction: f64,
    /// Initial state.
    pub initial: TraceInitial,
    /// Targets per control step, rad.
    pub targets: Vec<Vec<f64>>,
    /// Time after each physics step, s.
    pub t: Vec<f64>,
    /// Joint angles after each physics step, rad.
    pub q: Vec<Vec<f64>>,
    /// Root (pelvis frame) position after each physics step, m.
    pub root_pos: Vec<[f64; 3]>,
    /// Root orientation after each physics step (w, x, y, z).
    pub root_quat_wxyz: Vec<[f64; 4]>,
}

/// Initial state in the trace.
#[derive(Debug, Clone, Serialize)]
pub struct TraceInitial {
    /// Root position, m.
    pub root_pos: [f64; 3],
    /// Root orientation (w, x, y, z).
    pub root_quat_wxyz: [f64; 4],
    /// Joint angles, rad.
    pub q: Vec<f64>,
    /// Joint velocities, rad/s.
    pub qd: Vec<f64>,
}

fn pos_quat(p: &Isometry3<f64>) -> ([f64; 3], [f64; 4]) {
    let t = p.translation.vector;
    let r = p.rotation;
    ([t.x, t.y, t.z], [r.w, r.i, r.j, r.k])
}

/// Why a scenario cannot run with the settings given.
#[derive(Debug, thiserror::Error)]
pub enum ScenarioError {
    /// The physics step is not positive, or longer than the 50 ms a trace can resolve.
    #[error("`option.dt_s` must be in (0, 0.05] s, got {0}")]
    PhysicsStep(f64),
    /// The solver would not iterate at all.
    #[error("`option.iterations` must be at least 1")]
    NoSolverIterations,
}

/// Runs a scenario on the rapier backend and records the trajectory.
pub fn run_scenario(
    model: Arc<RobotModel>,
    scenario: Scenario,
    settings: PhysicsSettings,
) -> Result<Trace, ScenarioError> {
    if !(settings.dt_s > 0.0 && settings.dt_s <= 0.05) {
        return Err(ScenarioError::PhysicsStep(settings.dt_s));
    }
    if settings.solver_iterations == 0 {
        return Err(ScenarioError::NoSolverIterations);
    }
    let setup = scenario.setup(&model, settings);
    let mut physics =
        RapierPhysics::new(model.clone(), setup.settings.clone(), setup.gains.clone());
    physics.reset(&setup.initial);
    let dt = setup.settings.dt_s;
    let n_steps = (setup.duration_s / dt).round() as usize;
    let (root_pos, root_quat_wxyz) = pos_quat(&setup.initial.root.world_from_root);
    let mut trace = Trace {
        scenario,
        physics_dt_s: dt,
        control_dt_s: CONTROL_DT_S,
        duration_s: setup.duration_s,
        gravity: setup.settings.gravity,
        fixed_base: setup.settings.fixed_base,
        joint_names: model.joints.iter().map(|j| j.name.clone()).collect(),
        kp: setup.gains.kp.clone(),
        kd: setup.gains.kd.clone(),
        effort_limit: setup.gains.effort_limit_nm.clone(),
        armature: model.joints.iter().map(|j| j.armature_kgm2).collect(),
        pd_form: setup.settings.pd_form,
        friction: setup.settings.friction,
        initial: TraceInitial {
            root_pos,
            root_quat_wxyz,
            q: setup.initial.q.clone(),
            qd: setup.initial.qd.clone(),
        },
        targets: setup.targets.clone(),
        t: Vec::with_capacity(n_steps),
        q: Vec::with_capacity(n_steps),
        root_pos: Vec::with_capacity(n_steps),
        root_quat_wxyz: Vec::with_capacity(n_steps),
    };
    let mut state = PhysicsState::default();
    for k in 0..n_steps {
        let c = ((k as f64 * dt) / CONTROL_DT_S + 1e-9).floor() as usize;
        physics.set_targets(&setup.targets[c.min(setup.targets.len() - 1)]);
        physics.step();
        physics.read_state(&mut state);
        let root = state.root.as_ref().expect("root state");
        let (p, r) = pos_quat(&root.world_from_root);
        trace.t.push((k + 1) as f64 * dt);
        trace.q.push(state.q.clone());
        trace.root_pos.push(p);
        trace.root_quat_wxyz.push(r);
    }
    Ok(trace)
}
