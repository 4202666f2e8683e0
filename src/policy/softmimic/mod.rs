//! SoftMimic (Lee et al., "SoftMimic: Learning Compliant Whole-body Control from
//! Examples", arXiv:2510.17792; github.com/Improbable-AI/softmimic, MIT), its released G1
//! networks in process: `--policy softmimic:FILE.onnx[@stiffness=N]` under the `softmimic`
//! profile.
//!
//! Every released network observes a **stiffness command** — how hard the robot should
//! hold its reference against a push, N/m, and N·m/rad for rotation — the compliant
//! members (`*-SoftMimic`) trained to yield as that stiffness asks, their baselines
//! (`*-Baseline`) trained on the same clips to track stiffly whatever it says. The command
//! is a policy parameter: `@stiffness=K` (N/m) sets it, the rotational one following as
//! K / 60 N·m/rad (the deploy's MuJoCo joystick, `mujoco_joystick.py`
//! `get_rotational_stiffness`), unless `@rotational_stiffness=R` names it. Without one the
//! deploy's default holds: 60 N/m and 1 N·m/rad (`deploy/sensors/desired_stiffness_log_sensor.py:20`).
//!
//! The action is `default + 0.5 · a` in Isaac Lab's joint order (`SS:1553-1563`); the
//! adapter reorders it to the canonical order and the profile maps it.

pub mod observation;

use super::batch_plans::BatchPlans;
use super::{ActOutcome, Observation, Policy, Wiring};
use crate::sim::profile::Profile;
use crate::sim::robot::{forward_kinematics, lowest_sole_point_z_of, RobotModel};
use nalgebra::Isometry3;
use observation::{History, Layout, Stiffness, ISAAC_FROM_CANONICAL, N_JOINTS};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use tract_onnx::prelude::*;

/// Default stiffness command (the deploy's), N/m and N·m/rad.
pub const DEFAULT_STIFFNESS: Stiffness = Stiffness {
    linear: 60.0,
    rotational: 1.0,
};
/// Linear stiffness range of the training data, N/m: each force event drew it log-uniform
/// in it (`compliant_motion_augmentation/constants.py` `MIN/MAX_ROBOT_STIFFNESS`).
pub const STIFFNESS_RANGE: (f64, f64) = (10.0, 1000.0);
/// Rotational stiffness range of the training data, N·m/rad (same file).
pub const ROTATIONAL_RANGE: (f64, f64) = (0.1, 10.0);
/// The rotational stiffness a linear one implies when none is named (÷ 60).
pub const ROTATIONAL_PER_LINEAR: f64 = 1.0 / 60.0;
/// Action scale, every joint (`SS:1553-1563`).
pub const ACTION_SCALE: f64 = 0.5;
/// Default joint angles, canonical order (`SS:147-155`, `deploy/robots/g1_config.py:104-120`).
pub const DEFAULT_POSE: [f64; N_JOINTS] = [
    -0.2, 0.0, 0.0, 0.42, -0.23, 0.0, -0.2, 0.0, 0.0, 0.42, -0.23, 0.0, 0.0, 0.0, 0.0, 0.35, 0.16,
    0.0, 0.87, 0.0, 0.0, 0.0, 0.35, -0.16, 0.0, 0.87, 0.0, 0.0, 0.0,
];
/// A reference foot is in contact when its sole's lowest point is within this height of
/// the other foot's, m (the lower foot always is). The clips carry contact labels the
/// dataset does not keep (`sim/motion/import/lafan_csv.rs`); the standing, pouring and
/// box-picking clips label every frame 1, which this gives (their right sole sits up to
/// 5.3 mm above the left throughout), and on `walk.csv` it agrees with 2350 of the 2400
/// labels that are clear (≥ 0.99 or ≤ 0.01; the rest are soft). A height above the
/// ground could not: that clip's soles sit 1–3 cm below it, and its labels say 0 for a
/// swing foot 1.5 cm above the stance foot.
pub const CONTACT_ABOVE_LOWER_FOOT_M: f64 = 0.010;

