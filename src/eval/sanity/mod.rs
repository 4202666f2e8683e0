//! The sanity check a policy passes before its scores count (`thorarena policy check`):
//! a policy that fails it is wired wrong — layout, joint order, action mapping, profile —
//! not a bad policy, and its scores would measure the wiring (the DDC benchmark's rule).
//!
//! Four checks, each reported with its numbers:
//! 1. **wiring** — the policy's own account of its inputs and action mapping against the
//!    profile ([`Policy::wiring`]): any disagreement fails;
//! 2. **stand** — a standing reference (the profile's default pose, feet on the ground)
//!    for [`SanityOptions::stand_s`] without force: survival 1.0;
//! 3. **track** — a reference without force (the first seconds of a walking sequence for a
//!    general tracker, a single-clip policy's own clip): survival 1.0 and the RMS keypoint
//!    error under [`SanityOptions::max_kp_rms_mm`];
//! 4. **zero action** — the same reference with the policy's zero action
//!    ([`Policy::zero_action`]) in place of its own: clearly worse — lower survival, or a
//!    keypoint error at least [`SanityOptions::zero_worse_ratio`] times the policy's — so
//!    the network, not the PD, is doing the work.
//!
//! Episodes run one at a time on one engine, through the same `Episode` as an evaluation.

pub mod following;

use crate::eval::episode::{Episode, EpisodeSetup};
use crate::eval::TerminationRule;
use crate::policy::{ActOutcome, Observation, Policy};
use crate::sim::motion::Sequence;
use crate::sim::physics::{make_physics, Engine, EngineError, PhysicsSettings};
use crate::sim::profile::Profile;
use crate::sim::robot::{forward_kinematics, lowest_sole_point_z, RobotModel};
use following::{Following, FollowingMeter};
use nalgebra::Isometry3;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// Why the check could not run (a failed check is a result, not an error).
#[derive(Debug, thiserror::Error)]
pub enum SanityError {
    /// The engine could not be made.
    #[error(transparent)]
    Engine(#[from] EngineError),
    /// The robot has no keypoint set of that name.
    #[error("the robot has no keypoint set `{0}`")]
    Keypoints(String),
    /// The tracking reference is shorter than one control step.
    #[error("the tracking reference `{0}` is shorter than one control step")]
    EmptyReference(String),
    /// A command follower's root velocity is judged over windows longer than the clip.
    #[error("`{clip}` lasts {duration_s:.2} s, shorter than the {window_s} s window over which a command follower's root velocity is judged: check the policy on a clip of at least {window_s} s (`option.sequence`)")]
    TooShortToFollow {
        /// The clip, `task/sequence`.
        clip: String,
        /// Its length, s.
        duration_s: f64,
        /// The velocity window, s.
        window_s: f64,
    },
}

/// The check's thresholds and durations.
#[derive(Debug, Clone)]
pub struct SanityOptions {
    /// Length of the standing reference, s.
    pub stand_s: f64,
    /// How much of the tracking reference is run, s (all of it when shorter).
    pub track_s: f64,
    /// The largest RMS keypoint error tracking may have, mm.
    pub max_kp_rms_mm: f64,
    /// Zero action is clearly worse when it survives less, or when its keypoint error is
    /// at least this many times the policy's.
    pub zero_worse_ratio: f64,
    /// The engine.
    pub engine: Engine,
    /// The keypoint set errors are measured on.
    pub keypoints: String,
    /// Say each check as it starts and what it took (`log::info!`): `policy check` on a
    /// slow network would otherwise print nothing for minutes.
    pub announce: bool,
}

impl Default for SanityOptions {
    fn default() -> Self {
        Self {
            stand_s: 5.0,
            track_s: 10.0,
            max_kp_rms_mm: 100.0,
            zero_worse_ratio: 1.5,
            engine: Engine::Rapier,
            keypoints: "default".into(),
            announce: false,
        }
    }
}

/// One check's outcome.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CheckOutcome {
    /// `wiring`, `stand`, `track` or `zero_action`.
    pub name: String,
    /// Whether it passed.
    pub passed: bool,
    /// What was measured and against what, in one sentence.
    pub detail: String,
    /// Survival of its episode, where it ran one.
    pub survival: Option<f64>,
    /// RMS keypoint error of its episode, mm, where it ran one and survived a step.
    pub kp_rms_mm: Option<f64>,
}

