//! Synthetic motion–force dataset: the six tasks of the ThorArena paper (SOURCES.md) generated
//! kinematically for our robot, with hand forces calibrated so that the benchmark
//! discriminates between policies (SOURCES.md, push probe).
//!
//! Each sequence is planned in the world (pelvis, feet, waist and hand targets, world hand
//! forces), solved to joint angles by inverse kinematics, and its forces converted to the
//! hand's sensor frame through a per-sequence sensor calibration. Every sequence draws
//! from its own generator seeded by (seed, task, index), so any subset of tasks or any
//! number of sequences per task regenerates the same sequences bit for bit.
//!
//! One file per idea: `tasks.rs` and `walking.rs` plan each frame in the world, `gait.rs`
//! makes the walking tasks' footholds and pelvis path, `solve.rs` turns a plan into joints
//! with `ik.rs` (6-D leg IK per foot relative to the planned pelvis, the waist set
//! directly, 3-D hand IK with a null-space pull toward a nominal arm; joints kept 0.03 rad
//! inside their limits), and `forces.rs` draws the forces and says how their levels were
//! calibrated. Hand targets are first pulled within 90 % of the arm's reach, so the IK
//! fails (`SynthError::IkFailed`, naming task, sequence, frame and limb) only where a
//! joint limit binds.
//!
//! The tasks: `clean_table` stands and wipes (circles or back and forth, one hand or
//! both, bouts with pauses); `liftup_water` / `liftdown_water` squat to a container on a
//! low surface and stand up holding it, or the reverse; `push_chair` walks forward and
//! `pull_chair` backward with both hands on a chair back; `syn_carry` walks forward or
//! backward, turning in 60 % of its sequences, holding an object with a partner. Steps
//! are 0.15–0.26 m forward (longer ones push a flat trailing foot's ankle past its
//! −0.87 rad limit) and 0.15–0.22 m backward.
//!
//! Forces are planned in the world and stored in each hand's sensor frame,
//! `f_sensor = (R_world_hand · R_hand_sensor)⁻¹ f_world`, through a per-sequence
//! `hand_from_sensor` of ±90° about the hand's x axis (opposite per side) tilted by up to
//! 3°, so a replay that skips the calibration applies wrongly directed forces.

mod balance;
mod forces;
mod gait;
mod ik;
mod skeleton;
mod solve;
mod tasks;
mod walking;
mod write;

pub use ik::{chain_to_root, Chain, IkParams, Residual, Target};
pub use solve::IkStats;
pub use write::{write_synthetic, SynthWriteError};

use crate::sim::motion::{Sequence, LEFT, RIGHT};
use crate::sim::robot::RobotModel;
use nalgebra::{UnitQuaternion, Vector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::json;
use walking::WalkTask;

/// The paper's six tasks, in a fixed order (the order enters the per-sequence seed).
pub const TASKS: [&str; 6] = [
    "clean_table",
    "liftdown_water",
    "liftup_water",
    "pull_chair",
    "push_chair",
    "syn_carry",
];

/// The generator versions, each reproducible for its seed: 1 plans the motion
/// kinematically with forces scaled below the real levels; 2 draws the real levels and
/// balances each motion under its forces ([`balance`]). Recorded in the provenance.
pub const GENERATOR_VERSIONS: [u32; 2] = [1, 2];

/// The version [`SynthOptions::default`] generates.
pub const GENERATOR_VERSION: u32 = 1;

/// What to generate.
#[derive(Debug, Clone)]
pub struct SynthOptions {
    /// Sequences per task (the paper has 60).
    pub per_task: usize,
    /// Master seed.
    pub seed: u64,
    /// Frame rate, Hz (50: the control rate of the peer policies).
    pub fps: f64,
    /// Tasks to generate (names from [`TASKS`]); empty means all.
    pub tasks: Vec<String>,
    /// Generator version, one of [`GENERATOR_VERSIONS`].
    pub version: u32,
}

impl Default for SynthOptions {
    fn default() -> Self {
        Self {
            per_task: 60,
            seed: 0,
            fps: 50.0,
            tasks: Vec::new(),
            version: GENERATOR_VERSION,
        }
    }
}

/// Why generation failed.
#[derive(Debug, thiserror::Error)]
pub enum SynthError {
    /// A task name not in [`TASKS`].
    #[error("unknown task `{0}` (known: {known})", known = TASKS.join(", "))]
    UnknownTask(String),
    /// The robot lacks a link or joint the generator needs.
    #[error("robot unsuitable for synthesis: {0}")]
    Robot(String),
    /// Options out of range.
    #[error("invalid option: {0}")]
    Options(String),
    /// Inverse kinematics missed a target by more than its tolerance.
    #[error(
        "{task}/{sequence} frame {frame}: {limb} IK did not converge (residual {residual_m:.4})"
    )]
    IkFailed {
        /// Task.
        task: String,
        /// Sequence id.
        sequence: String,
        /// Frame index.
        frame: usize,
        /// Which limb.
        limb: String,
        /// Remaining error (m, plus rad for feet).
        residual_m: f64,
    },
}

