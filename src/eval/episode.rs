//! One episode as a state machine the runner can batch: start (reset to the first reference
//! frame), observe, advance one control step (action delay, force replay and PD at the
//! physics rate, metrics, termination), finish.

use crate::eval::metrics::{keypoint_error_m, reanchor, EpisodeSeries};
use crate::eval::{reference_steps, EpisodeRecord, PolicyFault, PolicyFaults, Setting};
use crate::eval::{Termination, TerminationRule};
use crate::policy::Observation;
use crate::sim::disturbance::{ActiveDisturbance, Disturbance};
use crate::sim::feet::{FeetMeter, FootContact};
use crate::sim::motion::{heading_rad, Reference, ReferenceFrame, Sequence};
use crate::sim::physics::{Physics, PhysicsState, ResetState, RootState};
use crate::sim::profile::Profile;
use crate::sim::replay::ForceReplay;
use crate::sim::robot::{
    forward_kinematics, frame_pose, lowest_sole_point_z, KeypointSet, RobotModel,
};
use nalgebra::{Isometry3, Point3, Vector3};
use serde::{Deserialize, Serialize};
use std::collections::VecDeque;

/// One control step of a rollout trace (`thorarena eval --trace`), for plots and replays.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TraceStep {
    /// Time since the episode started (end of the step), s.
    pub time_s: f64,
    /// Robot root position, m.
    pub root_pos: [f64; 3],
    /// Robot root orientation (w, x, y, z).
    pub root_quat_wxyz: [f64; 4],
    /// Joint angles, rad.
    pub q: Vec<f64>,
    /// PD targets applied during the step, rad.
    pub targets: Vec<f64>,
    /// Replayed hand forces (left, right) during the last physics step, world frame, N.
    pub hand_force_w: [[f64; 3]; 2],
    /// Robot keypoints, world frame, m.
    pub keypoints_w: Vec<[f64; 3]>,
    /// Reference keypoints re-anchored to the robot's root, world frame, m.
    pub reference_keypoints_w: Vec<[f64; 3]>,
    /// Keypoint error, m.
    pub kp_err_m: f64,
    /// Reference root position at this step (not re-anchored), m; lets a viewer pose the
    /// reference's bodies (absent in traces written before it existed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference_root_pos: Option<[f64; 3]>,
    /// Reference root orientation (w, x, y, z) at this step (not re-anchored).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference_root_quat_wxyz: Option<[f64; 4]>,
    /// Reference joint angles at this step, rad.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference_q: Option<Vec<f64>>,
    /// The feet on the ground over this step: forces, centre of pressure, slip.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub feet: Option<Vec<FootContact>>,
}

/// What an episode recorded while tracing was on: the trace proper, and the feet's
/// slip over the whole episode (kept even where the trace stops, for `crosscheck`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct EpisodeTrace {
    /// Steps of the trace (all, or the first seconds: see [`Episode::record_trace_for`]).
    pub steps: Vec<TraceStep>,
    /// Per control step of the whole episode, each foot's slip accumulated since the
    /// start (feet in robot-model order), m.
    pub foot_slip_m: Vec<Vec<f64>>,
}

/// What commands an episode's physics step by step ([`Episode::advance_driven`]): called
/// before each physics step with the physics, the state after the previous step and the
/// PD targets to record, rad.
pub type PhysicsDriver<'d> = dyn FnMut(&mut dyn Physics, &PhysicsState, &mut Vec<f64>) + 'd;

/// Everything fixed across the episodes of a run.
pub struct EpisodeSetup<'a> {
    /// The robot.
    pub robot: &'a RobotModel,
    /// The dynamics profile.
    pub profile: &'a Profile,
    /// Keypoints of the tracking error.
    pub keypoints: &'a KeypointSet,
    /// Termination rule.
    pub termination: TerminationRule,
    /// Force replay coefficient (1 = force setting, 0 = no force).
    pub force_coefficient: f64,
    /// Constant push on each hand, N (see `ForceReplay::push_w`): along world +x, or …
    pub push_n: f64,
    /// … at this angle, degrees counter-clockwise about z, from the reference's initial
    /// heading (90: towards the robot's left, i.e. a push from its right).
    pub push_heading_deg: Option<f64>,
    /// Events, impulses or payloads put on the robot (`None`: none).
    pub disturbance: Option<Disturbance>,
    /// Reference offsets the policy asked for, s.
    pub reference_offsets_s: Vec<f64>,
}

