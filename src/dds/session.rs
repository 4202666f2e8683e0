//! One deployment episode, whole: the evaluation it belongs to, the simulated robot on
//! its DDS interface, the episode run in real time by [`super::bridge::run_episode`], and
//! the run directory it is scored into (`run.json`, the record, `summary.json`,
//! `tables.md` with the real-time lines, `realtime.json`), through the same
//! [`crate::eval::pipeline::RunRecording`] that [`crate::eval::pipeline::evaluate`] writes
//! every other run with.

use super::bridge::{run_episode, BridgeOptions, BridgeProgress, RealTimeReport};
use super::scheduling::SchedulingError;
use super::wireless_remote::RemoteScript;
use super::RobotEndpoints;
use crate::eval::episode::{Episode, EpisodeSetup};
use crate::eval::pipeline::RunRecording;
use crate::eval::results::{RunDir, RunHeader};
use crate::eval::{EvalRequest, EvalSpec, TerminationRule};
use crate::sim::motion::SequenceSelection;
use crate::sim::physics::{make_physics, PhysicsSettings};
use std::net::IpAddr;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

/// The file beside the run's records that says how the run kept real time.
pub const REALTIME_FILE: &str = "realtime.json";

/// Period of `rt/lowstate`: the G1 publishes at 500 Hz.
const STATE_PERIOD: Duration = Duration::from_millis(2);

/// What a deployment episode is asked to be.
#[derive(Debug, Clone)]
pub struct DdsSessionRequest {
    /// The dataset holding the sequence (`None`: the bundled sample dataset).
    pub dataset: Option<PathBuf>,
    /// `TASK/SEQUENCE_ID`.
    pub sequence: String,
    /// One setting.
    pub setting: crate::eval::Setting,
    /// Dynamics profile.
    pub profile: String,
    /// Physics engine.
    pub engine: crate::eval::EngineChoice,
    /// MJCF for MuJoCo (`None`: generated from the robot model).
    pub mjcf: Option<PathBuf>,
    /// When a fall ends the episode.
    pub termination: TerminationRule,
    /// DDS domain.
    pub domain: u16,
    /// The local address DDS uses, unless `interface` is given.
    pub address: IpAddr,
    /// The network interface DDS uses, by name (its first IPv4 address).
    pub interface: Option<String>,
    /// Seconds to wait for the first command.
    pub start_timeout_s: f64,
    /// Wireless-remote presses.
    pub remote: RemoteScript,
    /// `first-command`, or the button or chord that starts the episode.
    pub start_on: String,
    /// Publish the simulator's clock on this ZeroMQ port (holosoma's sim time).
    pub zmq_clock_port: Option<u16>,
    /// SCHED_FIFO priority of the physics loop and DDS threads (0: normal).
    pub rt_priority: i32,
    /// The policy's name in the results.
    pub name: String,
    /// The run directory.
    pub out: PathBuf,
    /// Replace a run already there.
    pub overwrite: bool,
}

/// What the session tells its caller while it runs.
pub enum DdsSessionEvent<'a> {
    /// Something the user should know that does not stop the run.
    Advice(String),
    /// The bridge is up: what it serves and when the episode starts.
    Serving(String),
    /// Where the episode is.
    Progress {
        /// The bridge's own progress.
        progress: &'a BridgeProgress,
        /// The episode's length, s.
        duration_s: f64,
    },
}

/// A scored deployment episode.
#[derive(Debug)]
pub struct DdsSessionOutcome {
    /// `tables.md` as written, real-time lines included.
    pub tables: String,
    /// How the run kept real time (also in `realtime.json`).
    pub realtime: RealTimeReport,
}

impl DdsSessionOutcome {
    /// What went wrong in real time, one warning each: time not kept, a broken command
    /// stream (both detailed in `realtime.json`).
    pub fn warnings(&self) -> Vec<String> {
        let mut warnings = Vec::new();
        if !self.realtime.kept_real_time {
            warnings.push("the run did not keep real time (realtime.json)".to_string());
        }
        let stream = &self.realtime.command_stream;
        if !stream.healthy {
            warnings.push(format!(
                "the command stream broke: {} (realtime.json)",
                stream.problems.join("; ")
            ));
        }
        warnings
    }
}