/// The whole check: what was checked and how each part went.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SanityReport {
    /// The policy (its name in results).
    pub policy: String,
    /// The profile it ran under.
    pub profile: String,
    /// The engine, as `Engine::name` spells it.
    pub engine: String,
    /// The tracking reference, `task/sequence`.
    pub tracking_reference: String,
    /// The policy's own account of its wiring.
    pub facts: Vec<String>,
    /// The four checks, in order.
    pub checks: Vec<CheckOutcome>,
}

impl SanityReport {
    /// Whether every check passed.
    pub fn passed(&self) -> bool {
        self.checks.iter().all(|c| c.passed)
    }

    /// `Err` naming the failed checks when one failed: a command that ran the check
    /// ends with it (after showing the report).
    pub fn verdict(&self) -> Result<(), CheckFailed> {
        if self.passed() {
            return Ok(());
        }
        Err(CheckFailed {
            failed: self.failed().join(", "),
            profile: self.profile.clone(),
        })
    }

    /// The checks that failed, by name.
    pub fn failed(&self) -> Vec<&str> {
        self.checks
            .iter()
            .filter(|c| !c.passed)
            .map(|c| c.name.as_str())
            .collect()
    }
}

/// A sanity check that failed: the policy is wired wrong for its profile, or cannot track.
#[derive(Debug, thiserror::Error)]
#[error("policy check failed ({failed}): under `{profile}` this policy is wired wrong, or cannot track at all; its scores would not say how it handles force")]
pub struct CheckFailed {
    /// The failed checks, by name.
    pub failed: String,
    /// The profile it ran under.
    pub profile: String,
}

/// The report as `policy check` shows it: what ran, the policy's facts, one line per
/// check with its numbers, and the verdict when every check holds.
impl std::fmt::Display for SanityReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "policy check: {} under profile `{}` on {}, tracking {}",
            self.policy, self.profile, self.engine, self.tracking_reference
        )?;
        for fact in &self.facts {
            writeln!(f, "  {fact}")?;
        }
        for c in &self.checks {
            let mark = if c.passed { "pass" } else { "FAIL" };
            writeln!(f, "  {mark} {:<12} {}", c.name, c.detail)?;
        }
        if self.passed() {
            writeln!(f, "passed: every check holds, its scores can count")?;
        }
        Ok(())
    }
}

/// How one episode went.
#[derive(Debug, Clone, Copy)]
struct Run {
    survival: f64,
    kp_rms_mm: Option<f64>,
    /// Control steps whose action had a non-finite value (the previous action was held
    /// instead, as an evaluation's miss rule would), and the first of them.
    non_finite: Option<(usize, usize)>,
    /// What a command follower was asked to follow, and how it did (measured when the
    /// policy follows commands).
    following: Option<Following>,
}

impl Run {
    /// The check's verdict, failed by any non-finite action, and its detail, which then
    /// says so.
    fn verdict(&self, passed: bool, detail: String) -> (bool, String) {
        match self.non_finite {
            None => (passed, detail),
            Some((steps, first)) => (
                false,
                format!(
                    "{detail}; the network's actions were not finite on {steps} control steps (first at step {first}): a broken network or input"
                ),
            ),
        }
    }
}

