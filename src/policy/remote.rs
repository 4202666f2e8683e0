//! A policy in another process, reached over shared memory (`thorarena-ipc`): each
//! control step the batch of observations is written straight into the request, and the
//! actions are read straight from the response, under the session's latency budget.

use super::declared_profile::{judge, ProcessProfile, ProfileDeclaration};
use super::inputs::InputBuilder;
use super::wire::write_observation;
use super::{ActOutcome, Observation, Policy};
use std::cell::RefCell;
use std::time::Duration;
use thorarena_ipc::{
    ActionMapping, IpcError, ObsBatchMut, PolicyInfo, Refusal, SimConfig, SimSession, StepOutcome,
    FLAG_PREVIOUS_TERMINATED,
};

/// How to serve a session: the session itself, and what to do about connections.
#[derive(Debug, Clone)]
pub struct RemoteConfig {
    /// Name, batch shape, action mapping, budget and wait of the session.
    pub session: SimConfig,
    /// How long to wait for a policy to connect, first and after a failure (`None`: forever).
    pub connect_timeout: Option<Duration>,
    /// After a policy failure, wait for a new policy process instead of ending the run.
    pub reconnect: bool,
}

/// The longest wait for a process a run waits on (a policy connecting, a deployment's
/// first command): a day. Longer is a mistake, not a wait, and beyond a duration's range
/// it would panic.
pub const MAX_WAIT: Duration = Duration::from_secs(24 * 3600);

/// A wait of `secs` s checked — finite, at most [`MAX_WAIT`], and above 0 unless
/// `zero_waits_forever` (then 0 is `None`, no limit). The one check of every timeout a
/// user gives, from a flag, a sweep spec, a leaderboard policy file or a request.
pub fn check_wait_s(secs: f64, zero_waits_forever: bool) -> Result<Option<Duration>, String> {
    let shown = crate::files::names::short_number(secs);
    let range = if zero_waits_forever {
        "give 0 (wait forever) to 86400 s"
    } else {
        "give more than 0 s, at most 86400 s"
    };
    if !secs.is_finite() || secs < 0.0 || secs > MAX_WAIT.as_secs_f64() {
        return Err(format!("{shown} s: {range}"));
    }
    if secs == 0.0 {
        return if zero_waits_forever {
            Ok(None)
        } else {
            Err(format!("{shown} s: {range}"))
        };
    }
    Ok(Some(Duration::from_secs_f64(secs)))
}

/// How a run serves its policy process, beyond what the robot and the profile fix.
#[derive(Debug, Clone)]
pub struct SessionOptions {
    /// Latency budget per control step (`None`: lock-step).
    pub budget: Option<Duration>,
    /// Busy-poll this long for the actions before blocking.
    pub spin: Duration,
    /// How long to wait for a policy to connect (`None`: forever).
    pub connect_timeout: Option<Duration>,
    /// After a policy failure, wait for a new policy process instead of ending the run.
    pub reconnect: bool,
}

impl SessionOptions {
    /// How a run serves a policy process it starts itself (the leaderboard's, `bench
    /// eval`'s): lock-step, a 50 µs spin before blocking, no reconnect; the wait for it
    /// to connect is its command's own (`PolicyCommand::connect_timeout_s`).
    pub const LAUNCHED: Self = Self {
        budget: None,
        spin: Duration::from_micros(50),
        connect_timeout: None,
        reconnect: false,
    };

    /// Options from what a user gives: the run's latency budget (s, checked with the
    /// evaluation), the spin before blocking (µs), the connect timeout (s; 0 waits
    /// forever) and whether a failed policy may be replaced by a reconnecting one.
    pub fn checked(
        budget_s: Option<f64>,
        spin_us: u64,
        connect_timeout_s: f64,
        reconnect: bool,
    ) -> Result<Self, SessionOptionsError> {
        let connect_timeout =
            check_wait_s(connect_timeout_s, true).map_err(SessionOptionsError::ConnectTimeout)?;
        Ok(Self {
            budget: budget_s.map(Duration::from_secs_f64),
            spin: Duration::from_micros(spin_us),
            connect_timeout,
            reconnect,
        })
    }
}

/// Why session options are unusable.
#[derive(Debug, thiserror::Error)]
pub enum SessionOptionsError {
    /// A connect timeout outside 0 (forever) to [`MAX_WAIT`].
    #[error("`option.connect_timeout` {0}")]
    ConnectTimeout(String),
}

