//! Whether a dataset's motions could be performed by the robot under the forces recorded
//! with them (`thorarena data check`).
//!
//! **Dynamic consistency.** Each frame's inverse dynamics (`sim::robot::inverse_dynamics`,
//! contacts off) of the smoothed reference ([`derivatives`]) is the wrench the world must
//! apply to move the robot so; minus the replayed hand forces it is what the ground must
//! supply. On a flat ground that wrench has a centre of pressure; a motion a G1 can perform
//! keeps it inside the support polygon of the sole points on the ground ([`support`]),
//! never needs the ground to pull (normal force ≤ 0) and never more tangential force than
//! friction gives. Counted over *stance frames* (at least one sole point on the ground),
//! with the hand forces and without them: the share of frames whose CoP is more than
//! [`CheckOptions::outside_tolerance_m`] outside (a pulling ground counts as outside), and
//! the 95th percentile of the distance outside (0 inside).
//!
//! **Kinematic checks** as published curation uses them, so the numbers compare: PHUMA's
//! (DAVIAN-Robotics/PHUMA, arXiv 2510.26236) foot-contact share, pelvis distance to the base
//! of support (the hull of all sole points, on the ground or not, averaged over frames) and
//! root jerk (mean norm of the root position's third derivative); PBHC's (TeleHuman/PBHC,
//! arXiv 2506.12851) CoM–CoP distance, here with the CoP of the inverse dynamics; foot
//! skating (horizontal speed of sole points on the ground), ground penetration and the
//! joint-limit margin.
//!
//! **Force levels** per task: the mean hand force while loaded (more than
//! [`LOADED_N`] on that hand) and the peaks, so the levels can be compared with the ranges
//! the data claims (SOURCES.md).
//!
//! **Style** per sequence ([`style`]): speed, turning, stance width and stagger, squat
//! depth, handedness, how a hold's force builds and trembles — shown per task as
//! distributions over its sequences, a data card's numbers.

pub mod derivatives;
pub mod frames;
pub mod held;
mod report;
pub mod style;
pub mod support;
pub mod zero_phase;

pub use report::{CheckGateError, CheckWriteError, CHECK_JSON, CHECK_MARKDOWN};

use crate::eval::metrics::percentile;
use crate::sim::motion::{joint_limit_margin, Dataset, Sequence};
use crate::sim::robot::RobotModel;
use frames::frame_states;
use nalgebra::{Point2, Vector3};
use serde::{Deserialize, Serialize};
use support::{convex_hull, distance_outside, SolePoints, CONTACT_HEIGHT_M};

/// A hand carries a load when its force is above this, N.
pub const LOADED_N: f64 = 2.0;

/// How a dataset is checked.
#[derive(Debug, Clone, Serialize)]
pub struct CheckOptions {
    /// Cutoff of the zero-phase low-pass before differentiating, Hz.
    pub cutoff_hz: f64,
    /// A CoP further outside the support than this counts as outside, m.
    pub outside_tolerance_m: f64,
    /// Friction coefficient of the ground (the simulator's), for the friction share.
    pub friction: f64,
    /// Gravity, world frame, m/s².
    pub gravity_w: [f64; 3],
    /// A sole point touches when its bottom is this close to the ground, m.
    pub contact_height_m: f64,
}

impl Default for CheckOptions {
    fn default() -> Self {
        let physics = crate::sim::physics::PhysicsSettings::default();
        Self {
            cutoff_hz: zero_phase::DEFAULT_CUTOFF_HZ,
            outside_tolerance_m: 0.01,
            friction: physics.friction,
            gravity_w: physics.gravity,
            contact_height_m: CONTACT_HEIGHT_M,
        }
    }
}

/// One force setting's balance, frame by frame (stance frames only).
#[derive(Debug, Clone, Default)]
struct BalanceSeries {
    stance_frames: usize,
    /// Frames whose ground would have to pull.
    pulling_frames: usize,
    /// Per pushing stance frame: CoP distance outside the support, m.
    cop_outside_m: Vec<f64>,
    /// Per pushing stance frame: tangential over normal ground force.
    friction_ratio: Vec<f64>,
    /// Per pushing stance frame: horizontal CoM–CoP distance, m.
    com_cop_m: Vec<f64>,
}