/// Generates `per_task` sequences for each selected task, calling `progress(done, total)`
/// after each sequence.
pub fn synthesize(
    robot: &RobotModel,
    opts: &SynthOptions,
    mut progress: impl FnMut(usize, usize),
) -> Result<Vec<Sequence>, SynthError> {
    if !(opts.fps.is_finite() && opts.fps >= 10.0) {
        return Err(SynthError::Options(format!("fps {} (need ≥ 10)", opts.fps)));
    }
    if !GENERATOR_VERSIONS.contains(&opts.version) {
        return Err(SynthError::Options(format!(
            "generator version {}: the versions are {GENERATOR_VERSIONS:?}",
            opts.version
        )));
    }
    let mut selected = Vec::new();
    for name in &opts.tasks {
        let i = TASKS
            .iter()
            .position(|t| t == name)
            .ok_or_else(|| SynthError::UnknownTask(name.clone()))?;
        if !selected.contains(&i) {
            selected.push(i);
        }
    }
    if selected.is_empty() {
        selected = (0..TASKS.len()).collect();
    }
    selected.sort_unstable();
    let sk = skeleton::Skeleton::new(robot)?;
    let total = selected.len() * opts.per_task;
    let mut out = Vec::with_capacity(total);
    for &t in &selected {
        for i in 0..opts.per_task {
            out.push(sequence(robot, &sk, opts, t, i)?);
            progress(out.len(), total);
        }
    }
    Ok(out)
}

/// The generator of one sequence: 32 seed bytes from (seed, task, index) by SplitMix64,
/// independent of any other sequence.
fn rng_for(seed: u64, task: usize, index: usize) -> ChaCha8Rng {
    let mut state = seed ^ ((task as u64) << 48) ^ (index as u64).wrapping_mul(0x9E37_79B9);
    let mut bytes = [0u8; 32];
    for chunk in bytes.chunks_mut(8) {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        chunk.copy_from_slice(&(z ^ (z >> 31)).to_le_bytes());
    }
    ChaCha8Rng::from_seed(bytes)
}

/// The sensor-to-hand calibration: the sensor is mounted rolled ±90° about the hand's x
/// axis (opposite per side, so a policy that ignores the calibration gets the force
/// direction wrong) and off by up to 3° about a random axis, as a real mounting would be.
fn calibration(rng: &mut ChaCha8Rng, side: usize) -> UnitQuaternion<f64> {
    let roll = if side == LEFT { 1.0 } else { -1.0 } * std::f64::consts::FRAC_PI_2;
    let axis = Vector3::new(
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
    );
    let tilt = rng.random_range(0.0..3f64.to_radians());
    let jitter = nalgebra::Unit::try_new(axis, 1e-6).map_or(UnitQuaternion::identity(), |a| {
        UnitQuaternion::from_axis_angle(&a, tilt)
    });
    UnitQuaternion::from_axis_angle(&Vector3::x_axis(), roll) * jitter
}