/// Runs the four checks of `policy` under `profile` on `robot`, tracking `tracking` (the
/// first `options.track_s` of it).
pub fn check_policy(
    policy: &mut dyn Policy,
    robot: &RobotModel,
    profile: &Profile,
    tracking: &Sequence,
    options: &SanityOptions,
) -> Result<SanityReport, SanityError> {
    let keypoints = robot
        .keypoint_set(&options.keypoints)
        .ok_or_else(|| SanityError::Keypoints(options.keypoints.clone()))?;
    let tracking = truncated(tracking, options.track_s);
    if tracking.joint_pos.len() < 2 {
        return Err(SanityError::EmptyReference(format!(
            "{}/{}",
            tracking.task, tracking.sequence_id
        )));
    }
    if policy.follows_commands().is_some() && duration_s(&tracking) < following::VELOCITY_WINDOW_S {
        return Err(SanityError::TooShortToFollow {
            clip: format!("{}/{}", tracking.task, tracking.sequence_id),
            duration_s: duration_s(&tracking),
            window_s: following::VELOCITY_WINDOW_S,
        });
    }
    let wiring = policy.wiring();
    let mut checks = vec![CheckOutcome {
        name: "wiring".into(),
        passed: wiring.disagreements.is_empty(),
        detail: if wiring.disagreements.is_empty() {
            format!("the policy agrees with the profile `{}`", profile.name)
        } else {
            wiring.disagreements.join("; ")
        },
        survival: None,
        kp_rms_mm: None,
    }];
    let setup = EpisodeSetup {
        robot,
        profile,
        keypoints,
        termination: TerminationRule::default(),
        force_coefficient: 0.0,
        push_n: 0.0,
        push_heading_deg: None,
        disturbance: None,
        reference_offsets_s: policy.reference_offsets_s(),
    };
    let stand = standing_reference(robot, profile, options.stand_s);
    let phase = |name: &str, seq: &Sequence| {
        if options.announce {
            log::info!("policy check: {name} ({:.1} s simulated)…", duration_s(seq));
        }
        std::time::Instant::now()
    };
    let done = |started: std::time::Instant| {
        if options.announce {
            log::info!("  took {:.1} s", started.elapsed().as_secs_f64());
        }
    };
    let started = phase("stand", &stand);
    let stood = run_episode(policy, false, &setup, &stand, &options.engine)?;
    done(started);
    let (passed, detail) = stood.verdict(
        stood.survival >= 1.0,
        format!(
            "{:.0} s standing on the profile's default pose: survival {:.3} (must be 1.0)",
            options.stand_s, stood.survival
        ),
    );
    checks.push(CheckOutcome {
        name: "stand".into(),
        passed,
        detail,
        survival: Some(stood.survival),
        kp_rms_mm: stood.kp_rms_mm,
    });
    let started = phase("track", &tracking);
    let tracked = run_episode(policy, false, &setup, &tracking, &options.engine)?;
    done(started);
    checks.push(track_outcome(
        policy.follows_commands(),
        &tracked,
        &tracking,
        options,
    ));
    let started = phase("zero action", &tracking);
    let zeroed = run_episode(policy, true, &setup, &tracking, &options.engine)?;
    done(started);
    checks.push(zero_action_outcome(&zeroed, &tracked, options));
    Ok(SanityReport {
        policy: policy.name().to_string(),
        profile: profile.name.clone(),
        engine: options.engine.name().to_string(),
        tracking_reference: format!("{}/{}", tracking.task, tracking.sequence_id),
        facts: wiring.facts,
        checks,
    })
}