/// One force setting's balance over a sequence or a task.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Balance {
    /// Frames with a sole point on the ground.
    pub stance_frames: usize,
    /// Share of stance frames with the CoP outside by more than the tolerance, or with a
    /// pulling ground.
    pub outside_share: f64,
    /// 95th percentile of the CoP's distance outside the support, pushing stance frames, mm.
    pub outside_p95_mm: f64,
    /// Share of stance frames whose ground would have to pull.
    pub pulling_share: f64,
    /// 95th percentile of tangential over normal ground force.
    pub friction_ratio_p95: f64,
    /// Share of pushing stance frames needing more friction than the ground has.
    pub friction_over_share: f64,
    /// 95th percentile of the horizontal CoM–CoP distance, mm.
    pub com_cop_p95_mm: f64,
}

fn sorted(mut v: Vec<f64>) -> Vec<f64> {
    v.sort_by(f64::total_cmp);
    v
}

fn share(count: usize, of: usize) -> f64 {
    if of == 0 {
        0.0
    } else {
        count as f64 / of as f64
    }
}

impl Balance {
    fn pooled(series: &[&BalanceSeries], opts: &CheckOptions) -> Self {
        let stance: usize = series.iter().map(|s| s.stance_frames).sum();
        let pulling: usize = series.iter().map(|s| s.pulling_frames).sum();
        let gather = |f: fn(&BalanceSeries) -> &Vec<f64>| {
            sorted(series.iter().flat_map(|s| f(s).iter().copied()).collect())
        };
        let outside = gather(|s| &s.cop_outside_m);
        let friction = gather(|s| &s.friction_ratio);
        let com_cop = gather(|s| &s.com_cop_m);
        let beyond = outside
            .iter()
            .filter(|d| **d > opts.outside_tolerance_m)
            .count();
        Self {
            stance_frames: stance,
            outside_share: share(beyond + pulling, stance),
            outside_p95_mm: 1e3 * percentile(&outside, 95.0),
            pulling_share: share(pulling, stance),
            friction_ratio_p95: percentile(&friction, 95.0),
            friction_over_share: share(
                friction.iter().filter(|r| **r > opts.friction).count(),
                friction.len(),
            ),
            com_cop_p95_mm: 1e3 * percentile(&com_cop, 95.0),
        }
    }
}

/// The kinematic checks, frame by frame.
#[derive(Debug, Clone, Default)]
struct KinematicSeries {
    frames: usize,
    contact_frames: usize,
    pelvis_outside_m: Vec<f64>,
    root_jerk_m_s3: Vec<f64>,
    skate_m_s: Vec<f64>,
    lowest_sole_z_m: f64,
    limit_margin_rad: f64,
}

/// The kinematic checks over a sequence or a task.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Kinematics {
    /// Share of frames with a sole point on the ground (PHUMA's foot-contact score).
    pub contact_share: f64,
    /// Mean distance of the pelvis outside the hull of all sole points, mm (PHUMA's
    /// pelvis-to-base-of-support distance).
    pub pelvis_outside_mean_mm: f64,
    /// Mean norm of the root position's third derivative, m/s³ (PHUMA's root jerk).
    pub root_jerk_mean_m_s3: f64,
    /// 95th percentile of the horizontal speed of sole points on the ground, m/s.
    pub skate_p95_m_s: f64,
    /// Deepest sole point below the ground, mm (0 when none is below).
    pub penetration_max_mm: f64,
    /// Smallest distance of a joint to its limits, rad (negative: beyond).
    pub limit_margin_rad: f64,
}

impl Kinematics {
    fn pooled(series: &[&KinematicSeries]) -> Self {
        let frames: usize = series.iter().map(|s| s.frames).sum();
        let mean = |v: Vec<f64>| {
            if v.is_empty() {
                0.0
            } else {
                v.iter().sum::<f64>() / v.len() as f64
            }
        };
        let all = |f: fn(&KinematicSeries) -> &Vec<f64>| -> Vec<f64> {
            series.iter().flat_map(|s| f(s).iter().copied()).collect()
        };
        Self {
            contact_share: share(series.iter().map(|s| s.contact_frames).sum(), frames),
            pelvis_outside_mean_mm: 1e3 * mean(all(|s| &s.pelvis_outside_m)),
            root_jerk_mean_m_s3: mean(all(|s| &s.root_jerk_m_s3)),
            skate_p95_m_s: percentile(&sorted(all(|s| &s.skate_m_s)), 95.0),
            penetration_max_mm: 1e3
                * series
                    .iter()
                    .map(|s| -s.lowest_sole_z_m)
                    .fold(0.0, f64::max),
            limit_margin_rad: series
                .iter()
                .map(|s| s.limit_margin_rad)
                .fold(f64::INFINITY, f64::min),
        }
    }
}

