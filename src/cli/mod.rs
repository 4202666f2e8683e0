//! The `thorarena` command line: the argument tree and one module per subcommand.

mod bench_eval;
mod bench_ipc;
mod bench_physics;
mod choices;
mod client;
mod crosscheck;
mod data;
mod data_check;
mod data_list;
mod dds;
mod eval;
mod eval_run;
pub(crate) use thorarena::eval::flag_names as flags;
mod leaderboard;
mod logging;
mod policy_check;
mod policy_io_args;
mod report_html;
mod robot;
mod run_args;
mod serve;
mod sweep;

use clap::{Parser, Subcommand};

/// ThorArena: force-aware benchmark for humanoid whole-body control policies.
///
/// A simulated Unitree G1 (rapier multibody) tracks retargeted human motion while the
/// recorded two-hand interaction forces are replayed on its hands; policies are scored with
/// the Force-Aware Tracking Score (FATS) with and without force.
#[derive(Debug, Parser)]
#[command(name = "thorarena", version, about, long_about, after_long_help = FILES_HELP)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// Where the binary finds what it needs (`thorarena --help`).
const FILES_HELP: &str = "\
Files:
  Robots (data/robots), dynamics profiles (data/profiles) and the sample dataset
  (data/sample) are compiled into the binary and written once to
  $XDG_CACHE_HOME/thorarena/data-<hash> (else ~/.cache/thorarena/…), so an installed
  binary needs no checkout. THORARENA_DATA=DIR uses another data directory.
  The report and viewer front end (three.js, Chart.js) is compiled in as well;
  THORARENA_WEB_DIST=DIR uses another build of it.
  Results go to results/<policy>-<dataset> under the working directory unless --out says
  otherwise.";

/// Subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Evaluate a policy on a dataset, with and without force (FATS and diagnostics).
    Eval(eval::Args),
    /// Serve a session and evaluate every policy process that connects, one after another.
    Serve(serve::Args),
    /// Run a built-in policy as a separate process connected to a session (the Rust
    /// example client; `echo` for latency benchmarks).
    Client(client::Args),
    /// Serve the G1's own DDS interface (rt/lowstate, rt/lowcmd) for one episode in real
    /// time, so deployment code written for the robot drives it; scored like `eval`.
    Dds(dds::Args),
    /// List the policy families `--policy` can name: what each needs and its profile.
    Policies,
    /// Check a policy's wiring before scoring it (`policy check`).
    #[command(subcommand)]
    Policy(policy_check::PolicyCommand),
    /// Merge the shards of one evaluation (`eval --shard I/N`) into one run.
    Merge(eval::MergeArgs),
    /// Run the same episodes on rapier and on MuJoCo and compare them (survival, keypoint
    /// error, FATS per setting and per push force, with bootstrap confidence intervals;
    /// joint-angle divergence over the first second).
    Crosscheck(crosscheck::Args),
    /// Compare runs in one self-contained HTML report with plots (+ Markdown and CSV tables).
    Report(report_html::Args),
    /// Every policy given on the synthetic dataset, force and no-force, on each engine:
    /// one eval run per (policy, engine), one table, the paper's tables and figures.
    Leaderboard(leaderboard::Args),
    /// Replay one episode's trace (`eval --trace`) in 3D in a self-contained HTML page.
    View(report_html::ViewArgs),
    /// Inspect a robot model.
    #[command(subcommand)]
    Robot(RobotCommand),
    /// Run open-loop physics scenarios (used by the MuJoCo cross-check).
    #[command(subcommand)]
    Sim(SimCommand),
    /// Import motion data and inspect datasets.
    #[command(subcommand)]
    Data(data::DataCommand),
    /// Measure performance.
    #[command(subcommand)]
    Bench(BenchCommand),
    /// Headless sweeps: plan a spec of policies × datasets × settings × latency rules,
    /// run its tasks locally, on a Slurm array or a Kubernetes Indexed Job, and collect.
    #[command(subcommand)]
    Sweep(sweep::SweepCommand),
}

/// `thorarena robot …`
#[derive(Debug, Subcommand)]
pub enum RobotCommand {
    /// Print joints (order, limits, effort, armature), bodies with masses, keypoints, hands.
    Info(robot::Args),
    /// Print the robot as an MJCF: what `eval --engine mujoco` simulates without --mjcf.
    Mjcf(robot::MjcfArgs),
}

/// `thorarena sim …`
#[derive(Debug, Subcommand)]
pub enum SimCommand {
    /// Run an open-loop scenario and print its inputs and trajectory as one JSON object.
    Trace(robot::TraceArgs),
}

/// `thorarena bench …`
#[derive(Debug, Subcommand)]
pub enum BenchCommand {
    /// Cost of one physics step of the standing G1, against MuJoCo when available.
    Physics(bench_physics::Args),
    /// A whole evaluation of a policy in process against its physics floor measured in
    /// the same run: simulated s per wall s, cores busy, run ÷ floor.
    Eval(bench_eval::Args),
    /// A network's cost per environment against the batch size of one tract call.
    Inference(bench_physics::InferenceArgs),
    /// Policy round trip over shared memory (Rust, C++, Python echo policies) against a
    /// Unix-socket baseline moving the same bytes.
    Ipc(bench_ipc::Args),
    /// Sweep overhead: `sweep run` against `eval` on the same episodes, and planning a
    /// sweep of thousands of tasks.
    Sweep(bench_eval::SweepArgs),
    /// The socket baseline's echo peer (started by `bench ipc`).
    #[command(hide = true)]
    SocketPeer(bench_ipc::PeerArgs),
}

/// Runs the command line `cli`.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    logging::init();
    if let Command::Bench(bench) = &cli.command {
        if !matches!(bench, BenchCommand::SocketPeer(_)) {
            println!("{}", thorarena::campaign::bench::Machine::this());
        }
    }
    match cli.command {
        Command::Robot(RobotCommand::Info(args)) => robot::run(&args),
        Command::Robot(RobotCommand::Mjcf(args)) => robot::mjcf(&args),
        Command::Sim(SimCommand::Trace(args)) => robot::trace(&args),
        Command::Bench(BenchCommand::Physics(args)) => bench_physics::run(&args),
        Command::Bench(BenchCommand::Eval(args)) => bench_eval::run(&args),
        Command::Bench(BenchCommand::Inference(args)) => bench_physics::inference(&args),
        Command::Bench(BenchCommand::Ipc(args)) => bench_ipc::run(&args),
        Command::Bench(BenchCommand::Sweep(args)) => bench_eval::sweep(&args),
        Command::Bench(BenchCommand::SocketPeer(args)) => bench_ipc::run_peer(&args),
        Command::Data(cmd) => data::run(&cmd),
        Command::Eval(args) => eval::run(&args),
        Command::Merge(args) => eval::merge(&args),
        Command::Policies => {
            print!(
                "{}",
                flags::as_flags(&thorarena::policy::registry::families_text())
            );
            Ok(())
        }
        Command::Leaderboard(args) => leaderboard::run(&args),
        Command::Policy(cmd) => policy_check::run(&cmd),
        Command::Crosscheck(args) => crosscheck::run(&args),
        Command::Report(args) => report_html::run(&args),
        Command::View(args) => report_html::view(&args),
        Command::Serve(args) => serve::run(&args),
        Command::Client(args) => client::run(&args),
        Command::Dds(args) => dds::run(&args),
        Command::Sweep(cmd) => sweep::run(&cmd),
    }
}