/// The track check: the reference tracked to its end, judged as a command follower's
/// (`follows`: what it follows) or a tracker's.
fn track_outcome(
    follows: Option<&str>,
    tracked: &Run,
    tracking: &Sequence,
    options: &SanityOptions,
) -> CheckOutcome {
    let kp_ok = tracked.kp_rms_mm.is_some_and(|e| e < options.max_kp_rms_mm);
    let (passed, detail) = match (follows, tracked.following) {
        (Some(what), Some(f)) => {
            let problems = f.problems(options.max_kp_rms_mm);
            tracked.verdict(
                tracked.survival >= 1.0 && problems.is_empty(),
                format!(
                    "{:.1} s of {}/{}, judged as a command follower ({what}): survival {:.3} (must be 1.0), root velocity error {:.3} m/s over {} s windows (under {}), heading error {:.1}° (under {}°), height error {:.1} mm (under {} mm), upper-body keypoint error in the root frame {:.1} mm (under {:.0} mm); world keypoint error {} (not judged: commands leave drift uncorrected){}",
                    duration_s(tracking),
                    tracking.task,
                    tracking.sequence_id,
                    tracked.survival,
                    f.velocity_rms_m_per_s,
                    following::VELOCITY_WINDOW_S,
                    following::MAX_VELOCITY_RMS_M_PER_S,
                    f.heading_rms_deg,
                    following::MAX_HEADING_RMS_DEG,
                    f.height_rms_mm,
                    following::MAX_HEIGHT_RMS_MM,
                    f.upper_kp_rms_mm,
                    options.max_kp_rms_mm,
                    mm(tracked.kp_rms_mm),
                    if problems.is_empty() {
                        String::new()
                    } else {
                        format!("; fails: {}", problems.join(", "))
                    }
                ),
            )
        }
        _ => tracked.verdict(
            tracked.survival >= 1.0 && kp_ok,
            format!(
                "{:.1} s of {}/{}: survival {:.3} (must be 1.0), keypoint error {} (must be under {:.0} mm)",
                duration_s(tracking),
                tracking.task,
                tracking.sequence_id,
                tracked.survival,
                mm(tracked.kp_rms_mm),
                options.max_kp_rms_mm
            ),
        ),
    };
    CheckOutcome {
        name: "track".into(),
        passed,
        detail,
        survival: Some(tracked.survival),
        kp_rms_mm: tracked.kp_rms_mm,
    }
}

/// The zero-action check: the same reference with zero action must do worse than
/// `tracked`.
fn zero_action_outcome(zeroed: &Run, tracked: &Run, options: &SanityOptions) -> CheckOutcome {
    // A command follower's zero action stands still where the reference moves: its
    // velocity error, not its world keypoint error, shows the network at work.
    let worse = zeroed.survival < tracked.survival
        || match (zeroed.following, tracked.following) {
            (Some(z), Some(t)) => {
                z.velocity_rms_m_per_s >= options.zero_worse_ratio * t.velocity_rms_m_per_s
            }
            _ => match (zeroed.kp_rms_mm, tracked.kp_rms_mm) {
                (Some(z), Some(t)) => z >= options.zero_worse_ratio * t,
                _ => false,
            },
        };
    CheckOutcome {
        name: "zero_action".into(),
        passed: worse,
        detail: match (zeroed.following, tracked.following) {
            (Some(z), Some(t)) => format!(
                "the same reference with zero action: survival {:.3} against {:.3}, root velocity error {:.3} against {:.3} m/s (must survive less, or err {:.1}× more)",
                zeroed.survival,
                tracked.survival,
                z.velocity_rms_m_per_s,
                t.velocity_rms_m_per_s,
                options.zero_worse_ratio
            ),
            _ => format!(
                "the same reference with zero action: survival {:.3} against {:.3}, keypoint error {} against {} (must survive less, or err {:.1}× more)",
                zeroed.survival,
                tracked.survival,
                mm(zeroed.kp_rms_mm),
                mm(tracked.kp_rms_mm),
                options.zero_worse_ratio
            ),
        },
        survival: Some(zeroed.survival),
        kp_rms_mm: zeroed.kp_rms_mm,
    }
}

fn mm(v: Option<f64>) -> String {
    v.map_or("– (no step)".into(), |e| format!("{e:.1} mm"))
}

fn duration_s(seq: &Sequence) -> f64 {
    (seq.joint_pos.len() - 1) as f64 / seq.fps
}

/// The first `seconds` of `seq` (all of it when shorter), forces dropped: the check runs
/// without force.
fn truncated(seq: &Sequence, seconds: f64) -> Sequence {
    let mut s = crate::sim::motion::force_graft::first_seconds(seq, seconds);
    let frames = s.n_frames();
    s.force_sensor = [vec![[0.0; 3]; frames], vec![[0.0; 3]; frames]];
    s.forces_recorded = false;
    s
}