/// The hand forces, per hand-frame, and both hands together per frame.
#[derive(Debug, Clone, Default)]
struct ForceSeries {
    hand_frames: usize,
    loaded_n: Vec<f64>,
    peak_n: f64,
    both_loaded_n: Vec<f64>,
    both_peak_n: f64,
    span: HandForceSpan,
}

/// Where the recorded hand forces point in the world, per hand, through the reference's
/// hand poses: what a policy trained with a force curriculum is judged against
/// (`policy::registry::TrainedForces`). Walking: the root's horizontal speed above
/// 0.1 m/s, the style's threshold.
#[derive(Debug, Clone, Copy, Default, Serialize, Deserialize, PartialEq)]
pub struct HandForceSpan {
    /// Largest horizontal force on a hand while the root walks, N.
    pub horizontal_walking_max_n: f64,
    /// Largest horizontal force on a hand while the root stands, N.
    pub horizontal_standing_max_n: f64,
    /// Lowest and highest vertical force on a hand, N (z up).
    pub vertical_n: (f64, f64),
}

impl HandForceSpan {
    /// Widened to hold force `f_w` (N, world) with the root walking or not.
    fn add(&mut self, f_w: &Vector3<f64>, walking: bool) {
        let h = f_w.xy().norm();
        if walking {
            self.horizontal_walking_max_n = self.horizontal_walking_max_n.max(h);
        } else {
            self.horizontal_standing_max_n = self.horizontal_standing_max_n.max(h);
        }
        self.vertical_n = (self.vertical_n.0.min(f_w.z), self.vertical_n.1.max(f_w.z));
    }

    /// The span of both.
    fn union(self, other: Self) -> Self {
        Self {
            horizontal_walking_max_n: self
                .horizontal_walking_max_n
                .max(other.horizontal_walking_max_n),
            horizontal_standing_max_n: self
                .horizontal_standing_max_n
                .max(other.horizontal_standing_max_n),
            vertical_n: (
                self.vertical_n.0.min(other.vertical_n.0),
                self.vertical_n.1.max(other.vertical_n.1),
            ),
        }
    }

    /// Scaled by a setting's force coefficient (≥ 0).
    pub fn scaled(self, coefficient: f64) -> Self {
        Self {
            horizontal_walking_max_n: self.horizontal_walking_max_n * coefficient,
            horizontal_standing_max_n: self.horizontal_standing_max_n * coefficient,
            vertical_n: (
                self.vertical_n.0 * coefficient,
                self.vertical_n.1 * coefficient,
            ),
        }
    }
}

/// How strong the recorded hand forces are over a sequence or a task.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct ForceLevels {
    /// Mean force on a hand while it is loaded (above [`LOADED_N`]), N.
    pub loaded_mean_n: f64,
    /// 95th percentile of a loaded hand's force, N.
    pub loaded_p95_n: f64,
    /// Largest force on either hand, N.
    pub peak_n: f64,
    /// Share of hand-frames that are loaded.
    pub loaded_share: f64,
    /// Both hands together (sum of the two magnitudes): mean over the frames it is above
    /// [`LOADED_N`], N — the object's level when both hands hold it.
    pub both_loaded_mean_n: f64,
    /// Both hands together: the largest sum, N.
    pub both_peak_n: f64,
    /// Where the forces point in the world, per hand.
    pub span: HandForceSpan,
}

impl ForceLevels {
    fn pooled(series: &[&ForceSeries]) -> Self {
        let loaded = sorted(
            series
                .iter()
                .flat_map(|s| s.loaded_n.iter().copied())
                .collect(),
        );
        let hand_frames: usize = series.iter().map(|s| s.hand_frames).sum();
        let mean = |v: &[f64]| {
            if v.is_empty() {
                0.0
            } else {
                v.iter().sum::<f64>() / v.len() as f64
            }
        };
        let both: Vec<f64> = series
            .iter()
            .flat_map(|s| s.both_loaded_n.iter().copied())
            .collect();
        Self {
            both_loaded_mean_n: mean(&both),
            both_peak_n: series.iter().map(|s| s.both_peak_n).fold(0.0, f64::max),
            loaded_mean_n: mean(&loaded),
            loaded_p95_n: percentile(&loaded, 95.0),
            peak_n: series.iter().map(|s| s.peak_n).fold(0.0, f64::max),
            loaded_share: share(loaded.len(), hand_frames),
            span: series
                .iter()
                .fold(HandForceSpan::default(), |a, s| a.union(s.span)),
        }
    }
}

