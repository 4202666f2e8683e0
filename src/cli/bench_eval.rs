//! `thorarena bench eval`: the cost of the whole episode loop on one core — simulated
//! seconds per wall second, and the share of time spent outside the physics step (force
//! replay, metrics, policy, bookkeeping).

use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};
use thorarena::episode::{Episode, EpisodeSetup};
use thorarena::evaluation::TerminationRule;
use thorarena::motion::Dataset;
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
    let (mut wall, mut in_physics, mut simulated) = (Duration::ZERO, Duration::ZERO, 0.0);
    let mut actions = vec![vec![0.0; robot.n_joints()]];
    for seq in &sequences {
        let started = Instant::now();
        let mut ep = Episode::start(&setup, seq, &mut physics);
        let mut steps = 0usize;
        while !ep.is_done() {
            policy.act(&[ep.observation()], &mut actions);
            ep.advance(&mut physics, &actions[0]);
            steps += 1;
        }
        in_physics += ep.physics_wall();
        wall += started.elapsed();
        simulated += steps as f64 * profile.control_dt_s;
    }
    let rtf = simulated / wall.as_secs_f64();
    let outside = 1.0 - in_physics.as_secs_f64() / wall.as_secs_f64();
    println!(
        "episode loop: {} episodes, {simulated:.1} s simulated in {:.2} s wall on one core = {rtf:.1} simulated s per wall s",
        sequences.len(),
        wall.as_secs_f64()
    );
    println!(
        "physics step: {:.2} s ({:.1} %); outside physics (replay, metrics, policy, bookkeeping): {:.2} s = {:.1} % (goal ≤ 3 %)",
        in_physics.as_secs_f64(),
        100.0 * (1.0 - outside),
        (wall - in_physics).as_secs_f64(),
        100.0 * outside
    );
    Ok(())
}
