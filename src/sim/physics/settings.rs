//! Physics settings and their defaults.

use serde::{Deserialize, Serialize};

/// How the PD law is applied each physics step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PdForm {
    /// `clamp(kp·(q* − q), ±effort)` as an explicit torque plus `kd` as implicit joint
    /// damping. Stable at 5 ms on the G1's light wrist and ankle links (kd·dt/I > 2 there).
    Hybrid,
    /// `clamp(kp·(q* − q) − kd·q̇, ±effort)` as an explicit torque, as most trainers do at
    /// 1 ms; unstable at dt ≥ 5 ms on the G1.
    Explicit,
}

/// Which collision shapes of the robot touch the ground.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ContactMode {
    /// Only the sole shapes (the four 5 mm spheres per foot of the Unitree model).
    Soles,
    /// Every collision shape against the ground (never against the robot itself).
    AllShapes,
    /// No contacts at all (fixed-base scenarios).
    None,
}

/// Engine-independent physics settings.
///
/// The defaults are those with which the published TWIST2 policy walked in rapier as well
/// as in MuJoCo (SOURCES.md, Physics settings): 5 ms, one solver iteration, hybrid PD, sole contacts.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PhysicsSettings {
    /// Physics time step, s.
    pub dt_s: f64,
    /// Constraint solver iterations per step.
    pub solver_iterations: usize,
    /// PD form.
    pub pd_form: PdForm,
    /// Ground contacts.
    pub contacts: ContactMode,
    /// Coulomb friction coefficient between robot and ground.
    pub friction: f64,
    /// Gravity, m/s², world frame (z up).
    pub gravity: [f64; 3],
    /// Weld the root body in place (for open-loop joint tests).
    pub fixed_base: bool,
    /// Enforce the URDF joint position limits.
    pub joint_limits: bool,
}

impl Default for PhysicsSettings {
    fn default() -> Self {
        Self {
            dt_s: 0.005,
            solver_iterations: 1,
            pd_form: PdForm::Hybrid,
            contacts: ContactMode::Soles,
            friction: 1.0,
            gravity: [0.0, 0.0, -9.81],
            fixed_base: false,
            joint_limits: true,
        }
    }
}
