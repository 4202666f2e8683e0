//! What ThorArena costs, measured: one physics step per engine, the whole episode loop on
//! one core, a whole evaluation on every worker against its physics floor, the policy
//! round trip over shared memory next to a Unix-socket baseline moving the same bytes, and
//! a sweep run as tasks next to the same episodes run directly. Each function returns figures;
//! each benchmark of `thorarena bench …` (`IpcBench`, `EvalBench`, …) checks what it was
//! asked, runs its measurements and composes its lines with the ratio to the baseline
//! measured in the same run, handing each to its caller as it is measured ([`BenchLine`]).

mod bench_line;
mod episode_loop;
mod eval_bench;
mod full_run;
mod inference_bench;
mod ipc_bench;
mod ipc_clients;
mod ipc_tables;
mod machine;
mod physics_bench;
mod physics_step;
mod round_trip;
mod scratch;
mod socket;
mod sweep_bench;
mod sweep_cost;
mod timed_policy;

pub use bench_line::BenchLine;
pub use episode_loop::{time_episode_loop, EpisodeLoopTiming};
pub use eval_bench::EvalBench;
pub use full_run::{physics_floor, process_cpu_time, process_group_cpu_time, time_run, RunTiming};
pub use inference_bench::InferenceBench;
pub use ipc_bench::IpcBench;
pub use ipc_clients::{
    adapter_round_trip, ipc_library, shm_round_trips, AdapterRow, Builder, IpcClients, Measured,
    NetworkTiming,
};
pub use machine::Machine;
pub use physics_bench::PhysicsBench;
pub use physics_step::{python_mujoco_step, time_physics_steps, PythonMujocoTiming, StepTiming};
pub use round_trip::{
    adapter_round_trips, echo_round_trips, fill_echo_observations, standing_observation,
    AdapterTiming,
};
pub use scratch::ScratchDir;
pub use socket::{answer_socket_echo, socket_round_trips};
pub use sweep_bench::SweepBench;
pub use sweep_cost::{time_sweep_at_scale, time_sweep_round, SweepRoundTiming, SweepScaleTiming};

use std::path::PathBuf;

/// Why a measurement could not be taken.
#[derive(Debug, thiserror::Error)]
pub enum PerfError {
    /// A file, socket or process could not be used.
    #[error("{what}: {source}")]
    Io {
        /// What was being done.
        what: String,
        /// The cause.
        source: std::io::Error,
    },
    /// The shared-memory transport failed.
    #[error(transparent)]
    Ipc(#[from] thorarena_ipc::IpcError),
    /// A batch did not match its layout.
    #[error(transparent)]
    Layout(#[from] thorarena_ipc::LayoutError),
    /// An echo peer answered something other than action = q (an adapter: something not
    /// finite), or went away.
    #[error("the policy answered wrongly or went away at step {step} ({outcome})")]
    WrongEcho {
        /// The step.
        step: u64,
        /// What the transport said.
        outcome: String,
    },
    /// A command of this binary that the measurement runs failed.
    #[error("{what} failed:\n{message}")]
    Failed {
        /// The command.
        what: String,
        /// Its standard error.
        message: String,
    },
    /// The measurement cannot be taken with what it was given.
    #[error("{0}")]
    Precondition(String),
    /// A step the measurement relies on failed.
    #[error("{what}: {source}")]
    Other {
        /// What was being done.
        what: String,
        /// The cause.
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// A robot or policy named did not resolve.
    #[error(transparent)]
    Registry(#[from] crate::policy::registry::RegistryError),
    /// The evaluation asked for cannot run.
    #[error(transparent)]
    Spec(#[from] crate::eval::SpecError),
    /// A physics could not be made.
    #[error(transparent)]
    Engine(#[from] crate::sim::physics::EngineError),
    /// tract could not load, plan or run the network (its message and causes, joined).
    #[error("{0}")]
    Network(String),
    /// A policy process could not be started or did not connect (the end of its log
    /// quoted).
    #[error("{0}")]
    PolicyProcess(String),
    /// The Python MuJoCo baseline failed or wrote something unreadable.
    #[error("{}: {message}", script.display())]
    Baseline {
        /// The baseline's script.
        script: PathBuf,
        /// What went wrong.
        message: String,
    },
}

impl PerfError {
    fn other<E: std::error::Error + Send + Sync + 'static>(
        what: impl Into<String>,
    ) -> impl FnOnce(E) -> Self {
        let what = what.into();
        move |source| PerfError::Other {
            what,
            source: Box::new(source),
        }
    }

    fn io(what: impl Into<String>) -> impl FnOnce(std::io::Error) -> Self {
        let what = what.into();
        move |source| PerfError::Io { what, source }
    }
}

/// The median of `v` (sorted in place); NaN for none.
fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}
