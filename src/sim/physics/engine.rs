//! Which engine simulates the robot, chosen per run (`eval --engine`), and the one place a
//! [`Physics`] is made for it.

use super::{PdGains, Physics, PhysicsSettings, RapierPhysics};
use crate::sim::robot::RobotModel;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;
use std::sync::Arc;

/// A physics engine and its model of the robot.
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(tag = "name", rename_all = "snake_case")]
pub enum Engine {
    /// rapier3d multibody on the robot model (the default).
    #[default]
    Rapier,
    /// MuJoCo (cargo feature `mujoco`) on an MJCF of the same robot.
    Mujoco {
        /// A user's MJCF, joints and bodies named as in the robot model; `None`: the one
        /// generated from the robot model ([`super::mjcf_of`]).
        mjcf: Option<PathBuf>,
        /// SHA-256 of the user's MJCF file ([`Engine::mujoco_on`]): a run is identified by
        /// the model's content, not its path — `--resume`, `merge` and sweeps then refuse
        /// to mix episodes simulated on two versions of one file. (Files the MJCF includes
        /// or meshes it loads are not covered.)
        #[serde(default, skip_serializing_if = "Option::is_none")]
        mjcf_sha256: Option<String>,
    },
}

impl Engine {
    /// MuJoCo on the generated MJCF (`None`) or on the user's MJCF file at `path`, read
    /// once here for its content hash.
    pub fn mujoco_on(path: Option<PathBuf>) -> Result<Self, EngineError> {
        let Some(path) = path else {
            return Ok(Self::Mujoco {
                mjcf: None,
                mjcf_sha256: None,
            });
        };
        if !path.is_file() {
            return Err(EngineError::MjcfNotAFile(path));
        }
        let bytes = std::fs::read(&path).map_err(|source| EngineError::MjcfUnreadable {
            path: path.clone(),
            source,
        })?;
        let hash = crate::files::content_hash::sha256_hex(&bytes);
        Ok(Self::Mujoco {
            mjcf: Some(path),
            mjcf_sha256: Some(hash),
        })
    }

    /// `rapier` or `mujoco`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Rapier => "rapier",
            Self::Mujoco { .. } => "mujoco",
        }
    }
}

/// Why a physics could not be made.
#[derive(Debug, thiserror::Error)]
pub enum EngineError {
    /// `--mjcf` names no file (a directory, or nothing).
    #[error("MJCF {0}: not a file")]
    MjcfNotAFile(PathBuf),
    /// The MJCF could not be read.
    #[error("MJCF {path}: {source}")]
    MjcfUnreadable {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// This build has no MuJoCo.
    #[error("this thorarena was built without MuJoCo: run `tools/mujoco-lib.sh` once (it puts the libmujoco.so of the PyPI wheel mujoco==3.17.0 under target/), then `cargo build --release --features mujoco` (docs/engines.md, \"MuJoCo backend\")")]
    NotBuilt,
    /// MuJoCo refused the model.
    #[cfg(feature = "mujoco")]
    #[error(transparent)]
    Mujoco(#[from] super::mujoco::MujocoError),
}

/// A physics of `engine` for `model`, at rest in the default pose.
pub fn make_physics(
    engine: &Engine,
    model: Arc<RobotModel>,
    settings: PhysicsSettings,
    gains: PdGains,
) -> Result<Box<dyn Physics + Send>, EngineError> {
    match engine {
        Engine::Rapier => Ok(Box::new(RapierPhysics::new(model, settings, gains))),
        #[cfg(feature = "mujoco")]
        Engine::Mujoco { mjcf, .. } => Ok(Box::new(super::mujoco::MujocoPhysics::new(
            mjcf.as_deref(),
            model,
            settings,
            gains,
        )?)),
        #[cfg(not(feature = "mujoco"))]
        Engine::Mujoco { .. } => {
            let _ = (model, settings, gains);
            Err(EngineError::NotBuilt)
        }
    }
}