/// Why the policy could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum SoftMimicError {
    /// tract could not load or prepare the network at either width.
    #[error("loading the SoftMimic network {path}: {message} (SoftMimic's networks take [1, 285] or [1, 1159] and give [1, 29])")]
    Load {
        /// The ONNX file.
        path: PathBuf,
        /// tract's message.
        message: String,
    },
    /// The robot is not the 29-joint G1.
    #[error("SoftMimic needs the 29-joint G1 (got {0} joints)")]
    Joints(usize),
    /// A stiffness outside what the network was trained on, or a parameter it does not take.
    #[error("softmimic policy parameter: {0}")]
    Parameter(String),
}

/// The stiffness command from the parameters of
/// `softmimic:FILE.onnx@stiffness=K[,rotational_stiffness=R]` (each already held to its
/// declared range by the registry; `None`: not given). The rotational stiffness follows
/// the linear one (÷ 60) unless given, and must then still lie in the trained range.
pub fn stiffness_from(
    linear: Option<f64>,
    rotational: Option<f64>,
) -> Result<Stiffness, SoftMimicError> {
    let bad = |m: String| SoftMimicError::Parameter(m);
    let named_rotational = rotational.is_some();
    let linear = linear.unwrap_or(DEFAULT_STIFFNESS.linear);
    let rotational = rotational.unwrap_or(linear * ROTATIONAL_PER_LINEAR);
    let within = |v: f64, (lo, hi): (f64, f64)| (lo..=hi).contains(&v);
    if !within(linear, STIFFNESS_RANGE) {
        return Err(bad(format!(
            "stiffness {linear} N/m is outside the {}–{} N/m the networks were trained on",
            STIFFNESS_RANGE.0, STIFFNESS_RANGE.1
        )));
    }
    if !within(rotational, ROTATIONAL_RANGE) {
        return Err(bad(format!(
            "rotational stiffness {rotational} N·m/rad is outside the {}–{} N·m/rad the networks were trained on{}",
            ROTATIONAL_RANGE.0,
            ROTATIONAL_RANGE.1,
            if named_rotational {
                ""
            } else {
                " (it follows stiffness / 60 unless rotational_stiffness= names it)"
            }
        )));
    }
    Ok(Stiffness { linear, rotational })
}

/// One environment's state between steps.
#[derive(Debug, Clone, Default)]
struct Slot {
    history: History,
    /// The network's last output, Isaac Lab order (the `actions` term).
    last_raw: Vec<f64>,
}

/// A SoftMimic network in process.
pub struct SoftMimicPolicy {
    plans: BatchPlans,
    plan: Arc<TypedRunnableModel>,
    /// The file loaded, by content (`run.json`'s network).
    network: crate::policy::network_file::NetworkFile,
    layout: Layout,
    stiffness: Stiffness,
    robot: Arc<RobotModel>,
    disagreements: Vec<String>,
    slots: Vec<Slot>,
    input: Vec<f32>,
    last_inputs: Vec<Vec<f32>>,
    poses: Vec<Isometry3<f64>>,
}

impl SoftMimicPolicy {
    /// Loads the network (input `[1, 285]` or `[1, 1159]`, output `[1, 29]`) to run on
    /// `robot` under `profile` with the stiffness command `stiffness`.
    pub fn load(
        path: &Path,
        robot: Arc<RobotModel>,
        profile: &Profile,
        stiffness: Stiffness,
    ) -> Result<Self, SoftMimicError> {
        if robot.n_joints() != N_JOINTS {
            return Err(SoftMimicError::Joints(robot.n_joints()));
        }
        let load = |layout: Layout| -> TractResult<(BatchPlans, Arc<TypedRunnableModel>, _)> {
            let (model, network) = super::network_kernels::load_onnx(path)?;
            let plans = BatchPlans::new(model, layout.width(), Some(N_JOINTS))?;
            let plan = plans.plan(1)?;
            Ok((plans, plan, network))
        };
        let (layout, (plans, plan, network)) = match load(Layout::Stand) {
            Ok(p) => (Layout::Stand, p),
            Err(first) => match load(Layout::Track) {
                Ok(p) => (Layout::Track, p),
                Err(second) => {
                    return Err(SoftMimicError::Load {
                        path: path.to_path_buf(),
                        message: format!(
                            "neither a standing network ({first:#}) nor a tracking one ({second:#})"
                        ),
                    })
                }
            },
        };
        Ok(Self {
            plans,
            plan,
            network,
            layout,
            stiffness,
            robot,
            disagreements: disagreements(profile),
            slots: Vec::new(),
            input: vec![0.0; layout.width()],
            last_inputs: Vec::new(),
            poses: Vec::new(),
        })
    }

