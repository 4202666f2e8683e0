//! The real-time bridge: one episode of a sequence, its physics driven by whatever
//! `rt/lowcmd` says, as the G1's motor controllers would apply it, while `rt/lowstate`
//! and `rt/secondary_imu` go out at the robot's rate.
//!
//! DDS has no lock-step: the simulation paces itself by the wall clock (physics step `k`
//! is due `k · dt` after the first valid command, the moment the reference clock starts)
//! and records how well it kept to it. Each physics step applies the newest command whose
//! checksum holds, with the robot's law per motor, `τ = τ_ff + kp (q* − q) + kd (q̇* − q̇)`,
//! clamped to the motor's limit: the simulator's PD law with the command's gains and
//! `τ_ff + kd q̇*` as its feed-forward torque (`Physics::set_feedforward`).
//!
//! Until the reference clock starts (the first valid command, or with a start button the
//! command in force at its press) the robot is held still at the reference's first frame.
//! What the run says about itself is `RealTimeReport`: late steps, each physics step's
//! wall time, and the command stream's health (`CommandStream`: broken by a second
//! publisher, another robot on the domain, or a gap over `MAX_COMMAND_GAP_MS`).

use super::scheduling::Scheduling;
use super::transport::{DdsError, RobotEndpoints};
use super::unitree_hg::{MODE_MACHINE_G1_29DOF, MOTOR_SLOTS};
use super::{ImuState, LowCmd, LowState};
use crate::eval::episode::Episode;
use crate::sim::physics::{PdGains, Physics, PhysicsState};
use nalgebra::{UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};
use std::time::{Duration, Instant};

/// How the bridge runs an episode.
#[derive(Debug, Clone)]
pub struct BridgeOptions {
    /// Period of `rt/lowstate` (the G1 publishes at 500 Hz).
    pub state_period: Duration,
    /// How long to wait for the first command before giving up.
    pub start_timeout: Duration,
    /// Index of the torso body in the robot model (its IMU is `rt/secondary_imu`).
    pub torso_body: usize,
    /// Button presses on the robot's wireless remote, from the bridge's start.
    pub remote: super::wireless_remote::RemoteScript,
    /// Start the episode when these buttons are held together (their bits; the first
    /// valid command after the press, if none came before) instead of at the first valid
    /// command. Until then the robot is held still at the reference's first frame, as on
    /// a gantry: commands are taken and counted, the physics does not step.
    pub start_button: Option<u16>,
    /// Also publish the simulator's clock as holosoma's simulator does, over ZeroMQ on
    /// 127.0.0.1 at this port ([`super::zmq_clock`]), with each state: time since the
    /// bridge started, the simulated time once the episode runs.
    pub zmq_clock_port: Option<u16>,
}

/// Percentiles of a duration sample, ms.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Percentiles {
    /// Median.
    pub p50_ms: f64,
    /// 90th percentile.
    pub p90_ms: f64,
    /// 99th percentile.
    pub p99_ms: f64,
    /// Largest.
    pub max_ms: f64,
}

impl Percentiles {
    fn of(mut sample: Vec<f64>) -> Self {
        if sample.is_empty() {
            return Self::default();
        }
        sample.sort_by(f64::total_cmp);
        let at = |p: f64| sample[((sample.len() - 1) as f64 * p).round() as usize];
        Self {
            p50_ms: at(0.5),
            p90_ms: at(0.9),
            p99_ms: at(0.99),
            max_ms: at(1.0),
        }
    }
}

/// Commands as they arrived.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct CommandCounts {
    /// Every decoded command.
    pub received: u64,
    /// Commands whose checksum failed: ignored, as the robot ignores them.
    pub bad_crc: u64,
    /// Commands that could not be decoded: ignored.
    pub undecodable: u64,
    /// Commands with a non-finite or negative gain, a non-finite target, velocity or
    /// torque, or a motor mode other than 0 (limp) or 1 (driven): ignored.
    pub unusable: u64,
    /// Applied commands that asked for a feed-forward torque or a target velocity (both
    /// applied: `τ_ff + kd q̇*` is added to the PD torque before its clamp).
    pub with_feedforward: u64,
    /// Applied commands in the parallel ankle mode (`mode_pr` 1, A/B motors): the
    /// simulated ankle has pitch and roll joints, so their targets were taken as those.
    pub parallel_ankle_mode: u64,
}