/// `seconds` of standing still on the profile's default pose (its action offset), the
/// root upright at the height that puts the lowest sole point on the ground, at 50 fps.
pub fn standing_reference(robot: &RobotModel, profile: &Profile, seconds: f64) -> Sequence {
    let fps = 50.0;
    let frames = (seconds * fps).round() as usize + 1;
    let q = profile.action_offset_rad.clone();
    let mut poses = Vec::new();
    forward_kinematics(robot, &Isometry3::identity(), &q, &mut poses);
    let height = -lowest_sole_point_z(robot, &poses).unwrap_or(-0.78);
    Sequence {
        task: "stand".into(),
        sequence_id: "stand".into(),
        fps,
        joint_names: robot.joints.iter().map(|j| j.name.clone()).collect(),
        root_pos: vec![[0.0, 0.0, height]; frames],
        root_quat_wxyz: vec![[1.0, 0.0, 0.0, 0.0]; frames],
        joint_pos: vec![q; frames],
        joint_vel: None,
        force_sensor: [vec![[0.0; 3]; frames], vec![[0.0; 3]; frames]],
        hand_from_sensor_wxyz: [[1.0, 0.0, 0.0, 0.0]; 2],
        force_point_hand: [[0.0; 3]; 2],
        forces_recorded: false,
        force_frame: Default::default(),
        provenance: serde_json::json!({"format": "thorarena-sanity-stand"}),
    }
}

/// One episode of `seq` on a fresh physics: the policy's actions, or its zero action
/// when `zero`. A policy that fails or misses ends the episode there.
fn run_episode(
    policy: &mut dyn Policy,
    zero: bool,
    setup: &EpisodeSetup,
    seq: &Sequence,
    engine: &Engine,
) -> Result<Run, SanityError> {
    let settings = PhysicsSettings {
        dt_s: setup.profile.physics_dt_s,
        ..Default::default()
    };
    let mut physics = make_physics(
        engine,
        Arc::new(setup.robot.clone()),
        settings,
        setup.profile.gains.clone(),
    )?;
    let mut episode = Episode::start(setup, seq, physics.as_mut());
    let mut meter = policy.follows_commands().map(|_| {
        FollowingMeter::new(
            setup.robot,
            setup.keypoints,
            seq,
            setup.profile.control_dt_s,
        )
    });
    policy.reset(0);
    let mut actions = vec![vec![0.0; setup.robot.n_joints()]];
    let mut applied = vec![0.0; setup.robot.n_joints()];
    let mut non_finite: Option<(usize, usize)> = None;
    let mut step = 0;
    while !episode.is_done() {
        let obs: Observation = episode.observation();
        if let Some(meter) = meter.as_mut() {
            meter.step(obs.time_s, &obs.root, &obs.q);
        }
        if policy.act(std::slice::from_ref(&obs), &mut actions) != ActOutcome::Acted {
            break;
        }
        if zero {
            policy.zero_action(&obs, &mut actions[0]);
        }
        if actions[0].iter().all(|a| a.is_finite()) {
            applied.copy_from_slice(&actions[0]);
        } else {
            let (n, _) = non_finite.get_or_insert((0, step));
            *n += 1;
        }
        episode.advance(physics.as_mut(), &applied);
        step += 1;
    }
    let (series, termination) = episode.finish();
    policy.episode_ended(0, termination.is_some());
    Ok(Run {
        survival: series.survival(),
        kp_rms_mm: series.kp_rms_m().map(|e| 1e3 * e),
        non_finite,
        following: meter.map(|m| m.finish()),
    })
}

/// Index of the sequence whose root travels farthest horizontally in its first `seconds`
/// — a walk, for a general tracker's tracking check; `None` for no sequences.
pub fn walking_sequence(sequences: &[Sequence], seconds: f64) -> Option<usize> {
    let travel = |s: &Sequence| {
        let frames = ((seconds * s.fps).round() as usize + 1).min(s.root_pos.len());
        s.root_pos[..frames]
            .windows(2)
            .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
            .sum::<f64>()
    };
    (0..sequences.len()).max_by(|&a, &b| travel(&sequences[a]).total_cmp(&travel(&sequences[b])))
}