/// Why serving a session failed.
#[derive(Debug, thiserror::Error)]
pub enum RemoteError {
    /// The transport failed or no policy connected in time.
    #[error(transparent)]
    Ipc(#[from] IpcError),
    /// The session offered a policy input this simulator has no builder for (a
    /// `SimConfig::inputs` entry not from [`super::inputs::offers`]).
    #[error("the session offers policy input `{0}`, which this simulator cannot build")]
    NoBuilder(String),
}

/// Counters of the transport, for the results.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct TransportStats {
    /// Round trips started.
    pub round_trips: u64,
    /// Steps whose actions missed the budget.
    pub deadline_misses: u64,
    /// Replies that arrived after their step's deadline (and were discarded).
    pub late_replies: u64,
    /// Times the policy process died or left mid-run.
    pub policy_failures: u64,
    /// Policies that connected after a failure.
    pub reconnections: u64,
}

/// The simulator's end of a session, as a [`Policy`].
pub struct RemotePolicy {
    session: SimSession,
    config: RemoteConfig,
    name: String,
    offsets_s: Vec<f64>,
    previous_terminated: Vec<bool>,
    last_round_trip: Option<Duration>,
    stats: TransportStats,
    /// The network input the policy asked the simulator to build, and its builder.
    input: Option<(String, InputBuilder)>,
    /// The profile the policy declared, as the run judged it (`None`: connected without
    /// a run's judgement, [`Self::connect`]).
    declaration: Option<ProfileDeclaration>,
    /// What it declared, as it declared it: a reconnecting policy must declare the same.
    declared: Option<thorarena_ipc::DeclaredProfile>,
    /// It runs under the baselines' `default` dynamics (by the numbers): a baseline, not
    /// a tracker, so the sanity check before a run does not apply to it.
    under_baseline_profile: bool,
    /// Reports a policy that keeps a step waiting (lock-step waits as long as it lives).
    stall_watch: super::stall_watch::StallWatch,
}

impl RemotePolicy {
    /// Serves session `session` for `robot` under `profile`'s action mapping, `envs`
    /// environment slots wide, and waits for a policy process: one whose declared name is
    /// not usable in paths, whose declared profile `rule` refuses
    /// ([`super::declared_profile::judge`]), or that `vet` refuses, is told why and the
    /// wait goes on. A profile the run takes from the process is the session's action
    /// mapping from then on, and [`Policy::profile_declaration`] tells the run. `note`
    /// hears what a user watching the run should know (waiting, refusals, who connected);
    /// `gone` ends the wait at once when the policy expected cannot come any more (the
    /// process the run started for it exited).
    #[allow(clippy::too_many_arguments)]
    pub fn serve(
        session: &str,
        robot: &crate::sim::robot::RobotModel,
        profile: &crate::sim::profile::Profile,
        rule: ProcessProfile,
        options: &SessionOptions,
        envs: usize,
        vet: &mut dyn FnMut(&str) -> Result<(), String>,
        note: &mut dyn FnMut(&str),
        gone: &mut dyn FnMut() -> bool,
    ) -> Result<Self, RemoteError> {
        let config = RemoteConfig {
            session: SimConfig {
                session: session.to_string(),
                n_envs: envs,
                joint_names: robot.joints.iter().map(|j| j.name.clone()).collect(),
                control_dt_s: profile.control_dt_s,
                action_offset_rad: profile.action_offset_rad.clone(),
                action_scale: profile.action_scale.clone(),
                budget: options.budget,
                wait: thorarena_ipc::WaitPolicy {
                    spin: options.spin,
                    ..thorarena_ipc::WaitPolicy::default()
                },
                inputs: super::inputs::offers(robot.joints.len()),
            },
            connect_timeout: options.connect_timeout,
            reconnect: options.reconnect,
        };
        note(&format!(
            "serving session `{session}` ({envs} environment slots, budget {}): waiting for a policy to connect…",
            options
                .budget
                .map_or("none (lock-step)".to_string(), |b| format!("{b:?}"))
        ));
        // The name a policy process declares becomes part of paths: a name the run cannot
        // use is refused in the handshake, so the policy hears why.
        let mut judged = None;
        let mut vet_name = |info: &PolicyInfo| -> Result<Option<ActionMapping>, Refusal> {
            crate::files::names::check_name("policy name", &info.name)
                .map_err(|e| e.to_string())?;
            vet(&info.name)?;
            let declaration = judge(&info.name, info.profile.as_ref(), profile, rule, robot)?;
            let mapping = declaration.mapping();
            judged = Some(declaration);
            Ok(mapping)
        };
        let mut remote = Self::connect(
            config,
            &mut vet_name,
            &mut |m| note(&format!("refused a policy: {m}")),
            gone,
        )?;
        let effective = judged
            .as_ref()
            .and_then(|d| d.declared.as_ref().filter(|_| d.adopted))
            .unwrap_or(profile);
        remote.under_baseline_profile = is_baseline_profile(effective, robot);
        remote.declaration = judged;
        let declared = match remote
            .declaration
            .as_ref()
            .and_then(|d| d.declared.as_ref())
        {
            None => format!("no profile declared, the run's `{}`", profile.name),
            Some(p) if remote.declaration.as_ref().is_some_and(|d| d.mismatch) => format!(
                "declared profile `{}`, run under `{}` (--profile-mismatch-ok)",
                p.name, profile.name
            ),
            Some(p) => format!("profile `{}`", p.name),
        };
        note(&format!(
            "policy `{}` (pid {}) connected, reference offsets {:?} s, {declared}",
            remote.name(),
            remote.policy_pid().unwrap_or(0),
            remote.reference_offsets_s()
        ));
        Ok(remote)
    }