/// The longest a deployment may leave the robot without a new command before the run's
/// command stream counts as broken, ms: five 50 Hz policy periods. A robot left on the
/// last command holds it, so a script that stopped after 0.7 s would otherwise score as
/// a steady stand.
pub const MAX_COMMAND_GAP_MS: f64 = 100.0;

/// What the command stream was during the episode (`realtime.json`'s `command_stream`):
/// one deployment, commanding throughout, or not — and then the run's scores are not a
/// deployment's, which the tables say.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct CommandStream {
    /// DDS writers whose usable commands were applied (a deployment is one).
    pub publishers: u64,
    /// Longest time between two usable commands during the episode, ms.
    pub longest_gap_ms: f64,
    /// Time from the last usable command to the episode's end, ms.
    pub silent_at_end_ms: f64,
    /// Other robots seen on the domain: writers of `rt/lowstate` besides this bridge (a
    /// second bridge), whose states the deployment may have read as this robot's.
    #[serde(default)]
    pub other_robots: u64,
    /// One publisher, no other robot, and no gap (nor silence at the end) over
    /// [`MAX_COMMAND_GAP_MS`].
    pub healthy: bool,
    /// What broke it, in words.
    pub problems: Vec<String>,
}

impl CommandStream {
    fn judge(
        publishers: u64,
        other_robots: u64,
        longest_gap_ms: f64,
        silent_at_end_ms: f64,
    ) -> Self {
        let mut problems = Vec::new();
        if other_robots > 0 {
            problems.push(format!(
                "another robot publishes rt/lowstate on this domain ({other_robots} writers besides this bridge): the deployment may have read its states as this robot's"
            ));
        }
        if publishers > 1 {
            problems.push(format!(
                "{publishers} publishers sent commands that were applied interleaved"
            ));
        }
        if longest_gap_ms > MAX_COMMAND_GAP_MS {
            problems.push(format!(
                "no command for {longest_gap_ms:.0} ms during the episode (the last one was held)"
            ));
        }
        if silent_at_end_ms > MAX_COMMAND_GAP_MS {
            problems.push(format!(
                "the commands stopped {:.2} s before the episode's end (the last one was held)",
                silent_at_end_ms / 1e3
            ));
        }
        Self {
            publishers,
            other_robots,
            longest_gap_ms,
            silent_at_end_ms,
            healthy: problems.is_empty(),
            problems,
        }
    }
}

/// How well a run kept real time (`realtime.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RealTimeReport {
    /// Wall time from the bridge's start to the episode's start (the first valid command,
    /// or the one in force at the start button's press), when the reference clock
    /// started, s.
    pub start_offset_s: f64,
    /// Physics steps run.
    pub physics_steps: u64,
    /// Simulated time, s.
    pub simulated_s: f64,
    /// Wall time of the episode, s.
    pub wall_s: f64,
    /// Simulated seconds per wall second (1: real time).
    pub real_time_factor: f64,
    /// Physics steps that started more than one physics period after they were due.
    pub late_steps: u64,
    /// The latest a physics step started after it was due, ms.
    pub max_lateness_ms: f64,
    /// `rt/lowstate` messages published.
    pub states_published: u64,
    /// `motion_switcher` requests answered (CheckMode, ReleaseMode, …).
    pub service_calls: u64,
    /// The commands.
    pub commands: CommandCounts,
    /// Time between consecutive commands, ms.
    pub command_interarrival: Percentiles,
    /// Wall time of each physics step with the episode's bookkeeping (metrics,
    /// termination), from one step's command handling to the next's, ms. Real time needs it
    /// below the physics period; a median far below it with a p99 or maximum above is the
    /// machine pausing or slowing the loop, not the engine's usual cost.
    #[serde(default)]
    pub physics_step_ms: Percentiles,
    /// Whether the run kept real time: at most 1 % of the physics steps late and a
    /// real-time factor of at least 0.98. Scores of a run that did not are marked so.
    pub kept_real_time: bool,
    /// The scheduling the physics loop ran under ([`super::scheduling`]).
    pub scheduling: Scheduling,
    /// Whether one deployment commanded the robot throughout.
    #[serde(default)]
    pub command_stream: CommandStream,
}