/// A field of [`DdsSessionRequest`] a refusal is about (the command line names its flag).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DdsSetting {
    /// [`DdsSessionRequest::sequence`].
    Sequence,
    /// [`DdsSessionRequest::start_timeout_s`].
    StartTimeout,
    /// [`DdsSessionRequest::start_on`].
    StartOn,
    /// [`DdsSessionRequest::rt_priority`].
    RtPriority,
}

impl DdsSetting {
    /// The field as messages name it (`option.<field>`; the command line shows its flag).
    pub fn field(self) -> &'static str {
        match self {
            Self::Sequence => "option.sequence",
            Self::StartTimeout => "option.start_timeout",
            Self::StartOn => "option.start_on",
            Self::RtPriority => "option.rt_priority",
        }
    }
}

/// Why a deployment episode did not run or was not scored.
#[derive(Debug, thiserror::Error)]
pub enum DdsSessionError {
    /// A setting the session cannot run with: which one, and why (naming its value).
    #[error("`{}`: {why}", setting.field())]
    Setting {
        /// The request's field.
        setting: DdsSetting,
        /// What is wrong with it.
        why: String,
    },
    /// The evaluation the episode belongs to.
    #[error(transparent)]
    Spec(#[from] crate::eval::SpecError),
    /// The run directory.
    #[error(transparent)]
    Results(#[from] crate::eval::results::ResultsError),
    /// Writing the run's records and scores.
    #[error(transparent)]
    Recording(#[from] crate::eval::pipeline::BenchmarkError),
    /// Where the run would be written.
    #[error(transparent)]
    Output(#[from] crate::eval::results::OutputRefused),
    /// The physics engine.
    #[error(transparent)]
    Engine(#[from] crate::sim::physics::EngineError),
    /// DDS itself, or the episode over it.
    #[error(transparent)]
    Dds(#[from] super::DdsError),
    /// The network interface.
    #[error(transparent)]
    Interface(#[from] super::interface::InterfaceError),
    /// The policy name.
    #[error(transparent)]
    Name(#[from] crate::files::names::NameError),
    /// Writing `realtime.json`.
    #[error("writing {path}: {source}")]
    Write {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
}

fn refused(setting: DdsSetting, why: String) -> DdsSessionError {
    DdsSessionError::Setting { setting, why }
}

/// The button bits that start the episode (`None`: the first valid command), checked
/// against the remote's script and the start timeout.
fn start_button(req: &DdsSessionRequest) -> Result<Option<u16>, DdsSessionError> {
    let bits = match req.start_on.as_str() {
        "first-command" => return Ok(None),
        name => match super::wireless_remote::chord_bits(name) {
            Some(bits) if req.remote.presses(bits) => bits,
            Some(_) => {
                return Err(refused(
                    DdsSetting::StartOn,
                    format!("`{name}`: the remote script never presses it"),
                ))
            }
            None => {
                return Err(refused(
                    DdsSetting::StartOn,
                    format!(
                        "`{name}`: give first-command, a button ({}) or a chord (select+A)",
                        super::wireless_remote::BUTTONS.join(", ")
                    ),
                ))
            }
        },
    };
    if let Some(at) = req.remote.first_press(bits) {
        if at.as_secs_f64() >= req.start_timeout_s {
            return Err(refused(
                DdsSetting::StartOn,
                format!(
                    "`{}` is pressed at {:.1} s, after the start timeout of {} s: the bridge would give up first",
                    req.start_on,
                    at.as_secs_f64(),
                    req.start_timeout_s
                ),
            ));
        }
    }
    Ok(Some(bits))
}

/// Checks `req`, waits on DDS for deployment code, runs its episode in real time and
/// scores it into `req.out`. The run directory is locked from before the bridge joins the
/// domain and written only once a command came: a bridge that got none leaves no run.
pub fn run_dds_session(
    req: &DdsSessionRequest,
    on_event: &mut dyn FnMut(DdsSessionEvent<'_>),
) -> Result<DdsSessionOutcome, DdsSessionError> {
    crate::files::names::check_name("policy name", &req.name)?;
    crate::policy::check_wait_s(req.start_timeout_s, false)
        .map_err(|why| refused(DdsSetting::StartTimeout, why))?;
    let start_button = start_button(req)?;
    let address = match &req.interface {
        Some(name) => IpAddr::V4(super::interface::ipv4_of(name)?),
        None => req.address,
    };
    super::interface::check_local_address(address)?;
    if req.domain > super::MAX_DOMAIN {
        return Err(super::DdsError::Domain(req.domain).into());
    }
    let Some((task, _)) = req.sequence.split_once('/') else {
        return Err(refused(
            DdsSetting::Sequence,
            format!("`{}`: give TASK/SEQUENCE_ID", req.sequence),
        ));
    };
    let spec = EvalSpec::load_deployment(&EvalRequest {
        dataset: req.dataset.clone(),
        profile: Some(req.profile.clone()),
        settings: vec![req.setting.clone()],
        selection: SequenceSelection {
            tasks: vec![task.to_string()],
            sequences: vec![req.sequence.clone()],
        },
        workers: Some(1),
        envs: Some(1),
        engine: req.engine,
        mjcf: req.mjcf.clone(),
        trace: vec![req.sequence.clone()],
        termination: req.termination,
        ..EvalRequest::default()
    })?;
    for advice in &spec.advice {
        on_event(DdsSessionEvent::Advice(advice.to_string()));
    }
    let [seq] = spec.sequences.as_slice() else {
        return Err(refused(
            DdsSetting::Sequence,
            format!(
                "`{}` names {} sequences",
                req.sequence,
                spec.sequences.len()
            ),
        ));
    };
    crate::eval::results::check_run_dir(&req.out, req.overwrite, Some(&spec.dataset))?;
    let run = RunDir::new(&req.out);
    run.check_writable()?;
    // The one writer of the run from now until its last file: a second bridge given the
    // same --out is refused before it joins the domain.
    let writer = run.lock()?;
    let scored = serve_and_score(req, &spec, seq, &run, start_button, address, on_event);
    if scored.is_err() {
        // A bridge that got no command, or failed before its run began, leaves no
        // directory holding a lock file alone.
        writer.release_if_unwritten();
    }
    scored
}

/// The episode of `seq` served over DDS, run in real time and scored into `run` (whose
/// writer lock the caller holds).
fn serve_and_score(
    req: &DdsSessionRequest,
    spec: &EvalSpec,
    seq: &crate::sim::motion::Sequence,
    run: &RunDir,
    start_button: Option<u16>,
    address: IpAddr,
    on_event: &mut dyn FnMut(DdsSessionEvent<'_>),
) -> Result<DdsSessionOutcome, DdsSessionError> {
    let robot = Arc::new(spec.robot.clone());
    let mut physics = make_physics(
        &spec.engine,
        robot,
        PhysicsSettings {
            dt_s: spec.profile.physics_dt_s,
            ..Default::default()
        },
        spec.profile.gains.clone(),
    )?;
    let setting = &spec.settings[0];
    let keypoints = spec
        .robot
        .keypoint_set(&spec.keypoints)
        .expect("the keypoint set was checked with the evaluation");
    let setup = EpisodeSetup::for_setting(
        &spec.robot,
        &spec.profile,
        keypoints,
        spec.termination,
        setting,
        vec![0.0],
    );
    // Before the DDS participant starts its threads: they inherit it.
    if req.rt_priority != 0 {
        match super::scheduling::enter_fifo(req.rt_priority) {
            Ok(_) => {}
            Err(e @ SchedulingError::OutOfRange { .. }) => {
                return Err(refused(DdsSetting::RtPriority, e.to_string()))
            }
            Err(e @ SchedulingError::Refused { .. }) => on_event(DdsSessionEvent::Advice(format!(
                "warning: {e}: running at normal priority, where the policy's process can delay physics steps (priority 0 asks for it)"
            ))),
        }
    }
    let mut endpoints = RobotEndpoints::join(req.domain, Some(address))?;
    let mut episode = Episode::start(&setup, seq, physics.as_mut());
    episode.record_trace();
    on_event(DdsSessionEvent::Serving(format!(
        "{}/{} ({}, {:.1} s): rt/lowstate at 500 Hz on DDS domain {} ({}); the episode starts {}…",
        seq.task,
        seq.sequence_id,
        setting.name,
        seq.duration_s(),
        req.domain,
        match &req.interface {
            Some(name) => format!("{name}, {address}"),
            None => address.to_string(),
        },
        match start_button {
            None => "with the first valid rt/lowcmd".to_string(),
            Some(_) => format!("at the remote's {} press", req.start_on),
        }
    )));
    let options = BridgeOptions {
        state_period: STATE_PERIOD,
        start_timeout: Duration::from_secs_f64(req.start_timeout_s),
        torso_body: spec.robot.frame_index("torso_link").unwrap_or(0),
        remote: req.remote.clone(),
        start_button,
        zmq_clock_port: req.zmq_clock_port,
    };
    let duration_s = seq.duration_s();
    let realtime = run_episode(
        &mut endpoints,
        &mut episode,
        physics.as_mut(),
        &spec.profile.gains,
        &options,
        &mut |progress| {
            on_event(DdsSessionEvent::Progress {
                progress,
                duration_s,
            })
        },
    )?;
    let trace = episode.take_trace();
    let record = episode.into_record(seq, setting, &req.name);
    // Started only now: a bridge that got no command leaves no empty run behind.
    let mut header = RunHeader::of(spec, &req.name);
    // Deployment code runs its own network, which the bridge never sees.
    header.identity = Some(crate::eval::results::PolicyIdentity {
        network: None,
        profile_sha256: spec.profile.fingerprint(),
        robot_sha256: spec.robot.fingerprint(),
    });
    let (mut recording, _) = RunRecording::start(run, spec, header, false)?;
    recording.record(&record, trace.as_ref().map(|t| t.steps.as_slice()));
    let recorded = recording.finish(None, &realtime_lines(&realtime))?;
    let realtime_path = run.path().join(REALTIME_FILE);
    let json = serde_json::to_string_pretty(&realtime).expect("a real-time report serializes");
    crate::files::atomic_file::write(&realtime_path, json.as_bytes()).map_err(|source| {
        DdsSessionError::Write {
            path: realtime_path,
            source,
        }
    })?;
    let tables = recorded.tables;
    Ok(DdsSessionOutcome { tables, realtime })
}

/// The lines `tables.md` gains: whether the run kept real time, and whether the command
/// stream was one publisher's throughout.
pub fn realtime_lines(report: &RealTimeReport) -> String {
    let c = &report.commands;
    let mut lines = format!(
        "\nReal time: {} — real-time factor {:.3}, {} of {} physics steps late (latest {:.1} ms); a physics step with its bookkeeping took p50 {:.3} ms, p99 {:.3} ms, at most {:.1} ms; commands: {} received, {} bad checksum (ignored), {} unusable (ignored), {} with feed-forward torque or velocity (applied), {} in the parallel ankle mode (targets taken as pitch/roll); inter-arrival p50 {:.2} ms, p99 {:.2} ms; episode (and reference clock) started {:.2} s after the bridge; the physics loop ran at {}.\n",
        if report.kept_real_time { "kept" } else { "NOT KEPT — these scores are not those of a real-time run" },
        report.real_time_factor,
        report.late_steps,
        report.physics_steps,
        report.max_lateness_ms,
        report.physics_step_ms.p50_ms,
        report.physics_step_ms.p99_ms,
        report.physics_step_ms.max_ms,
        c.received,
        c.bad_crc,
        c.unusable,
        c.with_feedforward,
        c.parallel_ankle_mode,
        report.command_interarrival.p50_ms,
        report.command_interarrival.p99_ms,
        report.start_offset_s,
        report.scheduling,
    );
    let stream = &report.command_stream;
    lines.push_str(&if stream.healthy {
        format!(
            "\nCommands: one publisher throughout (longest gap {:.1} ms, the last {:.1} ms before the end).\n",
            stream.longest_gap_ms, stream.silent_at_end_ms
        )
    } else {
        format!(
            "\nCommands: BROKEN — {}; these scores are not those of a deployment.\n",
            stream.problems.join("; ")
        )
    });
    lines
}