fn wxyz(q: &UnitQuaternion<f64>) -> [f64; 4] {
    [q.w, q.i, q.j, q.k]
}

fn sequence(
    robot: &RobotModel,
    sk: &skeleton::Skeleton,
    opts: &SynthOptions,
    task_index: usize,
    index: usize,
) -> Result<Sequence, SynthError> {
    let task = TASKS[task_index];
    let id = format!("{task}_{index:03}");
    let mut rng = rng_for(opts.seed, task_index, index);
    let dur = rng.random_range(10.0..30.0);
    let lv = forces::Levels::of(opts.version);
    let fps = opts.fps;
    let mut plan = match task {
        "clean_table" => tasks::clean_table(sk, &mut rng, fps, dur, &lv),
        "liftdown_water" => tasks::lift(sk, &mut rng, fps, dur, false, &lv),
        "liftup_water" => tasks::lift(sk, &mut rng, fps, dur, true, &lv),
        "pull_chair" => walking::walking(sk, &mut rng, fps, dur, WalkTask::PullChair, &lv),
        "push_chair" => walking::walking(sk, &mut rng, fps, dur, WalkTask::PushChair, &lv),
        _ => walking::walking(sk, &mut rng, fps, dur, WalkTask::Carry, &lv),
    };
    let (solved, balanced) = if opts.version >= 2 {
        let (solved, stats) = balance::balance(robot, sk, &mut plan, fps, task, &id)?;
        (solved, Some(stats))
    } else {
        (solve::realize(robot, sk, &plan, task, &id)?, None)
    };
    let cal = [calibration(&mut rng, LEFT), calibration(&mut rng, RIGHT)];
    let noise = [LEFT, RIGHT].map(|_| {
        let drift = rng.random_range(0.2..0.6);
        forces::SensorNoise::new(&mut rng, 0.3, drift)
    });
    let mut force_sensor = [Vec::new(), Vec::new()];
    for side in [LEFT, RIGHT] {
        for (k, f_w) in plan.force_world[side].iter().enumerate() {
            // world = hand_rot · hand_from_sensor · sensor, so sensor = (…)⁻¹ · world.
            let world_from_sensor = solved.hand_rot[side][k] * cal[side];
            let f_s = world_from_sensor.inverse() * f_w;
            let e = noise[side].sample(&mut rng, k as f64 / opts.fps);
            force_sensor[side].push([f_s.x + e[0], f_s.y + e[1], f_s.z + e[2]]);
        }
    }
    let mut provenance = json!({"generator": "thorarena synth", "version": opts.version,
        "seed": opts.seed, "duration_s": dur, "task_params": plan.params, "ik": solved.stats});
    if let Some(stats) = balanced {
        // Version 1's provenance stays as it was, so its files (and hashes) do too.
        provenance["balance"] = json!(stats);
        provenance["force_levels"] = json!(lv);
    }
    let frames = &plan.frames;
    Ok(Sequence {
        task: task.to_string(),
        sequence_id: id,
        fps: opts.fps,
        joint_names: robot.joints.iter().map(|j| j.name.clone()).collect(),
        root_pos: frames
            .iter()
            .map(|f| f.pelvis.translation.vector.into())
            .collect(),
        root_quat_wxyz: frames.iter().map(|f| wxyz(&f.pelvis.rotation)).collect(),
        joint_pos: solved.joint_pos,
        joint_vel: None,
        force_sensor,
        hand_from_sensor_wxyz: [wxyz(&cal[LEFT]), wxyz(&cal[RIGHT])],
        force_point_hand: [LEFT, RIGHT].map(|s| robot.hands[s].point_hand.coords.into()),
        forces_recorded: true,
        provenance,
    })
}