/// Where a running episode is, for a progress display (every half second of it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BridgeProgress {
    /// Simulated time of the episode, s.
    pub simulated_s: f64,
    /// Physics steps more than a step late so far.
    pub late_steps: u64,
    /// Commands received so far (since the bridge started).
    pub commands: u64,
}

/// Runs `episode` in real time from `rt/lowcmd`, publishing the robot's state: waits up
/// to [`BridgeOptions::start_timeout`] for a valid command (publishing the initial state
/// meanwhile), then steps the physics on the wall clock until the episode is done, telling
/// `on_progress` where it is every half second of simulated time.
pub fn run_episode(
    endpoints: &mut RobotEndpoints,
    episode: &mut Episode,
    physics: &mut dyn Physics,
    gains: &PdGains,
    options: &BridgeOptions,
    on_progress: &mut dyn FnMut(&BridgeProgress),
) -> Result<RealTimeReport, DdsError> {
    let dt = Duration::from_secs_f64(physics.settings().dt_s);
    let mut io = RobotIo::new(options.clone(), gains.clone())?;
    let bridge_start = Instant::now();
    io.state.read_from(physics);
    let first = first_command(endpoints, &mut io, options, bridge_start)?;
    let start = Instant::now();
    let start_offset_s = (start - bridge_start).as_secs_f64();
    io.episode_offset_s = Some(start_offset_s);
    io.apply(&first, physics);
    let mut steps = 0u64;
    let steps_per_progress = ((0.5 / dt.as_secs_f64()).round() as u64).max(1);
    let mut late_steps = 0u64;
    let mut max_lateness = Duration::ZERO;
    let mut failure = None;
    // When the previous physics step's command handling ended, and the time from there to
    // the next step's (its physics and bookkeeping), ms.
    let mut handled_at: Option<Instant> = None;
    let mut physics_step_ms = Vec::new();
    while !episode.is_done() && failure.is_none() {
        episode.advance_driven(physics, &mut |physics, state, targets| {
            if let Some(then) = handled_at {
                physics_step_ms.push(then.elapsed().as_secs_f64() * 1e3);
            }
            let due = start + dt * steps as u32;
            loop {
                if let Err(e) = io.publish_state(endpoints, state) {
                    failure.get_or_insert(e);
                }
                if let Err(e) = endpoints.serve_services() {
                    failure.get_or_insert(e);
                }
                match io.take_commands(endpoints) {
                    Ok(Some(command)) => io.apply(&command, physics),
                    Ok(None) => {}
                    Err(e) => {
                        failure.get_or_insert(e);
                    }
                }
                let now = Instant::now();
                if now >= due {
                    let lateness = now - due;
                    max_lateness = max_lateness.max(lateness);
                    if lateness > dt {
                        late_steps += 1;
                    }
                    break;
                }
                std::thread::sleep((due - now).min(io.until_next_state()));
            }
            if let Some(t) = &io.targets {
                targets.clone_from(t);
            }
            handled_at = Some(Instant::now());
            steps += 1;
            if steps.is_multiple_of(steps_per_progress) {
                on_progress(&BridgeProgress {
                    simulated_s: steps as f64 * dt.as_secs_f64(),
                    late_steps,
                    commands: io.counts.received,
                });
            }
        });
    }
    if let Some(e) = failure {
        return Err(e);
    }
    let wall_s = start.elapsed().as_secs_f64();
    let simulated_s = steps as f64 * dt.as_secs_f64();
    let real_time_factor = simulated_s / wall_s.max(f64::MIN_POSITIVE);
    io.counts.undecodable = endpoints.undecodable_commands();
    let end = Instant::now();
    let silent_at_end_ms = io
        .last_usable_at
        .map_or(0.0, |t| (end - t).as_secs_f64() * 1e3);
    let command_stream = CommandStream::judge(
        io.applied_from.len() as u64,
        io.other_robots.len() as u64,
        io.longest_gap.as_secs_f64() * 1e3,
        silent_at_end_ms,
    );
    Ok(RealTimeReport {
        command_stream,
        start_offset_s,
        physics_steps: steps,
        simulated_s,
        wall_s,
        real_time_factor,
        late_steps,
        max_lateness_ms: max_lateness.as_secs_f64() * 1e3,
        states_published: io.published,
        service_calls: endpoints.service_calls().len() as u64,
        commands: io.counts,
        command_interarrival: Percentiles::of(io.interarrival_ms),
        physics_step_ms: Percentiles::of(physics_step_ms),
        kept_real_time: late_steps * 100 <= steps && real_time_factor >= 0.98,
        scheduling: Scheduling::of_this_thread(),
    })
}

