//! `thorarena bench eval`: the cost of the whole episode loop on one core — simulated
//! seconds per wall second, and the share of time spent outside the physics step (force
//! replay, metrics, policy, bookkeeping).

use std::path::PathBuf;
use std::sync::Arc;
use thorarena::episode::EpisodeSetup;
use thorarena::evaluation::TerminationRule;
use thorarena::motion::Dataset;
use thorarena::perf::time_episode_loop;
use thorarena::physics::{PhysicsSettings, RapierPhysics};
use thorarena::registry::{self, PolicyChoice};

/// Arguments of `bench eval`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Dataset directory.
    #[arg(long, default_value = "data/sample")]
    pub dataset: PathBuf,
    /// Policy in process: a built-in (hold, replay, balance) or a network
    /// (`twist2:FILE.onnx`, `beyondmimic:FILE.onnx`; see `thorarena policies`).
    #[arg(long, default_value = "hold")]
    pub policy: String,
    /// Force replay coefficient.
    #[arg(long, default_value_t = 1.0)]
    pub coefficient: f64,
    /// Robot.
    #[arg(long, default_value = "g1_29dof")]
    pub robot: String,
}

pub(super) fn run(args: &Args) -> anyhow::Result<()> {
    let robot = Arc::new(registry::robot(&args.robot)?);
    let profile = registry::profile(registry::family_profile(&args.policy), &robot)?;
    let ds = Dataset::open(&args.dataset, &robot)?;
    let sequences = ds.load_all()?;
    let PolicyChoice::InProcess(mut policy) = registry::policy(&args.policy, &robot, &profile)?
    else {
        anyhow::bail!(
            "bench eval times a policy in process: not `{}`",
            args.policy
        );
    };
    let setup = EpisodeSetup {
        robot: &robot,
        profile: &profile,
        keypoints: robot.keypoint_set("default").expect("default keypoints"),
        termination: TerminationRule::default(),
        force_coefficient: args.coefficient,
        push_n: 0.0,
        push_heading_deg: None,
        reference_offsets_s: policy.reference_offsets_s(),
    };
    let settings = PhysicsSettings {
        dt_s: profile.physics_dt_s,
        ..Default::default()
    };
    let mut physics = RapierPhysics::new(robot.clone(), settings, profile.gains.clone());
    let t = time_episode_loop(
        &setup,
        &sequences,
        policy.as_mut(),
        &mut physics,
        profile.control_dt_s,
    );
    let (wall, in_physics) = (t.wall.as_secs_f64(), t.in_physics.as_secs_f64());
    println!(
        "episode loop: {} episodes, {:.1} s simulated in {wall:.2} s wall on one core = {:.1} simulated s per wall s",
        t.episodes,
        t.simulated_s,
        t.real_time_factor()
    );
    println!(
        "physics step: {in_physics:.2} s ({:.1} %); outside physics (replay, metrics, policy, bookkeeping): {:.2} s = {:.1} % (goal ≤ 3 %)",
        100.0 * (1.0 - t.outside_physics()),
        wall - in_physics,
        100.0 * t.outside_physics()
    );
    Ok(())
}
