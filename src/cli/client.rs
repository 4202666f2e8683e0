//! `thorarena client`: a built-in policy as a separate process speaking the protocol —
//! the Rust example client, the reference the Python and C++ clients are tested against
//! (same policy in process and out of process gives the same episodes, bit for bit), and
//! the echo policy of the latency benchmark.

use std::io::Write;
use std::time::Duration;
use thorarena::policy::client_process::{ClientFaults, ClientObserver};
use thorarena::policy::registry::{run_named_client, ClientRequest};

/// Arguments of `client`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Session to join (the simulator serves it: `thorarena eval --policy ipc:<session>` or
    /// `thorarena serve --session <session>`).
    #[arg(long)]
    pub session: String,
    /// `balance`, `replay`, `hold` (the built-in baselines; their action offset is the
    /// session's), or `echo` (action = q: the latency benchmark's policy).
    #[arg(long, default_value = "balance")]
    pub policy: String,
    /// Name in the results [default: the policy's].
    #[arg(long)]
    pub name: Option<String>,
    /// The bundled profile this client declares at connect as the one its policy runs
    /// under (the built-in baselines are made for `default`); `none` declares none, so
    /// the run must name one with `--profile`.
    #[arg(long, default_value = "default")]
    pub profile: String,
    /// Robot (its joint order is checked against the simulator's).
    #[arg(long, default_value = "g1_29dof")]
    pub robot: String,
    /// Seconds to wait for the simulator to serve the session.
    #[arg(long, default_value_t = 30.0)]
    pub connect_timeout: f64,
    /// Busy-poll this many µs for the next observations before blocking.
    #[arg(long, default_value_t = 50)]
    pub spin_us: u64,
    /// Testing aid: kill this process with SIGKILL after answering N steps.
    #[arg(long)]
    pub die_after_steps: Option<u64>,
    /// Testing aid: sleep this many ms before answering step `--delay-at-step`.
    #[arg(long, default_value_t = 0.0)]
    pub delay_ms: f64,
    /// Testing aid: the step (counted from 1) that `--delay-ms` delays; 0 delays every step.
    #[arg(long, default_value_t = 0)]
    pub delay_at_step: u64,
    /// Testing aid: announce this process id in the hello instead of ours (the simulator
    /// must not believe it).
    #[arg(long, hide = true)]
    pub announce_pid: Option<u32>,
    /// Testing aid: answer NaN for every joint of every environment at this step (counted
    /// from 1).
    #[arg(long)]
    pub nan_at_step: Option<u64>,
    /// Testing: answer this step (1-based) with a batch whose header is not the
    /// protocol's (its magic zeroed), as a broken policy would.
    #[arg(long, hide = true)]
    pub bad_header_at_step: Option<u64>,
}

pub(super) fn run(args: &Args) -> anyhow::Result<()> {
    let request = ClientRequest {
        session: args.session.clone(),
        policy: args.policy.clone(),
        name: args.name.clone(),
        profile: Some(args.profile.clone()).filter(|p| p != "none"),
        robot: args.robot.clone(),
        connect_timeout_s: args.connect_timeout,
        spin_us: args.spin_us,
        announced_pid: args.announce_pid,
        faults: ClientFaults {
            die_after_steps: args.die_after_steps,
            delay: Duration::try_from_secs_f64(args.delay_ms.max(0.0) / 1e3)
                .unwrap_or(Duration::MAX),
            delay_at_step: args.delay_at_step,
            nan_at_step: args.nan_at_step,
            bad_header_at_step: args.bad_header_at_step,
        },
    };
    let steps = run_named_client(&request, &mut Terminal)?;
    eprintln!("the run is over after {steps} steps");
    Ok(())
}

struct Terminal;

impl ClientObserver for Terminal {
    fn connected(&mut self) {
        println!("connected");
        let _ = std::io::stdout().flush();
    }

    fn dying(&mut self, steps: u64) {
        eprintln!("--die-after-steps {steps}: killing myself");
    }
}