    /// Creates the session and waits for a policy to connect; refused handshakes (wrong
    /// protocol version, joint count or order, or a policy `vet` refuses: the run's own
    /// conditions on its name and profile) are passed to `on_refused`, told to the
    /// policy, and the wait goes on. A mapping `vet` returns is the session's from then on.
    /// `gone`: the policy expected cannot come any more (its process exited), so the wait
    /// ends at once.
    pub fn connect(
        mut config: RemoteConfig,
        vet: &mut dyn FnMut(&PolicyInfo) -> Result<Option<ActionMapping>, Refusal>,
        on_refused: &mut dyn FnMut(&str),
        gone: &mut dyn FnMut() -> bool,
    ) -> Result<Self, RemoteError> {
        let mut session = SimSession::create(config.session.clone())?;
        let info =
            session.accept_unless_gone(config.connect_timeout, vet, |m| on_refused(m), gone)?;
        config.session = session.config().clone();
        let input = match &info.input {
            None => None,
            Some(name) => {
                let session = &config.session;
                let builder = InputBuilder::new(name, session.n_envs, &session.action_offset_rad)
                    .ok_or_else(|| RemoteError::NoBuilder(name.clone()))?;
                Some((name.clone(), builder))
            }
        };
        Ok(Self {
            input,
            declaration: None,
            declared: info.profile,
            under_baseline_profile: true,
            session,
            stall_watch: super::stall_watch::StallWatch::new(info.name.clone()),
            name: info.name,
            offsets_s: info.reference_offsets_s,
            previous_terminated: vec![false; config.session.n_envs],
            config,
            last_round_trip: None,
            stats: TransportStats::default(),
        })
    }

    /// The connected policy's process id.
    pub fn policy_pid(&self) -> Option<u32> {
        self.session.policy().map(|p| p.pid)
    }
}

impl Policy for RemotePolicy {
    fn name(&self) -> &str {
        &self.name
    }

    fn reference_offsets_s(&self) -> Vec<f64> {
        self.offsets_s.clone()
    }

