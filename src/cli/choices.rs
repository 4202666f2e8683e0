//! The command line's spellings of the library's choices: clap stays in the binary, so
//! the library's enums derive nothing from it. Each maps one to one onto the library's.

use thorarena::evaluation::{LatencyMode, MissRule};
use thorarena::scenario::Scenario;

/// `--miss-rule`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum MissRuleArg {
    /// Keep applying the last action that reached the robot.
    Hold,
    /// Apply the zero action.
    Zero,
    /// End the episode (`deadline_miss` or `invalid_action`).
    Fail,
}

impl From<MissRuleArg> for MissRule {
    fn from(a: MissRuleArg) -> Self {
        match a {
            MissRuleArg::Hold => Self::Hold,
            MissRuleArg::Zero => Self::Zero,
            MissRuleArg::Fail => Self::Fail,
        }
    }
}

/// `--latency-mode`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum LatencyModeArg {
    /// Actions act at the start of the control step (deterministic results).
    Ignore,
    /// The measured latency delays the action's effect in simulated time.
    Measured,
}

impl From<LatencyModeArg> for LatencyMode {
    fn from(a: LatencyModeArg) -> Self {
        match a {
            LatencyModeArg::Ignore => Self::Ignore,
            LatencyModeArg::Measured => Self::Measured,
        }
    }
}

/// `sim-trace --scenario`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ScenarioArg {
    /// Pelvis welded 1 m above the ground, every joint sweeping a sine for 4 s.
    FixedBase,
    /// Free robot standing on flat ground, a smaller sweep for 2 s.
    Floating,
}

impl From<ScenarioArg> for Scenario {
    fn from(a: ScenarioArg) -> Self {
        match a {
            ScenarioArg::FixedBase => Self::FixedBase,
            ScenarioArg::Floating => Self::Floating,
        }
    }
}

/// `eval --engine`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum EngineArg {
    /// rapier3d multibody on the robot model.
    Rapier,
    /// MuJoCo on the MJCF given by --mjcf (a build with the `mujoco` feature).
    Mujoco,
}

impl From<EngineArg> for thorarena::evaluation::EngineChoice {
    fn from(a: EngineArg) -> Self {
        match a {
            EngineArg::Rapier => Self::Rapier,
            EngineArg::Mujoco => Self::Mujoco,
        }
    }
}
