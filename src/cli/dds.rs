//! `thorarena dds`: the simulated G1 on its own DDS interface (`rt/lowstate`,
//! `rt/secondary_imu` out, `rt/lowcmd` in), so deployment code written for the robot
//! drives one episode of a sequence in real time, with its hand forces replayed, and the
//! episode is scored into a normal run directory (plus `realtime.json`).

use super::choices::EngineArg;
use std::path::PathBuf;
use thorarena::dds::session::{run_dds_session, DdsSessionEvent, DdsSessionRequest};
use thorarena::dds::wireless_remote::RemoteScript;
use thorarena::eval::TerminationRule;

/// Arguments of `dds`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Dataset directory [default: the bundled sample dataset, as for `eval`].
    #[arg(long, value_parser = thorarena::sim::motion::dataset_arg)]
    pub dataset: Option<PathBuf>,
    /// The sequence of the episode, `TASK/SEQUENCE_ID`.
    #[arg(long)]
    pub sequence: String,
    /// Setting: `force` (the recorded hand forces replayed), `no-force`, or one of
    /// `eval --settings`' other forms.
    #[arg(long, default_value = "force", value_parser = super::choices::SettingArg)]
    pub setting: thorarena::eval::Setting,
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
    #[arg(long, default_value = "")]
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
    let request = DdsSessionRequest {
        dataset: args.dataset.clone(),
        sequence: args.sequence.clone(),
        setting: args.setting.clone(),
        profile: args.profile.clone(),
        engine: args.engine.into(),
        mjcf: args.mjcf.clone(),
        termination: TerminationRule {
            max_torso_height_error_m: args.max_torso_height_error,
            max_torso_tilt_error_rad: args.max_torso_tilt_error,
        },
        domain: args.domain,
        address: args.address,
        interface: args.interface.clone(),
        start_timeout_s: args.start_timeout,
        remote: args.remote.clone(),
        start_on: args.start_on.clone(),
        zmq_clock_port: args.zmq_clock,
        rt_priority: args.rt_priority,
        name: args.name.clone(),
        out: args.out.clone(),
        overwrite: args.overwrite,
    };
    let bar = indicatif::ProgressBar::new(0);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:40} {msg}").expect("valid template"),
    );
    let outcome = run_dds_session(&request, &mut |event| match event {
        DdsSessionEvent::Advice(text) | DdsSessionEvent::Serving(text) => {
            bar.suspend(|| eprintln!("{}", super::flags::as_flags(&text)))
        }
        DdsSessionEvent::Progress {
            progress: p,
            duration_s,
        } => {
            bar.set_length((duration_s * 10.0).round() as u64);
            bar.set_position((p.simulated_s * 10.0).round() as u64);
            bar.set_message(format!(
                "{:.1}/{duration_s:.1} s, {} commands, {} physics steps late",
                p.simulated_s, p.commands, p.late_steps
            ));
        }
    });
    bar.finish_and_clear();
    let outcome = outcome?;
    println!("{}", outcome.tables);
    for warning in outcome.warnings() {
        eprintln!("warning: {warning}");
    }
    eprintln!("results in {}", args.out.display());
    Ok(())
}