    fn sanity_exempt(&self) -> Option<&'static str> {
        self.under_baseline_profile.then_some(
            "a policy process under the baselines' `default` profile, a floor rather than a tracker (check it with `thorarena policy check ipc:SESSION`)",
        )
    }

    fn episode_ended(&mut self, env: usize, terminated: bool) {
        if let Some(t) = self.previous_terminated.get_mut(env) {
            *t = terminated;
        }
    }

    fn act(&mut self, observations: &[Observation], actions: &mut [Vec<f64>]) -> ActOutcome {
        let n_envs = self.config.session.n_envs;
        let offsets = &self.offsets_s;
        let previous_terminated = &mut self.previous_terminated;
        // Both closures use the builder: `fill` to write, `prepare_next` (run while the
        // policy computes) to read the histories into the next batch.
        let has_input = self.input.is_some();
        let input = RefCell::new(self.input.as_mut().map(|(_, builder)| builder));
        let mut prepare = |next: &mut ObsBatchMut| {
            if let Some(builder) = input.borrow().as_ref() {
                builder.prepare(next);
            }
        };
        let prepare_next: Option<&mut dyn FnMut(&mut ObsBatchMut)> =
            if has_input { Some(&mut prepare) } else { None };
        self.stats.round_trips += 1;
        self.stall_watch.waiting();
        let outcome = self.session.step_prepared(
            |batch, prepared| {
                let mut input = input.borrow_mut();
                let mut filled = vec![false; n_envs];
                for obs in observations {
                    let mut env = batch.env(obs.env);
                    let flags = if obs.step == 0 && previous_terminated[obs.env] {
                        FLAG_PREVIOUS_TERMINATED
                    } else {
                        0
                    };
                    write_observation(obs, offsets, &mut env, flags);
                    if let Some(builder) = input.as_mut() {
                        builder.write(obs, batch.policy_input(obs.env), prepared);
                    }
                    filled[obs.env] = true;
                }
                for (slot, _) in filled.iter().enumerate().filter(|(_, f)| !**f) {
                    let flags = if previous_terminated[slot] {
                        FLAG_PREVIOUS_TERMINATED
                    } else {
                        0
                    };
                    batch.env(slot).clear(flags);
                    batch.policy_input(slot).fill(0.0);
                }
                for obs in observations {
                    if obs.step == 0 {
                        previous_terminated[obs.env] = false;
                    }
                }
            },
            prepare_next,
            self.config.session.budget,
            |batch| {
                for (obs, action) in observations.iter().zip(actions.iter_mut()) {
                    action.copy_from_slice(batch.env(obs.env));
                }
            },
        );
        self.last_round_trip = Some(self.session.last_round_trip());
        self.stall_watch.answered();
        match outcome {
            Ok(StepOutcome::Answered) => ActOutcome::Acted,
            Ok(StepOutcome::Missed) => {
                self.stats.deadline_misses += 1;
                ActOutcome::Missed
            }
            Ok(StepOutcome::PolicyGone) => {
                self.stats.policy_failures += 1;
                log::warn!(
                    "policy `{}` is gone (its process died or left the session)",
                    self.name
                );
                ActOutcome::Failed
            }
            Err(e) => {
                // A malformed answer or a transport failure: the policy cannot be trusted
                // with this session any more. It is told to leave (the end-of-run notice),
                // or it would wait for observations while the run waits for a policy.
                self.stats.policy_failures += 1;
                log::warn!("policy `{}` failed: {e}; it is told to leave", self.name);
                self.session.end();
                self.session.drop_policy();
                ActOutcome::Failed
            }
        }
    }

    fn last_round_trip(&self) -> Option<Duration> {
        self.last_round_trip
    }

    fn recover(&mut self) -> bool {
        if !self.config.reconnect {
            return false;
        }
        self.session.drop_policy();
        log::info!(
            "waiting for a policy to reconnect to session `{}` (it must ask for the same reference offsets {:?})",
            self.config.session.session, self.offsets_s
        );
        let offsets = self.offsets_s.clone();
        let input = self.input.as_ref().map(|(name, _)| name.clone());
        let declared = self.declared.clone();
        let same_offsets = |info: &PolicyInfo| -> Result<Option<ActionMapping>, Refusal> {
            if info.reference_offsets_s != offsets {
                Err(format!(
                    "policy `{}` asks for reference offsets {:?}, the run uses {:?}",
                    info.name, info.reference_offsets_s, offsets
                )
                .into())
            } else if info.input != input {
                Err(format!(
                    "policy `{}` asks for policy input {:?}, the run's policy asked for {:?}",
                    info.name, info.input, input
                )
                .into())
            } else if info.profile != declared {
                Err(Refusal {
                    status: thorarena_ipc::Status::Profile,
                    message: format!(
                        "policy `{}` declares profile {:?}, the run's policy declared {:?}: a run goes on under one profile",
                        info.name,
                        info.profile.as_ref().map(|p| p.name()),
                        declared.as_ref().map(|p| p.name())
                    ),
                })
            } else {
                Ok(None)
            }
        };
        let accepted = self
            .session
            .accept_vetted(self.config.connect_timeout, same_offsets, |m| {
                log::warn!("refused a policy: {m}")
            });
        match accepted {
            Ok(info) => {
                log::info!("policy `{}` (pid {}) connected", info.name, info.pid);
                self.stats.reconnections += 1;
                self.name = info.name;
                true
            }
            Err(e) => {
                log::warn!("no policy reconnected: {e}");
                false
            }
        }
    }

    fn profile_declaration(&self) -> Option<&ProfileDeclaration> {
        self.declaration.as_ref()
    }

    fn transport_stats(&self) -> Option<TransportStats> {
        Some(TransportStats {
            late_replies: self.session.late_replies(),
            ..self.stats
        })
    }
}

/// Whether `profile` gives the built-in baselines' dynamics (`data/profiles/default.toml`,
/// compared by the numbers): a process running under it is judged as a baseline is —
/// exempt from the sanity check — and one under any other profile as a network is.
fn is_baseline_profile(
    profile: &crate::sim::profile::Profile,
    robot: &crate::sim::robot::RobotModel,
) -> bool {
    let path = crate::sim::profile::bundled_profile_path("default");
    crate::sim::profile::load_profile(&path, robot)
        .is_ok_and(|default| super::declared_profile::same_dynamics(profile, &default).is_ok())
}

impl Drop for RemotePolicy {
    /// Tells the policy the run is over, so its loop returns.
    fn drop(&mut self) {
        self.session.end();
    }
}
