//! `thorarena dds`: the simulated G1 on its own DDS interface (`rt/lowstate`,
//! `rt/secondary_imu` out, `rt/lowcmd` in), so deployment code written for the robot
//! drives one episode of a sequence in real time, with its hand forces replayed, and the
//! episode is scored into a normal run directory (plus `realtime.json`).

use super::choices::EngineArg;
use anyhow::{bail, Context};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;
use thorarena::dds::bridge::{run_episode, BridgeOptions, RealTimeReport};
use thorarena::dds::remote::RemoteScript;
use thorarena::dds::scheduling::SchedulingError;
use thorarena::dds::RobotEndpoints;
use thorarena::episode::{Episode, EpisodeSetup};
use thorarena::evaluation::{task_thresholds, EvalRequest, EvalSpec, TerminationRule};
use thorarena::motion::SequenceSelection;
use thorarena::physics::{make_physics, PhysicsSettings};
use thorarena::results::{RunDir, RunHeader};

/// Arguments of `dds`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Dataset directory.
    #[arg(long, default_value = "data/sample")]
    pub dataset: PathBuf,
    /// The sequence of the episode, `TASK/SEQUENCE_ID`.
    #[arg(long)]
    pub sequence: String,
    /// Setting: `force` (the recorded hand forces replayed), `no-force`, or one of
    /// `eval --settings`' other forms.
    #[arg(long, default_value = "force")]
    pub setting: String,
    /// Dynamics profile (its physics step, torque limits and control period for the
    /// metrics; the gains are the commands').
    #[arg(long, default_value = "default")]
    pub profile: String,
    /// Physics engine.
    #[arg(long, value_enum, default_value = "rapier")]
    pub engine: EngineArg,
    /// MJCF of the robot for `--engine mujoco` [default: generated from the robot model].
    #[arg(long)]
    pub mjcf: Option<PathBuf>,
    /// DDS domain (Unitree's scripts use 0).
    #[arg(long, default_value_t = 0)]
    pub domain: u16,
    /// Use only the network interface with this address for DDS (127.0.0.1: loopback,
    /// nothing leaves the machine; the deployment code must then use `lo`).
    #[arg(long, default_value = "127.0.0.1", conflicts_with = "interface")]
    pub address: std::net::IpAddr,
    /// Use only this network interface for DDS, by name as deployment code names it
    /// (`lo`, `enp3s0`; its first IPv4 address), instead of `--address`.
    #[arg(long)]
    pub interface: Option<String>,
    /// Seconds to wait for the first command (the reference clock starts with it).
    #[arg(long, default_value_t = 60.0)]
    pub start_timeout: f64,
    /// Termination: torso height off its reference by more than this, m (a large value
    /// lets a script that does not balance — Unitree's low-level examples, written for a
    /// robot on a gantry — run through its stages on the ground).
    #[arg(long, default_value_t = TerminationRule::default().max_torso_height_error_m)]
    pub max_torso_height_error: f64,
    /// Termination: torso tilt off its reference by more than this, rad.
    #[arg(long, default_value_t = TerminationRule::default().max_torso_tilt_error_rad)]
    pub max_torso_tilt_error: f64,
    /// Wireless-remote presses, each `BUTTON@SECONDS` after the bridge starts, for
    /// scripts that wait for buttons (e.g. `start@1s,A@3s`; a chord joins buttons with
    /// `+`, e.g. `select+A@4s`; buttons R1 L1 start select R2 L2 F1 F2 A B X Y up right
    /// down left). Carried in `rt/lowstate`'s `wireless_remote` and on
    /// `rt/wirelesscontroller`.
    #[arg(long, default_value = "", value_parser = parse_remote)]
    pub remote: RemoteScript,
    /// When the episode (and the reference clock) starts: `first-command`, or a button or
    /// chord `--remote` presses (e.g. `A`: a deploy script's "run the policy";
    /// `select+A`: holosoma's "start the motion clip"); until then the robot is held
    /// still at the reference's first frame, as on a gantry.
    #[arg(long, default_value = "first-command")]
    pub start_on: String,
    /// Also publish the simulator's clock as holosoma's simulator does (ZeroMQ PUB on
    /// 127.0.0.1:PORT, holosoma's default 5555; milliseconds as text, with each state),
    /// for holosoma's inference package run with `--task.use-sim-time`.
    #[arg(long, value_name = "PORT")]
    pub zmq_clock: Option<u16>,
    /// Real-time priority (SCHED_FIFO, 1–99) of the simulated robot: its physics loop
    /// and its DDS threads. The G1's motor controllers do not share a computer with the
    /// policy; on one machine the policy process could otherwise delay physics steps.
    /// 50 is ros2_control's default for its control loop. Needs root, or RLIMIT_RTPRIO
    /// at least this (`ulimit -r`); refused, the bridge runs at normal priority and says
    /// so (`realtime.json` records what it ran under). 0: normal priority.
    #[arg(long, default_value_t = 50)]
    pub rt_priority: i32,
    /// The policy's name in the results.
    #[arg(long, default_value = "dds")]
    pub name: String,
    /// Run directory.
    #[arg(long)]
    pub out: PathBuf,
    /// Replace a run already in `--out`.
    #[arg(long)]
    pub overwrite: bool,
}