impl<'a> EpisodeSetup<'a> {
    /// The setup of `setting`'s episodes (its force replay or push) for the run's robot,
    /// profile, keypoints and termination rule, with reference frames at `reference_offsets_s`.
    pub fn for_setting(
        robot: &'a RobotModel,
        profile: &'a Profile,
        keypoints: &'a KeypointSet,
        termination: TerminationRule,
        setting: &Setting,
        reference_offsets_s: Vec<f64>,
    ) -> Self {
        Self {
            robot,
            profile,
            keypoints,
            termination,
            force_coefficient: setting.coefficient,
            push_n: setting.push_n,
            push_heading_deg: setting.push_heading_deg,
            disturbance: setting.disturbance.clone(),
            reference_offsets_s,
        }
    }
}

/// A running episode.
pub struct Episode<'a> {
    setup: &'a EpisodeSetup<'a>,
    reference: Reference,
    replay: ForceReplay,
    torso_frame: usize,
    step: usize,
    steps_ref: usize,
    pending: VecDeque<Vec<f64>>,
    last_action: Vec<f64>,
    targets: Vec<f64>,
    state: PhysicsState,
    series: EpisodeSeries,
    termination: Option<Termination>,
    /// Wall time spent inside `Physics::step` (for `thorarena bench eval`; never in results).
    physics_wall: std::time::Duration,
    /// Rollout trace, when asked for.
    trace: Option<Vec<TraceStep>>,
    /// Steps ending later than this (s since the start) are left out of the trace.
    trace_until_s: f64,
    /// The feet's contacts, metered while a trace is recorded.
    feet: FeetMeter,
    /// Body poses at the start of the physics step (for the feet's slip).
    poses_before_step: Vec<Isometry3<f64>>,
    /// The feet's accumulated slip per control step, whole episode, while a trace is
    /// recorded (also past `trace_until_s`), m.
    foot_slip_m: Option<Vec<Vec<f64>>>,
    /// Hand forces of the last physics step, world frame.
    last_hand_force_w: [Vector3<f64>; 2],
    /// Body poses of the reference at the current step (set by `record`).
    reference_poses: Vec<Isometry3<f64>>,
    /// Deadline misses and invalid actions so far.
    faults: PolicyFaults,
    /// Scratch buffer for the next step's targets (kept to avoid an allocation per step).
    next_targets: Vec<f64>,
}

impl<'a> Episode<'a> {
    /// Resets `physics` to the first reference frame (with its velocities, lifted if the
    /// feet would start below the ground) and sets the profile's gains.
    pub fn start(setup: &'a EpisodeSetup<'a>, seq: &Sequence, physics: &mut dyn Physics) -> Self {
        let robot = setup.robot;
        let reference = Reference::new(seq);
        let first = reference.sample(0.0);
        let mut world_from_root = first.world_from_root;
        let mut poses = Vec::new();
        forward_kinematics(robot, &world_from_root, &first.joint_pos, &mut poses);
        if let Some(low) = lowest_sole_point_z(robot, &poses) {
            world_from_root.translation.vector.z += (-low).max(0.0);
        }
        physics.set_gains(&setup.profile.gains);
        physics.set_payloads(&match &setup.disturbance {
            Some(Disturbance::Payload(p)) => p.point_masses(robot),
            _ => Vec::new(),
        });
        physics.reset(&ResetState {
            root: RootState {
                world_from_root,
                lin_vel_w: first.root_lin_vel_w,
                ang_vel_w: first.root_ang_vel_w,
            },
            q: first.joint_pos.clone(),
            qd: first.joint_vel.clone(),
        });
        let n = robot.n_joints();
        let steps_ref = reference_steps(reference.duration_s(), setup.profile.control_dt_s);
        let mut state = PhysicsState::default();
        physics.read_state(&mut state);
        Self {
            setup,
            replay: replay_of(setup, seq, &reference),
            torso_frame: robot.frame_index("torso_link").unwrap_or(0),
            reference,
            step: 0,
            steps_ref,
            pending: (0..setup.profile.action_delay_steps)
                .map(|_| vec![0.0; n])
                .collect(),
            last_action: vec![0.0; n],
            targets: first.joint_pos,
            state,
            series: EpisodeSeries {
                steps_ref,
                ..Default::default()
            },
            termination: None,
            reference_poses: poses,
            physics_wall: std::time::Duration::ZERO,
            trace: None,
            trace_until_s: f64::INFINITY,
            feet: FeetMeter::new(robot),
            poses_before_step: Vec::new(),
            foot_slip_m: None,
            last_hand_force_w: [Vector3::zeros(); 2],
            faults: PolicyFaults::default(),
            next_targets: Vec::new(),
        }
    }

