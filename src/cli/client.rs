//! `thorarena client`: a built-in policy as a separate process speaking the protocol —
//! the Rust example client, the reference the Python and C++ clients are tested against
//! (same policy in process and out of process gives the same episodes, bit for bit), and
//! the echo policy of the latency benchmark.

use anyhow::{bail, Context};
use std::io::Write;
use std::time::Duration;
use thorarena::policy::wire::WireAnswer;
use thorarena::policy::Policy;
use thorarena_ipc::{Next, PolicyClient, PolicyConfig, WaitPolicy};

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
    let robot = thorarena::registry::robot(&args.robot)?;
    let joint_names: Vec<String> = robot.joints.iter().map(|j| j.name.clone()).collect();
    let mut config = PolicyConfig::new(
        &args.session,
        args.name.as_deref().unwrap_or(&args.policy),
        joint_names,
        vec![0.0],
    );
    if let Some(pid) = args.announce_pid {
        config.announced_pid = pid;
    }
    config.wait = WaitPolicy {
        spin: Duration::from_micros(args.spin_us),
        ..WaitPolicy::default()
    };
    if !(args.connect_timeout.is_finite() && args.connect_timeout > 0.0) {
        bail!("--connect-timeout must be > 0 s");
    }
    let timeout = Duration::try_from_secs_f64(args.connect_timeout).map_err(|_| {
        anyhow::anyhow!(
            "--connect-timeout {} s: too long to wait (give seconds that fit a duration)",
            args.connect_timeout
        )
    })?;
    let mut client = PolicyClient::connect(&config, timeout)
        .with_context(|| format!("joining session `{}`", args.session))?;
    let info = client.info().clone();
    let offset = info.action_offset_rad.clone();
    let mut policy: Option<Box<dyn Policy>> = match args.policy.as_str() {
        "echo" => None,
        name => match thorarena::registry::builtin_policy(name, &robot, &offset) {
            Some(policy) => Some(policy?),
            None => bail!("unknown policy `{name}` (balance, replay, hold, echo)"),
        },
    };
    println!("connected");
    std::io::stdout().flush()?;
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
        if args.delay_ms > 0.0 && (args.delay_at_step == 0 || args.delay_at_step == steps) {
            std::thread::sleep(
                Duration::try_from_secs_f64(args.delay_ms / 1e3).unwrap_or(Duration::MAX),
            );
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
            if args.nan_at_step == Some(steps) {
                out.all().fill(f64::NAN);
            }
            if args.bad_header_at_step == Some(steps) {
                out.header_bytes_mut()[..4].fill(0);
            }
        })?;
        if let Some(why) = broken {
            bail!("{why}");
        }
        step.send(&client)?;
        if args.die_after_steps == Some(steps) {
            eprintln!("--die-after-steps {steps}: killing myself");
            // SAFETY: raising a signal on our own process has no memory-safety effect.
            unsafe {
                libc::raise(libc::SIGKILL);
            }
        }
    }
    eprintln!("the run is over after {steps} steps");
    Ok(())
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
    fn check(&mut self, obs: &thorarena_ipc::ObsBatch) -> Option<String> {
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