/// Everything measured on one sequence, frame by frame.
#[derive(Debug, Clone)]
struct SequenceSeries {
    with_force: BalanceSeries,
    without_force: BalanceSeries,
    kinematics: KinematicSeries,
    forces: ForceSeries,
    style: style::SequenceStyle,
}

/// The check of one sequence, or of a task's sequences pooled frame by frame.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct CheckSummary {
    /// Task name.
    pub task: String,
    /// Sequence id, or `None` for a task's pooled row.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sequence_id: Option<String>,
    /// Sequences pooled (1 for a sequence).
    pub sequences: usize,
    /// Frames checked (the two end frames have no acceleration and are left out).
    pub frames: usize,
    /// Balance with the recorded hand forces replayed.
    pub with_force: Balance,
    /// Balance with no hand force.
    pub without_force: Balance,
    /// Kinematic checks.
    pub kinematics: Kinematics,
    /// Recorded hand force levels.
    pub forces: ForceLevels,
    /// The sequence's style (a sequence's row only; a task's is in
    /// [`DatasetCheck::styles`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub style: Option<style::SequenceStyle>,
}

impl CheckSummary {
    fn pooled(
        task: &str,
        sequence_id: Option<String>,
        series: &[&SequenceSeries],
        opts: &CheckOptions,
    ) -> Self {
        let style = match series {
            [one] if sequence_id.is_some() => Some(one.style.clone()),
            _ => None,
        };
        Self {
            task: task.to_string(),
            sequence_id,
            sequences: series.len(),
            frames: series.iter().map(|s| s.kinematics.frames).sum(),
            with_force: Balance::pooled(
                &series.iter().map(|s| &s.with_force).collect::<Vec<_>>(),
                opts,
            ),
            without_force: Balance::pooled(
                &series.iter().map(|s| &s.without_force).collect::<Vec<_>>(),
                opts,
            ),
            kinematics: Kinematics::pooled(
                &series.iter().map(|s| &s.kinematics).collect::<Vec<_>>(),
            ),
            forces: ForceLevels::pooled(&series.iter().map(|s| &s.forces).collect::<Vec<_>>()),
            style,
        }
    }

    /// The larger of the two settings' shares of stance frames outside.
    pub fn worst_outside_share(&self) -> f64 {
        self.with_force
            .outside_share
            .max(self.without_force.outside_share)
    }
}

/// The check of a dataset: per task (pooled over its sequences' frames) and per sequence.
#[derive(Debug, Clone, Serialize)]
pub struct DatasetCheck {
    /// The dataset's directory as given.
    pub dataset: String,
    /// The dataset's content hash (SHA-256 over its manifest entries).
    pub dataset_sha256: String,
    /// Robot name.
    pub robot: String,
    /// How it was checked.
    pub options: CheckOptions,
    /// Per task, in order of first appearance.
    pub tasks: Vec<CheckSummary>,
    /// Per sequence, in the dataset's order.
    pub sequences: Vec<CheckSummary>,
    /// Per task, its sequences' styles as distributions (a data card's numbers).
    pub styles: Vec<style::TaskStyle>,
    /// A named tracker's rollouts without force, when asked for (`data check --rollout`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tracker: Option<held::TrackerHeld>,
}