    /// Its input layout.
    pub fn layout(&self) -> Layout {
        self.layout
    }

    /// The stiffness command it observes.
    pub fn stiffness(&self) -> Stiffness {
        self.stiffness
    }

    /// The network's inputs of the last `act`, one per observation (for tests).
    pub fn last_inputs(&self) -> &[Vec<f32>] {
        &self.last_inputs
    }

    /// Runs the network on one observation; actions in Isaac Lab order.
    pub fn infer(&self, input: &[f32]) -> TractResult<Vec<f32>> {
        self.plans.run_on(&self.plan, input, 1)
    }

    /// Left and right foot contact of a reference frame, from its soles' height.
    fn contacts(&mut self, frame: &crate::sim::motion::ReferenceFrame) -> [f64; 2] {
        forward_kinematics(
            &self.robot,
            &frame.world_from_root,
            &frame.joint_pos,
            &mut self.poses,
        );
        let robot = &self.robot;
        let soles = ["left_", "right_"].map(|side| {
            lowest_sole_point_z_of(robot, &self.poses, |b| {
                robot.bodies[b].name.starts_with(side)
            })
            .unwrap_or(0.0)
        });
        let lower = soles[0].min(soles[1]);
        soles.map(|z| f64::from(u8::from(z - lower < CONTACT_ABOVE_LOWER_FOOT_M)))
    }
}

/// Where `profile` contradicts SoftMimic's training: rate, action scale, default pose.
fn disagreements(profile: &Profile) -> Vec<String> {
    super::trained_with::TrainedWith {
        family: "SoftMimic",
        control_dt_s: 0.02,
        action_scale: ACTION_SCALE,
        default_pose: &DEFAULT_POSE,
    }
    .contradictions(profile)
}

impl Policy for SoftMimicPolicy {
    /// The family's name, as every in-process network's; the stiffness it ran with is in
    /// [`Policy::parameters`] (`run.json`'s `policy_parameters`), and tables label runs by
    /// their policy argument, which names it.
    fn name(&self) -> &str {
        "softmimic"
    }

    fn network(&self) -> Option<&crate::policy::network_file::NetworkFile> {
        Some(&self.network)
    }