    /// True once the reference is over or the episode terminated.
    pub fn is_done(&self) -> bool {
        self.termination.is_some() || self.step >= self.steps_ref
    }

    /// The observation for the current control step (environment slot 0, episode 0: the
    /// runner sets both with [`Episode::observation_in`]).
    pub fn observation(&self) -> Observation {
        self.observation_in(0, 0)
    }

    /// The observation for the current control step, as environment slot `env` running
    /// episode `episode_id` of the run.
    pub fn observation_in(&self, env: usize, episode_id: u64) -> Observation {
        let t = self.step as f64 * self.setup.profile.control_dt_s;
        Observation {
            env,
            episode_id,
            step: self.step,
            time_s: t,
            root: self.state.root.clone().expect("root state"),
            q: self.state.q.clone(),
            qd: self.state.qd.clone(),
            last_action: self.last_action.clone(),
            reference: self
                .setup
                .reference_offsets_s
                .iter()
                .map(|o| self.reference.sample(t + o))
                .collect(),
        }
    }

    /// Applies one raw action (after the profile's delay) for one control step.
    pub fn advance(&mut self, physics: &mut dyn Physics, action: &[f64]) {
        self.advance_delayed(physics, action, 0);
    }

    /// Like [`Episode::advance`], but the new targets take effect only after
    /// `effect_delay_substeps` physics steps (the previous targets act until then); a delay
    /// of a whole control step or more applies them from the next step's start. This is how
    /// a measured policy latency costs tracking as it would on a robot.
    pub fn advance_delayed(
        &mut self,
        physics: &mut dyn Physics,
        action: &[f64],
        effect_delay_substeps: usize,
    ) {
        let profile = self.setup.profile;
        let bad = action.iter().any(|a| !a.is_finite());
        // A non-finite action never reaches the physics: the previous targets are held.
        self.pending.push_back(if bad {
            self.last_action.clone()
        } else {
            action.to_vec()
        });
        let applied = self
            .pending
            .pop_front()
            .expect("queue holds delay + 1 actions");
        let mut new_targets = std::mem::take(&mut self.next_targets);
        new_targets.resize(self.targets.len(), 0.0);
        profile.targets_from_action(&applied, &mut new_targets);
        if !bad {
            self.last_action.copy_from_slice(action);
        }
        let mut power = 0.0;
        for substep in 0..profile.substeps {
            if substep == effect_delay_substeps {
                std::mem::swap(&mut self.targets, &mut new_targets);
                physics.set_targets(&self.targets);
            }
            power += self.physics_step(physics);
        }
        if effect_delay_substeps >= profile.substeps {
            // Too late for this step: the targets act from the next one's start.
            std::mem::swap(&mut self.targets, &mut new_targets);
            physics.set_targets(&self.targets);
        }
        self.next_targets = new_targets;
        self.end_control_step(power);
    }

    /// One control step whose physics `drive` commands: before each physics step it may
    /// set gains and targets (as a robot applies its latest motor command), seeing the
    /// state after the previous step. Forces, metrics and termination are as in
    /// [`Episode::advance`]; `targets` records the PD targets in force at the step's end.
    pub fn advance_driven(&mut self, physics: &mut dyn Physics, drive: &mut PhysicsDriver) {
        let mut power = 0.0;
        for _ in 0..self.setup.profile.substeps {
            drive(physics, &self.state, &mut self.targets);
            power += self.physics_step(physics);
        }
        self.end_control_step(power);
    }

    /// One physics step with the replayed forces; returns the mechanical power of the PD
    /// torques over it, W.
    fn physics_step(&mut self, physics: &mut dyn Physics) -> f64 {
        self.last_hand_force_w =
            self.replay
                .apply(physics, &self.reference, &self.state.world_from_body);
        let metering = self.foot_slip_m.is_some();
        if metering {
            self.poses_before_step
                .clone_from(&self.state.world_from_body);
        }
        let started = std::time::Instant::now();
        physics.step();
        self.physics_wall += started.elapsed();
        physics.read_state(&mut self.state);
        if metering {
            self.feet.after_step(
                physics,
                &self.poses_before_step,
                &self.state.world_from_body,
                physics.settings().dt_s,
            );
        }
        self.state
            .applied_torque_nm
            .iter()
            .zip(&self.state.qd)
            .map(|(t, v)| (t * v).abs())
            .sum::<f64>()
    }