/// Publishes the standing robot's state and serves its services until the first valid
/// command (after the start button, when one is asked for), or the start timeout.
fn first_command(
    endpoints: &mut RobotEndpoints,
    io: &mut RobotIo,
    options: &BridgeOptions,
    bridge_start: Instant,
) -> Result<LowCmd, DdsError> {
    // Before the start the robot stands still and says so.
    let mut newest = None;
    let mut pressed = options.start_button.is_none();
    loop {
        io.publish_due(endpoints)?;
        endpoints.serve_services()?;
        if let Some(command) = io.take_commands(endpoints)? {
            newest = Some(command);
        }
        if let Some(bits) = options.start_button {
            pressed |= options.remote.buttons_at(io.started.elapsed()) & bits == bits;
        }
        if pressed {
            if let Some(command) = newest.take() {
                return Ok(command);
            }
        }
        if bridge_start.elapsed() > options.start_timeout {
            io.counts.undecodable = endpoints.undecodable_commands();
            return Err(DdsError::NoCommand {
                waited: options.start_timeout,
                counts: io.counts,
            });
        }
        std::thread::sleep(Duration::from_micros(500));
    }
}

/// The robot's side of the wire: the state it publishes, the commands it takes.
struct RobotIo {
    options: BridgeOptions,
    /// The profile's gains, whose torque limits every command keeps.
    limits: PdGains,
    state: StateMessages,
    published: u64,
    next_state_at: Instant,
    started: Instant,
    counts: CommandCounts,
    last_command_at: Option<Instant>,
    /// When the last usable command arrived, and the longest wait between two during
    /// the episode.
    last_usable_at: Option<Instant>,
    longest_gap: Duration,
    /// The writers whose usable commands arrived during the episode.
    applied_from: std::collections::BTreeSet<String>,
    /// Writers of `rt/lowstate` that are not this bridge.
    other_robots: std::collections::BTreeSet<String>,
    interarrival_ms: Vec<f64>,
    /// Targets of the command in force, rad.
    targets: Option<Vec<f64>>,
    gains_in_force: Option<PdGains>,
    /// The feed-forward torques set on the physics, N·m (set only when they change).
    feedforward_in_force: Option<Vec<f64>>,
    clock: Option<super::zmq_clock::ZmqClock>,
    /// When the episode started, s after the bridge; `None` before.
    episode_offset_s: Option<f64>,
    /// Simulated time of the episode, s.
    episode_time_s: f64,
}

impl RobotIo {
    fn new(options: BridgeOptions, limits: PdGains) -> Result<Self, DdsError> {
        let clock = options
            .zmq_clock_port
            .map(super::zmq_clock::ZmqClock::bind)
            .transpose()?;
        let now = Instant::now();
        Ok(Self {
            clock,
            episode_offset_s: None,
            episode_time_s: 0.0,
            state: StateMessages::new(options.torso_body),
            options,
            limits,
            published: 0,
            next_state_at: now,
            started: now,
            counts: CommandCounts::default(),
            last_command_at: None,
            last_usable_at: None,
            longest_gap: Duration::ZERO,
            applied_from: Default::default(),
            other_robots: Default::default(),
            interarrival_ms: Vec::new(),
            targets: None,
            gains_in_force: None,
            feedforward_in_force: None,
        })
    }

    fn until_next_state(&self) -> Duration {
        self.next_state_at.saturating_duration_since(Instant::now())
    }

    /// Publishes the last state read when its period has come.
    fn publish_due(&mut self, endpoints: &RobotEndpoints) -> Result<(), DdsError> {
        let now = Instant::now();
        if now < self.next_state_at {
            return Ok(());
        }
        // On the period's grid; after a stall of more than a period, from now on.
        self.next_state_at += self.options.state_period;
        if self.next_state_at < now {
            self.next_state_at = now + self.options.state_period;
        }
        self.published += 1;
        let since = now - self.started;
        self.state.low.tick = (since.as_millis() as u32).max(1);
        self.options
            .remote
            .write(since, &mut self.state.low.wireless_remote);
        self.state.low.crc = self.state.low.crc_of();
        if let Some(clock) = &self.clock {
            let time_s = match self.episode_offset_s {
                Some(offset) => offset + self.episode_time_s,
                None => since.as_secs_f64(),
            };
            clock.publish((time_s * 1e3) as u64);
        }
        endpoints.publish(
            &self.state.low,
            &self.state.torso,
            &self.options.remote.controller(since),
        )
    }

