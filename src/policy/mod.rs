//! The in-process `Policy` trait — batched, so a Rust baseline, a batched Python policy
//! and a C++ policy all see the same loop — the built-in baselines, and the remote policy
//! that speaks `thorarena-ipc` to a policy process; beside them the [`registry`] that
//! turns the names a user gives into policies, profiles and robots, and the ONNX side of
//! networks ([`network_kernels`], [`onnx_export`]).

mod batch_plans;
pub mod beyondmimic;
mod builtin;
pub mod client_process;
pub mod declared_profile;
pub mod falcon;
pub mod inputs;
pub mod launched;
pub mod network_file;
pub mod network_kernels;
pub mod onnx_export;
pub mod registry;
mod remote;
pub mod softmimic;
mod stall_watch;
mod trained_with;
pub mod twist2;
pub mod wire;

pub use batch_plans::BatchPlans;
pub use beyondmimic::BeyondMimicPolicy;
pub use builtin::{BalanceGains, BalancePolicy, HoldPolicy, ReplayPolicy};
pub use falcon::FalconPolicy;
pub use remote::{
    check_wait_s, RemoteConfig, RemoteError, RemotePolicy, SessionOptions, SessionOptionsError,
    TransportStats, MAX_WAIT,
};
pub use softmimic::SoftMimicPolicy;
pub use twist2::Twist2Policy;

use crate::sim::motion::ReferenceFrame;
use crate::sim::physics::RootState;
use std::time::Duration;

/// What a policy sees of one environment at one control step: benchmark signals, not any
/// policy's tensor (adapters build their own from these).
#[derive(Debug, Clone)]
pub struct Observation {
    /// Environment slot of the batch this observation belongs to.
    pub env: usize,
    /// The episode's index in the run's schedule (unique within a run).
    pub episode_id: u64,
    /// Control step within the episode (0 on the first observation of an episode).
    pub step: usize,
    /// Time since the episode started, s.
    pub time_s: f64,
    /// Root pose and velocity (base-frame velocity and projected gravity via its methods).
    pub root: RootState,
    /// Joint angles, canonical order, rad.
    pub q: Vec<f64>,
    /// Joint velocities, rad/s.
    pub qd: Vec<f64>,
    /// The previous raw action that reached the robot.
    pub last_action: Vec<f64>,
    /// Reference frames at the policy's requested offsets from now.
    pub reference: Vec<ReferenceFrame>,
}

/// How a batch's round trip ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ActOutcome {
    /// Every observation got an action (each still checked for range by the runner).
    Acted,
    /// The latency budget ran out first: the runner applies the miss rule to every slot.
    Missed,
    /// The policy is gone (its process died or left): every running episode ends as
    /// `policy_failed`.
    Failed,
}

/// A controller driven one control step at a time for a batch of environments.
pub trait Policy {
    /// Name used in results.
    fn name(&self) -> &str;

    /// Times ahead of the current step, s, at which the policy wants reference frames
    /// (TWIST2: `[0.0]`; GMT: 20 frames up to 1.9 s).
    fn reference_offsets_s(&self) -> Vec<f64> {
        vec![0.0]
    }

    /// Environment slot `env` starts a new episode.
    fn reset(&mut self, _env: usize) {}

    /// The episode in slot `env` ended, early (`terminated`) or at the end of its reference.
    fn episode_ended(&mut self, _env: usize, _terminated: bool) {}

    /// One raw action per observation (interpreted by the dynamics profile). In-process
    /// policies always act; a remote one may miss its deadline or fail.
    fn act(&mut self, observations: &[Observation], actions: &mut [Vec<f64>]) -> ActOutcome;

    /// The round trip of the last `act`, when the policy measures it more precisely than
    /// the caller's wall clock around `act` (a remote policy: observation published to
    /// actions received).
    fn last_round_trip(&self) -> Option<Duration> {
        None
    }

    /// After [`ActOutcome::Failed`]: wait for the policy to come back (a new process
    /// connecting). `false`: it will not, end the run.
    fn recover(&mut self) -> bool {
        false
    }

    /// Transport counters of a remote policy (late replies, reconnections).
    fn transport_stats(&self) -> Option<TransportStats> {
        None
    }

    /// What a policy process declared about the profile it was trained under, as the run
    /// judged it when it connected (`declared_profile`); `None` in process.
    fn profile_declaration(&self) -> Option<&declared_profile::ProfileDeclaration> {
        None
    }

    /// The raw action with which the policy adds nothing of its own — what the sanity
    /// check's zero-action run sends in its place (`crate::eval::sanity`). Raw zero, the
    /// profile's offset, unless the policy's actions are relative to something else (a
    /// residual policy: the reference's joints).
    fn zero_action(&self, _obs: &Observation, out: &mut [f64]) {
        out.fill(0.0);
    }

    /// Why the sanity check before a run does not apply to this policy, or `None` when it
    /// does (the published networks in process). By default a policy is a built-in
    /// baseline: a floor, not a tracker, that need not track a walk.
    fn sanity_exempt(&self) -> Option<&'static str> {
        Some("a built-in baseline (a floor, not a tracker)")
    }

    /// What the policy says about its own wiring: facts (inputs, terms, action mode) and
    /// where its file contradicts the profile. Empty for policies with nothing to say.
    fn wiring(&self) -> Wiring {
        Wiring::default()
    }

    /// `n` fresh copies of this policy (no episode started), one per worker thread of the
    /// runner (`eval/runner/free_running.rs`), each then acting for that worker's slots only,
    /// beside its physics: a network in process costs no core that waits for it, and no
    /// worker waits for another. `None` (the default): the policy acts on a coordinator for
    /// every slot, in lock-step — a policy process, whose answers are computed elsewhere,
    /// or a built-in costing next to nothing. A policy may offer copies only if an
    /// environment's action depends on that environment's observations alone.
    fn worker_copies(&self, _n: usize) -> Option<Vec<Box<dyn Policy + Send>>> {
        None
    }

    /// The network file this policy loaded, by content, when it is a network run in
    /// process: what `run.json` records as the run's network. `None` for a built-in (no
    /// network) and for a policy process (whose network this process never sees).
    fn network(&self) -> Option<&network_file::NetworkFile> {
        None
    }

    /// The kernels a network computed this policy's actions on, when it is a network run
    /// in process ([`network_kernels::network_kernels()`]); `None` for everything else, whose arithmetic is
    /// its own (a policy process) or has no kernels to choose (a baseline).
    fn network_kernels(&self) -> Option<&'static network_kernels::NetworkKernels> {
        None
    }

    /// The parameters the policy runs with that change its actions — SoftMimic's stiffness
    /// command — by name with their unit, for `run.json` (`RunHeader::policy_parameters`).
    fn parameters(&self) -> Vec<(&'static str, f64)> {
        Vec::new()
    }

    /// What the policy follows when it follows commands derived from the reference rather
    /// than the reference's joints (FALCON), in a few words; `None` for a tracker. The
    /// sanity check judges a follower by what it is asked to follow
    /// (`crate::eval::sanity::following`).
    fn follows_commands(&self) -> Option<&'static str> {
        None
    }
}

/// A policy's account of its wiring, for the sanity check.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Wiring {
    /// One sentence per fact (input width and terms, action mode, …).
    pub facts: Vec<String>,
    /// One sentence per quantity the file and the profile disagree on.
    pub disagreements: Vec<String>,
}
