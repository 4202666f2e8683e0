//! A policy as its own process speaking the protocol (`thorarena client`): the Rust
//! example client — the reference the Python and C++ clients are tested against (one
//! policy in process and out of process gives the same episodes, bit for bit) — and the
//! echo policy of the latency benchmark, with the faults the tests inject through it.

use super::wire::WireAnswer;
use super::Policy;
use std::time::Duration;
use thorarena_ipc::{IpcError, Next, ObsBatch, PolicyClient, PolicyConfig, SessionInfo};

/// Faults a test makes this process commit, each at a step counted from 1.
#[derive(Debug, Clone, Default)]
pub struct ClientFaults {
    /// Die by SIGKILL after answering this step.
    pub die_after_steps: Option<u64>,
    /// Sleep this long before answering (`delay_at_step`, or every step when 0).
    pub delay: Duration,
    /// The step `delay` delays; 0: every step.
    pub delay_at_step: u64,
    /// Answer NaN for every joint of every environment at this step.
    pub nan_at_step: Option<u64>,
    /// Answer this step with a batch whose header is not the protocol's (magic zeroed).
    pub bad_header_at_step: Option<u64>,
}

/// Why the client process ended other than with its run.
#[derive(Debug, thiserror::Error)]
pub enum ClientError {
    /// The session could not be joined, or the transport failed.
    #[error(transparent)]
    Ipc(#[from] IpcError),
    /// The policy could not be made for the session.
    #[error("{0}")]
    Policy(String),
    /// The simulator broke its promise about episodes (see `EpisodeContinuity`).
    #[error("{0}")]
    Continuity(String),
}

/// What the process tells its caller as it goes.
pub trait ClientObserver {
    /// Joined the session and made the policy.
    fn connected(&mut self);
    /// About to die by SIGKILL after `steps` steps.
    fn dying(&mut self, steps: u64);
}

/// The policy a client process answers with, made once the session says what it serves
/// (`None`: the echo, action = q; `Err`: why it cannot be made).
pub type MadePolicy = Result<Option<Box<dyn Policy>>, String>;

/// Joins the session of `config` within `timeout`, makes the policy with `make` (given
/// what the session says; `None`: the echo, action = q) and answers every step until the
/// run is over; returns the steps answered.
pub fn run_client_process(
    config: &PolicyConfig,
    timeout: Duration,
    make: &mut dyn FnMut(&SessionInfo) -> MadePolicy,
    faults: &ClientFaults,
    observer: &mut dyn ClientObserver,
) -> Result<u64, ClientError> {
    let mut client = PolicyClient::connect(config, timeout)?;
    let info = client.info().clone();
    let mut policy = make(&info).map_err(ClientError::Policy)?;
    observer.connected();
    let n_refs = info.layout.n_refs;
    let mut wire = WireAnswer::default();
    let mut episodes = EpisodeContinuity::new(info.budget.is_some());
    let mut steps = 0u64;
    loop {
        let mut step = match client.next_step(Some(Duration::from_secs(1)))? {
            Next::Step(step) => step,
            Next::End => break,
            Next::Timeout => continue,
        };
        steps += 1;
        if !faults.delay.is_zero() && (faults.delay_at_step == 0 || faults.delay_at_step == steps) {
            std::thread::sleep(faults.delay);
        }
        let mut broken = None;
        step.answer(&mut |obs, out| {
            broken = episodes.check(obs);
            match policy.as_mut() {
                // The echo: action = q.
                None => {
                    for i in (0..obs.n_envs()).filter(|&i| obs.env(i).is_active()) {
                        out.env(i).copy_from_slice(obs.env(i).array("q"));
                    }
                }
                Some(policy) => wire.answer(policy.as_mut(), obs, out, n_refs),
            }
            if faults.nan_at_step == Some(steps) {
                out.all().fill(f64::NAN);
            }
            if faults.bad_header_at_step == Some(steps) {
                out.header_bytes_mut()[..4].fill(0);
            }
        })?;
        if let Some(why) = broken {
            return Err(ClientError::Continuity(why));
        }
        step.send(&client)?;
        if faults.die_after_steps == Some(steps) {
            observer.dying(steps);
            // SAFETY: raising a signal on our own process has no memory-safety effect.
            unsafe {
                libc::raise(libc::SIGKILL);
            }
        }
    }
    Ok(steps)
}

/// Which episode each slot runs, as this process saw it start: the simulator never hands
/// a policy the middle of an episode it did not begin (after a reconnect, episodes cut
/// short run again from their start), and this client holds it to that — in lock-step.
/// Under a latency budget the simulator steps on without a late policy (the miss rule
/// acts for it), so a slow policy may first see an episode at any step: that is a
/// deadline missed, which the run scores, not a broken promise.
struct EpisodeContinuity {
    started: Vec<Option<u64>>,
    under_budget: bool,
}

impl EpisodeContinuity {
    fn new(under_budget: bool) -> Self {
        Self {
            started: Vec::new(),
            under_budget,
        }
    }

    /// Why `obs` breaks the rule, if it does.
    fn check(&mut self, obs: &ObsBatch) -> Option<String> {
        self.started.resize(obs.n_envs(), None);
        for i in (0..obs.n_envs()).filter(|&i| obs.env(i).is_active()) {
            let header = obs.env(i).header();
            if header.step == 0 || self.under_budget {
                self.started[i] = Some(header.episode_id);
            } else if self.started[i] != Some(header.episode_id) {
                return Some(format!(
                    "slot {i}: episode {} at step {}, but this process never saw it start (the simulator continued an episode begun with another policy)",
                    header.episode_id, header.step
                ));
            }
        }
        None
    }
}