    /// Reads `state` into the messages and publishes them when due.
    fn publish_state(
        &mut self,
        endpoints: &RobotEndpoints,
        state: &PhysicsState,
    ) -> Result<(), DdsError> {
        if Instant::now() >= self.next_state_at {
            self.state.read(state);
        }
        self.episode_time_s = state.time_s;
        self.publish_due(endpoints)
    }

    /// The newest usable command among those that arrived, counting the rest; also notes
    /// any other robot on the domain (said once each, as it is seen).
    fn take_commands(
        &mut self,
        endpoints: &mut RobotEndpoints,
    ) -> Result<Option<LowCmd>, DdsError> {
        for writer in endpoints.other_robots() {
            if self.other_robots.insert(writer.clone()) {
                log::warn!(
                    "another robot publishes rt/lowstate on this DDS domain (writer {writer}): the deployment may read its states; give each bridge its own `option.domain`"
                );
            }
        }
        let mut newest = None;
        for (command, writer) in endpoints.commands()? {
            let now = Instant::now();
            if let Some(before) = self.last_command_at.replace(now) {
                self.interarrival_ms
                    .push((now - before).as_secs_f64() * 1e3);
            }
            self.counts.received += 1;
            if !command.crc_ok() {
                self.counts.bad_crc += 1;
            } else if !usable(&command, self.limits.kp.len()) {
                self.counts.unusable += 1;
            } else {
                // The stream's health counts from the episode's start.
                if self.episode_offset_s.is_some() {
                    if let Some(before) = self.last_usable_at {
                        self.longest_gap = self.longest_gap.max(now - before);
                    }
                    self.applied_from
                        .insert(super::transport::guid_text(&writer));
                }
                self.last_usable_at = Some(now);
                newest = Some(command);
            }
        }
        Ok(newest)
    }

    /// Puts `command` in force: gains (a disabled motor, mode 0, has none) and targets.
    fn apply(&mut self, command: &LowCmd, physics: &mut dyn Physics) {
        let n = self.limits.kp.len();
        let motors = &command.motor_cmd[..n];
        let gains = PdGains {
            kp: motors
                .iter()
                .map(|m| if enabled(m) { f64::from(m.kp) } else { 0.0 })
                .collect(),
            kd: motors
                .iter()
                .map(|m| if enabled(m) { f64::from(m.kd) } else { 0.0 })
                .collect(),
            effort_limit_nm: self.limits.effort_limit_nm.clone(),
        };
        if self.gains_in_force.as_ref() != Some(&gains) {
            physics.set_gains(&gains);
            self.gains_in_force = Some(gains);
        }
        let feedforward = feedforward_nm(motors);
        if motors
            .iter()
            .any(|m| enabled(m) && (m.tau != 0.0 || m.dq != 0.0))
        {
            self.counts.with_feedforward += 1;
        }
        if self.feedforward_in_force.as_ref() != Some(&feedforward) {
            physics.set_feedforward(&feedforward);
            self.feedforward_in_force = Some(feedforward);
        }
        if command.mode_pr == 1 {
            self.counts.parallel_ankle_mode += 1;
        }
        let q: Vec<f64> = motors.iter().map(|m| f64::from(m.q)).collect();
        physics.set_targets(&q);
        self.targets = Some(q);
    }
}

/// Whether a motor is driven (mode 1); a motor in mode 0 is limp.
fn enabled(m: &super::MotorCmd) -> bool {
    m.mode != 0
}

/// The part of the robot's motor law `τ = τ_ff + kp (q* − q) + kd (q̇* − q̇)` that the
/// simulator's PD law lacks, `τ_ff + kd q̇*`, per motor, N·m (zero for a limp motor).
fn feedforward_nm(motors: &[super::MotorCmd]) -> Vec<f64> {
    motors
        .iter()
        .map(|m| {
            if enabled(m) {
                f64::from(m.tau) + f64::from(m.kd) * f64::from(m.dq)
            } else {
                0.0
            }
        })
        .collect()
}