    /// After a control step's physics: divergence, the step's metrics, termination.
    fn end_control_step(&mut self, power: f64) {
        let profile = self.setup.profile;
        if !(power.is_finite() && state_is_finite(&self.state)) {
            self.termination = Some(Termination::PhysicsDiverged);
            return;
        }
        self.step += 1;
        let t = self.step as f64 * profile.control_dt_s;
        let frame = self.reference.sample(t);
        self.record(&frame, power / profile.substeps as f64);
        self.check_termination();
    }

    fn record(&mut self, frame: &ReferenceFrame, power_w: f64) {
        let robot = self.setup.robot;
        let set = self.setup.keypoints;
        let root = self.state.root.as_ref().expect("root state");
        forward_kinematics(
            robot,
            &frame.world_from_root,
            &frame.joint_pos,
            &mut self.reference_poses,
        );
        let reference_w: Vec<Point3<f64>> = set
            .frames
            .iter()
            .map(|&f| frame_pose(robot, &self.reference_poses, f) * Point3::origin())
            .collect();
        let mut anchored = Vec::with_capacity(reference_w.len());
        reanchor(
            &reference_w,
            &frame.world_from_root,
            &root.world_from_root,
            &mut anchored,
        );
        let robot_w: Vec<Point3<f64>> = set
            .frames
            .iter()
            .map(|&f| frame_pose(robot, &self.state.world_from_body, f) * Point3::origin())
            .collect();
        let u = set.n_upper;
        self.series
            .kp_err_m
            .push(keypoint_error_m(&anchored, &robot_w));
        self.series
            .kp_err_upper_m
            .push(keypoint_error_m(&anchored[..u], &robot_w[..u]));
        self.series
            .kp_err_lower_m
            .push(keypoint_error_m(&anchored[u..], &robot_w[u..]));
        self.series
            .kp_err_global_m
            .push(keypoint_error_m(&reference_w, &robot_w));
        self.series
            .total_force_n
            .push(frame.force_sensor[0].norm() + frame.force_sensor[1].norm());
        self.series.power_w.push(power_w);
        let d = root.world_from_root.translation.vector - frame.world_from_root.translation.vector;
        self.series.root_drift_m.push(d.xy().norm());
        let time_s = self.step as f64 * self.setup.profile.control_dt_s;
        let feet = self.foot_slip_m.as_mut().map(|slip| {
            let feet = self.feet.finish_step(self.setup.profile.control_dt_s);
            slip.push(feet.iter().map(|f| f.slip_m).collect());
            feet
        });
        if let Some(trace) = self.trace.as_mut().filter(|_| time_s <= self.trace_until_s) {
            let p = root.world_from_root.translation.vector;
            let r = root.world_from_root.rotation;
            let xyz = |v: &Point3<f64>| [v.x, v.y, v.z];
            trace.push(TraceStep {
                time_s,
                root_pos: [p.x, p.y, p.z],
                root_quat_wxyz: [r.w, r.i, r.j, r.k],
                q: self.state.q.clone(),
                targets: self.targets.clone(),
                hand_force_w: self.last_hand_force_w.map(|f| [f.x, f.y, f.z]),
                keypoints_w: robot_w.iter().map(xyz).collect(),
                reference_keypoints_w: anchored.iter().map(xyz).collect(),
                kp_err_m: *self.series.kp_err_m.last().expect("pushed above"),
                reference_root_pos: Some(frame.world_from_root.translation.vector.into()),
                reference_root_quat_wxyz: Some({
                    let r = frame.world_from_root.rotation;
                    [r.w, r.i, r.j, r.k]
                }),
                reference_q: Some(frame.joint_pos.clone()),
                feet,
            });
        }
    }

    /// Wall time spent in physics steps so far (benchmarks only: not deterministic).
    pub fn physics_wall(&self) -> std::time::Duration {
        self.physics_wall
    }

    /// Records a rollout trace from now on (see [`TraceStep`]).
    pub fn record_trace(&mut self) {
        self.trace.get_or_insert_with(Vec::new);
        self.foot_slip_m.get_or_insert_with(Vec::new);
        self.trace_until_s = f64::INFINITY;
    }

    /// Records the trace of the steps ending within `seconds` of the episode's start only
    /// (a cross-engine comparison of the first second needs no more).
    /// The feet's slip is metered over the whole episode all the same
    /// ([`EpisodeTrace::foot_slip_m`]).
    pub fn record_trace_for(&mut self, seconds: f64) {
        self.trace.get_or_insert_with(Vec::new);
        self.foot_slip_m.get_or_insert_with(Vec::new);
        self.trace_until_s = seconds + 1e-9;
    }