pub(super) fn run(args: &Args) -> anyhow::Result<()> {
    thorarena::names::check_name("policy name", &args.name)?;
    if !(args.start_timeout.is_finite() && args.start_timeout > 0.0) {
        bail!("--start-timeout must be > 0 s");
    }
    let start_button = match args.start_on.as_str() {
        "first-command" => None,
        name => match thorarena::dds::remote::chord_bits(name) {
            Some(bits) if args.remote.presses(bits) => Some(bits),
            Some(_) => bail!("--start-on {name}: --remote never presses {name}"),
            None => bail!(
                "--start-on {name}: give first-command, a button ({}) or a chord (select+A)",
                thorarena::dds::remote::BUTTONS.join(", ")
            ),
        },
    };
    if let Some(at) = start_button.and_then(|bits| args.remote.first_press(bits)) {
        if at.as_secs_f64() >= args.start_timeout {
            bail!("--start-on {} presses at {:.1} s, after --start-timeout {} s: the bridge would give up first", args.start_on, at.as_secs_f64(), args.start_timeout);
        }
    }
    let address = match &args.interface {
        Some(name) => std::net::IpAddr::V4(thorarena::dds::interface::ipv4_of(name)?),
        None => args.address,
    };
    thorarena::dds::interface::check_local_address(address)?;
    if args.domain > thorarena::dds::MAX_DOMAIN {
        bail!("{}", thorarena::dds::DdsError::Domain(args.domain));
    }
    let Some((task, _)) = args.sequence.split_once('/') else {
        bail!("--sequence {}: give TASK/SEQUENCE_ID", args.sequence);
    };
    let spec = EvalSpec::load(&EvalRequest {
        policy: args.name.clone(),
        dataset: Some(args.dataset.clone()),
        profile: Some(args.profile.clone()),
        settings: vec![args.setting.clone()],
        selection: SequenceSelection {
            tasks: vec![task.to_string()],
            sequences: vec![args.sequence.clone()],
        },
        workers: Some(1),
        envs: Some(1),
        engine: args.engine.into(),
        mjcf: args.mjcf.clone(),
        trace: vec![args.sequence.clone()],
        termination: TerminationRule {
            max_torso_height_error_m: args.max_torso_height_error,
            max_torso_tilt_error_rad: args.max_torso_tilt_error,
        },
        ..EvalRequest::default()
    })?;
    for advice in &spec.advice {
        eprintln!("{advice}");
    }
    let [seq] = spec.sequences.as_slice() else {
        bail!(
            "--sequence {} names {} sequences",
            args.sequence,
            spec.sequences.len()
        );
    };
    super::eval::refuse_out_over_dataset(&args.out, Some(&args.dataset))?;
    let run = RunDir::new(&args.out);
    if run.holds_run() && !args.overwrite {
        bail!(
            "{} already holds a run: pass --overwrite to replace it, or choose another --out",
            args.out.display()
        );
    }
    run.check_writable()?;
    // The one writer of the run from now until its last file: a second bridge given the
    // same --out is refused before it joins the domain.
    let _writer = run.lock()?;
    let robot = Arc::new(spec.robot.clone());
    let mut physics = make_physics(
        &spec.engine,
        robot.clone(),
        PhysicsSettings {
            dt_s: spec.profile.physics_dt_s,
            ..Default::default()
        },
        spec.profile.gains.clone(),
    )?;
    let setting = &spec.settings[0];
    let setup = EpisodeSetup::for_setting(
        &spec.robot,
        &spec.profile,
        spec.robot
            .keypoint_set(&spec.keypoints)
            .context("keypoint set")?,
        spec.termination,
        setting,
        vec![0.0],
    );
    // Before the DDS participant starts its threads: they inherit it.
    if args.rt_priority != 0 {
        if let Err(e) = thorarena::dds::scheduling::enter_fifo(args.rt_priority) {
            match e {
                SchedulingError::OutOfRange { .. } => bail!("--rt-priority: {e}"),
                SchedulingError::Refused { .. } => eprintln!(
                    "warning: {e}: running at normal priority, where the policy's process can delay physics steps (--rt-priority 0 asks for it)"
                ),
            }
        }
    }
    let mut endpoints = RobotEndpoints::join(args.domain, Some(address))?;
    let mut episode = Episode::start(&setup, seq, physics.as_mut());
    episode.record_trace();
    eprintln!(
        "{}/{} ({}, {:.1} s): rt/lowstate at 500 Hz on DDS domain {} ({}); the episode starts {}…",
        seq.task,
        seq.sequence_id,
        setting.name,
        seq.duration_s(),
        args.domain,
        match &args.interface {
            Some(name) => format!("{name}, {address}"),
            None => address.to_string(),
        },
        match start_button {
            None => "with the first valid rt/lowcmd".to_string(),
            Some(_) => format!("at the remote's {} press", args.start_on),
        }
    );
    let options = BridgeOptions {
        state_period: Duration::from_millis(2),
        start_timeout: Duration::from_secs_f64(args.start_timeout),
        torso_body: spec.robot.frame_index("torso_link").unwrap_or(0),
        remote: args.remote.clone(),
        start_button,
        zmq_clock_port: args.zmq_clock,
    };
    let duration_s = seq.duration_s();
    let bar = indicatif::ProgressBar::new((duration_s * 10.0).round() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:40} {msg}").expect("valid template"),
    );
    let realtime = run_episode(
        &mut endpoints,
        &mut episode,
        physics.as_mut(),
        &spec.profile.gains,
        &options,
        &mut |p| {
            bar.set_position((p.simulated_s * 10.0).round() as u64);
            bar.set_message(format!(
                "{:.1}/{duration_s:.1} s, {} commands, {} physics steps late",
                p.simulated_s, p.commands, p.late_steps
            ));
        },
    );
    bar.finish_and_clear();
    let realtime = realtime?;
    let trace = episode.take_trace();
    let record = episode.into_record(seq, setting, &args.name);
    // Started only now: a bridge that got no command leaves no empty run behind.
    let header = RunHeader::of(&spec, &args.name);
    run.start(&header, false)?;
    let mut appender = run.appender()?;
    appender.append(&record)?;
    appender.flush()?;
    if let Some(trace) = trace {
        run.write_trace(&record.key(), &trace.steps)?;
    }
    let thresholds = task_thresholds(&spec.sequences, spec.profile.control_dt_s);
    let summary = run.finish(&header, &mut [record], thresholds, None)?;
    let mut tables = thorarena::report::write_run_tables(run.path(), &summary)?;
    write_realtime(&run, &realtime, &mut tables)?;
    println!("{tables}");
    eprintln!("results in {}", args.out.display());
    Ok(())
}

/// `realtime.json`, and a line in `tables.md` saying whether the run kept real time.
fn write_realtime(
    run: &RunDir,
    report: &RealTimeReport,
    tables: &mut String,
) -> anyhow::Result<()> {
    let path = run.path().join("realtime.json");
    thorarena::atomic_file::write(&path, serde_json::to_string_pretty(report)?)
        .with_context(|| format!("writing {}", path.display()))?;
    let c = &report.commands;
    let line = format!(
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
    tables.push_str(&line);
    let stream = &report.command_stream;
    tables.push_str(&if stream.healthy {
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
    let tables_path = run.path().join("tables.md");
    thorarena::atomic_file::write(&tables_path, tables.as_bytes())
        .with_context(|| format!("writing {}", tables_path.display()))?;
    if !report.kept_real_time {
        eprintln!("warning: the run did not keep real time (realtime.json)");
    }
    if !stream.healthy {
        eprintln!(
            "warning: the command stream broke: {} (realtime.json)",
            stream.problems.join("; ")
        );
    }
    Ok(())
}

fn parse_remote(text: &str) -> Result<RemoteScript, String> {
    RemoteScript::parse(text).map_err(|e| e.to_string())
}