/// Finite gains ≥ 0 and finite targets, velocities and torques on the robot's motors.
fn usable(command: &LowCmd, n_joints: usize) -> bool {
    command.motor_cmd[..n_joints.min(MOTOR_SLOTS)]
        .iter()
        .all(|m| {
            [m.q, m.dq, m.tau, m.kp, m.kd].iter().all(|v| v.is_finite())
                && m.kp >= 0.0
                && m.kd >= 0.0
                && m.mode <= 1
        })
}

/// The messages the robot publishes, read from the simulation.
struct StateMessages {
    low: LowState,
    torso: ImuState,
    torso_body: usize,
    /// Pelvis velocity (world) and torso orientation at the previous read, for the
    /// accelerometer and the torso's gyroscope.
    previous: Option<(Vector3<f64>, UnitQuaternion<f64>, f64)>,
}

impl StateMessages {
    fn new(torso_body: usize) -> Self {
        Self {
            low: LowState {
                mode_machine: MODE_MACHINE_G1_29DOF,
                ..Default::default()
            },
            torso: ImuState::default(),
            torso_body,
            previous: None,
        }
    }

    fn read_from(&mut self, physics: &dyn Physics) {
        let mut state = PhysicsState::default();
        physics.read_state(&mut state);
        self.read(&state);
    }

    /// Motors from the joints; the pelvis IMU from the root (gyroscope and accelerometer in
    /// its frame, the accelerometer measuring acceleration minus gravity); the torso IMU
    /// from the torso body.
    fn read(&mut self, state: &PhysicsState) {
        for (j, m) in self
            .low
            .motor_state
            .iter_mut()
            .enumerate()
            .take(state.q.len())
        {
            m.mode = 1;
            m.q = state.q[j] as f32;
            m.dq = state.qd[j] as f32;
            m.tau_est = state.applied_torque_nm.get(j).copied().unwrap_or(0.0) as f32;
        }
        let Some(root) = &state.root else {
            return;
        };
        let pelvis = root.world_from_root.rotation;
        let gravity_w = Vector3::new(0.0, 0.0, -9.81);
        let torso = state
            .world_from_body
            .get(self.torso_body)
            .map_or(pelvis, |p| p.rotation);
        let (accel_w, torso_rate_b) = match self.previous {
            Some((v0, torso0, t0)) if state.time_s > t0 => {
                let h = state.time_s - t0;
                let turn = (torso0.inverse() * torso).scaled_axis() / h;
                ((root.lin_vel_w - v0) / h, turn)
            }
            _ => (Vector3::zeros(), Vector3::zeros()),
        };
        self.previous = Some((root.lin_vel_w, torso, state.time_s));
        fill_imu(
            &mut self.low.imu_state,
            &pelvis,
            pelvis.inverse() * root.ang_vel_w,
            pelvis.inverse() * (accel_w - gravity_w),
        );
        fill_imu(
            &mut self.torso,
            &torso,
            torso_rate_b,
            torso.inverse() * (accel_w - gravity_w),
        );
    }
}

fn fill_imu(
    imu: &mut ImuState,
    orientation: &UnitQuaternion<f64>,
    gyro_b: Vector3<f64>,
    accel_b: Vector3<f64>,
) {
    let q = orientation.quaternion();
    imu.quaternion = [q.w as f32, q.i as f32, q.j as f32, q.k as f32];
    let (roll, pitch, yaw) = orientation.euler_angles();
    imu.rpy = [roll as f32, pitch as f32, yaw as f32];
    imu.gyroscope = [gyro_b.x as f32, gyro_b.y as f32, gyro_b.z as f32];
    imu.accelerometer = [accel_b.x as f32, accel_b.y as f32, accel_b.z as f32];
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dds::MotorCmd;

    #[test]
    fn the_feedforward_is_the_torque_plus_kd_times_the_target_velocity() {
        let motor = |mode, dq, tau, kd| MotorCmd {
            mode,
            dq,
            tau,
            kd,
            ..Default::default()
        };
        let motors = [
            motor(1, 0.0, 0.0, 2.0),
            motor(1, 0.5, 1.5, 2.0),
            motor(1, -1.0, 0.0, 3.0),
            motor(0, 0.5, 1.5, 2.0), // limp: nothing
        ];
        assert_eq!(feedforward_nm(&motors), vec![0.0, 2.5, -3.0, 0.0]);
    }
}