    /// The trace recorded so far, if tracing was on.
    pub fn take_trace(&mut self) -> Option<EpisodeTrace> {
        let steps = self.trace.take()?;
        Some(EpisodeTrace {
            steps,
            foot_slip_m: self.foot_slip_m.take().unwrap_or_default(),
        })
    }

    /// Compares the robot's torso with the reference's (poses from `record`).
    fn check_termination(&mut self) {
        if self.termination.is_some() {
            return;
        }
        let rule = self.setup.termination;
        let torso = frame_pose(
            self.setup.robot,
            &self.state.world_from_body,
            self.torso_frame,
        );
        let torso_ref = frame_pose(self.setup.robot, &self.reference_poses, self.torso_frame);
        let down = -Vector3::z();
        let tilt = (torso.rotation.inverse() * down).angle(&(torso_ref.rotation.inverse() * down));
        if (torso.translation.z - torso_ref.translation.z).abs() > rule.max_torso_height_error_m {
            self.termination = Some(Termination::TorsoHeight);
        } else if tilt > rule.max_torso_tilt_error_rad {
            self.termination = Some(Termination::TorsoTilt);
        }
    }

    /// Ends the episode now (the policy's fault, judged by the runner).
    pub fn terminate(&mut self, why: Termination) {
        self.termination.get_or_insert(why);
    }

    /// Counts a deadline miss or an invalid action against this episode.
    pub fn count_fault(&mut self, fault: PolicyFault) {
        match fault {
            PolicyFault::DeadlineMiss => self.faults.deadline_misses += 1,
            PolicyFault::InvalidAction => self.faults.invalid_actions += 1,
        }
    }

    /// Deadline misses and invalid actions so far.
    pub fn faults(&self) -> PolicyFaults {
        self.faults
    }

    /// The recorded series and why the episode ended early, if it did.
    pub fn finish(self) -> (EpisodeSeries, Option<Termination>) {
        (self.series, self.termination)
    }

    /// The record of this episode of `seq` under `setting`, for `policy` (take the trace
    /// first, if one was recorded).
    pub fn into_record(self, seq: &Sequence, setting: &Setting, policy: &str) -> EpisodeRecord {
        let faults = self.faults();
        let (series, termination) = self.finish();
        EpisodeRecord {
            task: seq.task.clone(),
            sequence_id: seq.sequence_id.clone(),
            setting: setting.name.clone(),
            coefficient: setting.coefficient,
            policy: policy.to_string(),
            termination,
            faults,
            series,
        }
    }
}

/// The forces `setup` puts on an episode of `seq`: the replay, the push, the disturbance.
fn replay_of(setup: &EpisodeSetup, seq: &Sequence, reference: &Reference) -> ForceReplay {
    let heading_rad = heading_rad(&reference.sample(0.0).world_from_root.rotation);
    let push_direction = match setup.push_heading_deg {
        None => Vector3::x(),
        Some(deg) => {
            let yaw = heading_rad + deg.to_radians();
            Vector3::new(yaw.cos(), yaw.sin(), 0.0)
        }
    };
    let replay = ForceReplay::new(setup.robot, seq, setup.force_coefficient)
        .with_push(push_direction * setup.push_n);
    match &setup.disturbance {
        Some(d) => replay.with_disturbance(ActiveDisturbance::new(
            d,
            setup.robot,
            heading_rad,
            &seq.sequence_id,
            reference.duration_s(),
        )),
        None => replay,
    }
}

/// Every number of the state is finite (a diverged simulation is not).
fn state_is_finite(state: &crate::sim::physics::PhysicsState) -> bool {
    let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
    let root_ok = state.root.as_ref().is_none_or(|r| {
        r.world_from_root
            .translation
            .vector
            .iter()
            .all(|x| x.is_finite())
            && r.world_from_root
                .rotation
                .coords
                .iter()
                .all(|x| x.is_finite())
            && r.lin_vel_w.iter().all(|x| x.is_finite())
            && r.ang_vel_w.iter().all(|x| x.is_finite())
    });
    root_ok
        && finite(&state.q)
        && finite(&state.qd)
        && finite(&state.applied_torque_nm)
        && state.world_from_body.iter().all(|p| {
            p.translation.vector.iter().all(|x| x.is_finite())
                && p.rotation.coords.iter().all(|x| x.is_finite())
        })
}
