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
use thorarena::policy::{HoldPolicy, Policy, ReplayPolicy};
use thorarena::profile::{bundled_profile_path, load_profile};

/// Arguments of `bench eval`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Dataset directory.
    #[arg(long, default_value = "data/sample")]
    pub dataset: PathBuf,
    /// Built-in policy: hold or replay.
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
    let robot = Arc::new(thorarena::registry::robot(&args.robot)?);
    let profile = load_profile(&bundled_profile_path("default"), &robot)?;
    let ds = Dataset::open(&args.dataset, &robot)?;
    let sequences = ds.load_all()?;
    let mut policy: Box<dyn Policy> = match args.policy.as_str() {
        "hold" => Box::new(HoldPolicy),
        "replay" => Box::new(ReplayPolicy::new(profile.action_offset_rad.clone())),
        other => anyhow::bail!("unknown policy `{other}` (hold, replay)"),
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