/// Why a dataset cannot be checked.
#[derive(Debug, thiserror::Error)]
pub enum CheckError {
    /// The robot has no sole shapes, so there is no support polygon.
    #[error("robot `{0}` has no sole collision shapes (robot.toml `sole_collision`): no support polygon to check against")]
    NoSoles(String),
    /// A sequence's joints are not the robot's canonical joints.
    #[error("{task}/{sequence}: its joints are not robot `{robot}`'s canonical joints")]
    Joints {
        /// Task.
        task: String,
        /// Sequence id.
        sequence: String,
        /// Robot name.
        robot: String,
    },
    /// A sequence is too short to differentiate twice.
    #[error("{task}/{sequence}: {frames} frames; the check needs at least 5")]
    TooShort {
        /// Task.
        task: String,
        /// Sequence id.
        sequence: String,
        /// Frames it has.
        frames: usize,
    },
    /// The dataset holds no sequence: a check over nothing would pass any gate.
    #[error("{0}: the dataset holds no sequence, so there is nothing to check")]
    Empty(String),
    /// The low-pass cutoff is no frequency.
    #[error("`option.cutoff_hz` must be a frequency above 0 Hz, got {0}")]
    Cutoff(f64),
    /// Reading the dataset failed.
    #[error(transparent)]
    Data(#[from] crate::sim::motion::DataError),
}

/// Per task, where `seqs`' recorded hand forces point (the spans [`check_dataset`]
/// reports, under the default options): what a run judges its cells against when its
/// policy's family was trained with forces (`eval::outside_training`).
pub fn task_force_spans(
    seqs: &[Sequence],
    robot: &RobotModel,
) -> Result<std::collections::BTreeMap<String, HandForceSpan>, CheckError> {
    let opts = CheckOptions::default();
    let mut spans = std::collections::BTreeMap::<String, HandForceSpan>::new();
    for seq in seqs {
        // The hand poses by forward kinematics only: the same span the check's series
        // gives (`forces.span`), without its inverse dynamics and support hulls.
        let mut span = HandForceSpan::default();
        for at in frames::hand_forces_w(seq, robot, &opts)? {
            for f_w in &at.force_w {
                span.add(f_w, at.root_speed_xy_m_s > style::MOVING_M_S);
            }
        }
        let task = spans.entry(seq.task.clone()).or_default();
        *task = task.union(span);
    }
    Ok(spans)
}

/// Checks every sequence of `ds` (loaded in `seqs`), calling `progress(done, total)` after
/// each; no sequence at all is an error ([`CheckError::Empty`]), not a pass.
pub fn check_dataset(
    ds: &Dataset,
    seqs: &[Sequence],
    robot: &RobotModel,
    opts: &CheckOptions,
    mut progress: impl FnMut(usize, usize),
) -> Result<DatasetCheck, CheckError> {
    let soles = checked_soles(robot, opts)?;
    if seqs.is_empty() {
        return Err(CheckError::Empty(ds.dir.display().to_string()));
    }
    let mut series = Vec::with_capacity(seqs.len());
    for (i, seq) in seqs.iter().enumerate() {
        series.push(sequence_series(seq, robot, &soles, opts)?);
        progress(i + 1, seqs.len());
    }
    let mut tasks: Vec<&str> = Vec::new();
    for q in seqs {
        if !tasks.contains(&q.task.as_str()) {
            tasks.push(q.task.as_str());
        }
    }
    Ok(DatasetCheck {
        dataset: ds.dir.display().to_string(),
        dataset_sha256: ds.content_hash(),
        robot: robot.name.clone(),
        options: opts.clone(),
        tasks: tasks
            .iter()
            .map(|task| {
                let of_task: Vec<&SequenceSeries> = seqs
                    .iter()
                    .zip(&series)
                    .filter(|(q, _)| q.task == *task)
                    .map(|(_, s)| s)
                    .collect();
                CheckSummary::pooled(task, None, &of_task, opts)
            })
            .collect(),
        sequences: seqs
            .iter()
            .zip(&series)
            .map(|(q, s)| CheckSummary::pooled(&q.task, Some(q.sequence_id.clone()), &[s], opts))
            .collect(),
        styles: tasks
            .iter()
            .map(|task| {
                let of_task: Vec<&style::SequenceStyle> = seqs
                    .iter()
                    .zip(&series)
                    .filter(|(q, _)| q.task == *task)
                    .map(|(_, s)| &s.style)
                    .collect();
                style::TaskStyle::of(task, &of_task)
            })
            .collect(),
        tracker: None,
    })
}

/// Checks one sequence on its own.
pub fn check_sequence(
    seq: &Sequence,
    robot: &RobotModel,
    opts: &CheckOptions,
) -> Result<CheckSummary, CheckError> {
    let soles = checked_soles(robot, opts)?;
    let s = sequence_series(seq, robot, &soles, opts)?;
    Ok(CheckSummary::pooled(
        &seq.task,
        Some(seq.sequence_id.clone()),
        &[&s],
        opts,
    ))
}

/// The robot's sole points, once the options are known to be usable.
fn checked_soles(robot: &RobotModel, opts: &CheckOptions) -> Result<SolePoints, CheckError> {
    if !(opts.cutoff_hz.is_finite() && opts.cutoff_hz > 0.0) {
        return Err(CheckError::Cutoff(opts.cutoff_hz));
    }
    let soles = SolePoints::of(robot);
    if soles.is_empty() {
        return Err(CheckError::NoSoles(robot.name.clone()));
    }
    Ok(soles)
}

fn sequence_series(
    seq: &Sequence,
    robot: &RobotModel,
    soles: &SolePoints,
    opts: &CheckOptions,
) -> Result<SequenceSeries, CheckError> {
    let frames = frame_states(seq, robot, soles, opts)?;
    let dt = 1.0 / seq.fps;
    let mut with_force = BalanceSeries::default();
    let mut without_force = BalanceSeries::default();
    let mut kin = KinematicSeries {
        lowest_sole_z_m: f64::INFINITY,
        limit_margin_rad: joint_limit_margin(seq, robot),
        ..Default::default()
    };
    let mut forces = ForceSeries::default();
    for (i, f) in frames.iter().enumerate() {
        // Kinematic checks.
        kin.frames += 1;
        kin.lowest_sole_z_m = f
            .soles
            .iter()
            .map(|s| s.bottom_w.z)
            .fold(kin.lowest_sole_z_m, f64::min);
        let all_soles: Vec<Point2<f64>> = f
            .soles
            .iter()
            .map(|s| Point2::new(s.bottom_w.x, s.bottom_w.y))
            .collect();
        kin.pelvis_outside_m.push(distance_outside(
            &convex_hull(&all_soles),
            &Point2::new(f.root_w.x, f.root_w.y),
        ));
        if (1..frames.len().saturating_sub(2)).contains(&i) {
            let p = |j: usize| frames[j].root_w;
            let jerk = (p(i + 2) - 3.0 * p(i + 1) + 3.0 * p(i) - p(i - 1)) / (dt * dt * dt);
            kin.root_jerk_m_s3.push(jerk.norm());
        }
        if let Some(before) = i.checked_sub(1).map(|j| &frames[j]) {
            for (now, then) in f
                .soles
                .iter()
                .zip(&before.soles)
                .zip(f.touching.iter().zip(&before.touching))
                .filter(|(_, (a, b))| **a && **b)
                .map(|(p, _)| p)
            {
                let d = now.bottom_w - then.bottom_w;
                kin.skate_m_s.push(d.xy().norm() / dt);
            }
        }
        let both = f.hand_force_n[0] + f.hand_force_n[1];
        forces.both_peak_n = forces.both_peak_n.max(both);
        if both > LOADED_N {
            forces.both_loaded_n.push(both);
        }
        let walking = f.root_speed_xy_m_s > style::MOVING_M_S;
        for f_w in &f.hand_force_w {
            forces.span.add(f_w, walking);
        }
        for magnitude in f.hand_force_n {
            forces.hand_frames += 1;
            forces.peak_n = forces.peak_n.max(magnitude);
            if magnitude > LOADED_N {
                forces.loaded_n.push(magnitude);
            }
        }
        if f.support.is_empty() {
            continue;
        }
        kin.contact_frames += 1;
        for (ground, series) in [
            (f.ground_with_force, &mut with_force),
            (f.ground_without_force, &mut without_force),
        ] {
            series.stance_frames += 1;
            match ground.centre_of_pressure() {
                None => series.pulling_frames += 1,
                Some(cop) => {
                    series
                        .cop_outside_m
                        .push(distance_outside(&f.support, &cop));
                    series
                        .friction_ratio
                        .push(ground.force.xy().norm() / ground.force.z);
                    series
                        .com_cop_m
                        .push((Point2::new(f.com_w.x, f.com_w.y) - cop).norm());
                }
            }
        }
    }
    kin.lowest_sole_z_m = kin.lowest_sole_z_m.min(0.0);
    Ok(SequenceSeries {
        with_force,
        without_force,
        kinematics: kin,
        forces,
        style: style::SequenceStyle::of(&frames, seq.fps),
    })
}