    fn network_kernels(&self) -> Option<&'static super::network_kernels::NetworkKernels> {
        Some(super::network_kernels::network_kernels())
    }

    fn reference_offsets_s(&self) -> Vec<f64> {
        self.layout.reference_offsets_s()
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        vec![
            ("stiffness_n_per_m", self.stiffness.linear),
            ("rotational_stiffness_nm_per_rad", self.stiffness.rotational),
        ]
    }

    fn sanity_exempt(&self) -> Option<&'static str> {
        None
    }

    fn reset(&mut self, env: usize) {
        if let Some(slot) = self.slots.get_mut(env) {
            *slot = Slot::default();
        }
    }

    fn wiring(&self) -> Wiring {
        let layout = match self.layout {
            Layout::Stand => "285 inputs: proprioception and the stiffness command, 3 frames per term (no reference observed)",
            Layout::Track => "1159 inputs: proprioception, the reference and the stiffness command, 3 frames per term, and 20 reference frames up to 1.9 s ahead",
        };
        Wiring {
            facts: vec![
                layout.into(),
                format!(
                    "stiffness command {} N/m, rotational {:.4} N·m/rad",
                    self.stiffness.linear, self.stiffness.rotational
                ),
                format!("{N_JOINTS} actions in Isaac Lab order, relative to the default pose, scale {ACTION_SCALE}"),
            ],
            disagreements: self.disagreements.clone(),
        }
    }

    fn worker_copies(&self, n: usize) -> Option<Vec<Box<dyn Policy + Send>>> {
        Some(
            (0..n)
                .map(|_| {
                    Box::new(Self {
                        plans: self.plans.clone(),
                        plan: self.plan.clone(),
                        network: self.network.clone(),
                        layout: self.layout,
                        stiffness: self.stiffness,
                        robot: self.robot.clone(),
                        disagreements: self.disagreements.clone(),
                        slots: Vec::new(),
                        input: vec![0.0; self.layout.width()],
                        last_inputs: Vec::new(),
                        poses: Vec::new(),
                    }) as Box<dyn Policy + Send>
                })
                .collect(),
        )
    }

    fn act(&mut self, observations: &[Observation], actions: &mut [Vec<f64>]) -> ActOutcome {
        // Kept for tests, in buffers reused from call to call (no allocation per step).
        self.last_inputs.resize_with(observations.len(), Vec::new);
        for (row, (obs, action)) in observations.iter().zip(actions.iter_mut()).enumerate() {
            if self.slots.len() <= obs.env {
                self.slots.resize_with(obs.env + 1, Slot::default);
            }
            let starts = obs.step == 0;
            if starts || self.slots[obs.env].last_raw.len() != N_JOINTS {
                self.slots[obs.env] = Slot {
                    last_raw: vec![0.0; N_JOINTS],
                    ..Slot::default()
                };
            }
            let (contacts_now, future) = match self.layout {
                Layout::Stand => ([1.0; 2], Vec::new()),
                Layout::Track => {
                    let now = self.contacts(&obs.reference[0]);
                    let future: Vec<Vec<f64>> = obs.reference[1..]
                        .iter()
                        .map(|f| {
                            let c = self.contacts(f);
                            let mut t = Vec::new();
                            observation::reference_terms(f, c, &mut t);
                            t
                        })
                        .collect();
                    (now, future)
                }
            };
            let slot = &mut self.slots[obs.env];
            let frame = observation::frame(
                self.layout,
                obs,
                &DEFAULT_POSE,
                &slot.last_raw,
                contacts_now,
                self.stiffness,
            );
            slot.history
                .push_into(self.layout, frame, starts, &future, &mut self.input);
            self.last_inputs[row].clone_from(&self.input);
            match self.plans.run_row(&self.plan, &self.input, "softmimic") {
                Some(out) => {
                    let slot = &mut self.slots[obs.env];
                    for (i, (last, o)) in slot.last_raw.iter_mut().zip(&out).enumerate() {
                        *last = f64::from(*o);
                        action[ISAAC_FROM_CANONICAL[i]] = *last;
                    }
                }
                None => action.fill(f64::NAN),
            }
        }
        ActOutcome::Acted
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stiffness_parameters_parse_and_refuse_what_training_never_saw() {
        assert_eq!(stiffness_from(None, None).unwrap(), DEFAULT_STIFFNESS);
        let s = stiffness_from(Some(300.0), None).unwrap();
        assert_eq!((s.linear, s.rotational), (300.0, 5.0));
        let s = stiffness_from(Some(300.0), Some(0.5)).unwrap();
        assert_eq!(s.rotational, 0.5);
        for (linear, rotational) in [(5.0, None), (900.0, Some(20.0)), (60.0, Some(0.01))] {
            assert!(
                stiffness_from(Some(linear), rotational).is_err(),
                "{linear}"
            );
        }
        // 900 N/m implies 15 N·m/rad, above the rotational range: the message says why.
        let e = stiffness_from(Some(900.0), None).unwrap_err().to_string();
        assert!(e.contains("stiffness / 60"), "{e}");
    }

    #[test]
    fn the_layouts_have_the_networks_widths() {
        assert_eq!(Layout::Stand.width(), 285);
        assert_eq!(Layout::Track.width(), 1159);
        assert_eq!(Layout::of_width(1159), Some(Layout::Track));
        assert_eq!(Layout::Track.reference_offsets_s().len(), 21);
    }
}
