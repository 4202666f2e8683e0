//! Gain sets used by the field, computed from the robot model.

use super::state::PdGains;
use crate::sim::robot::RobotModel;

/// Gains derived from each joint's armature, as BeyondMimic/mjlab do for the G1:
/// `kp = a·ω²`, `kd = 2·ζ·a·ω`, with torque limits from the model.
///
/// With `natural_freq_hz = 10` and `damping_ratio = 2` this gives the table of SOURCES.md, Gains
/// (e.g. hip pitch 40.18 / 2.558).
pub fn armature_derived_gains(
    model: &RobotModel,
    natural_freq_hz: f64,
    damping_ratio: f64,
) -> PdGains {
    let w = 2.0 * std::f64::consts::PI * natural_freq_hz;
    PdGains {
        kp: model
            .joints
            .iter()
            .map(|j| j.armature_kgm2 * w * w)
            .collect(),
        kd: model
            .joints
            .iter()
            .map(|j| 2.0 * damping_ratio * j.armature_kgm2 * w)
            .collect(),
        effort_limit_nm: model.joints.iter().map(|j| j.effort_nm).collect(),
    }
}

/// The legged-gym gains of GMT, TWIST and TWIST2 training (SOURCES.md, Gains): legs
/// kp 100/100/100/150/40/40 and kd 2/2/2/4/2/2 (hip pitch, roll, yaw, knee, ankle pitch,
/// roll), waist 150/4, arms 40/5. Joints are matched by name suffix, so any G1 variant works;
/// a joint matching none of them keeps kp = kd = 0.
pub fn legged_gym_gains(model: &RobotModel) -> PdGains {
    const TABLE: [(&str, f64, f64); 16] = [
        ("hip_pitch_joint", 100.0, 2.0),
        ("hip_roll_joint", 100.0, 2.0),
        ("hip_yaw_joint", 100.0, 2.0),
        ("knee_joint", 150.0, 4.0),
        ("ankle_pitch_joint", 40.0, 2.0),
        ("ankle_roll_joint", 40.0, 2.0),
        ("waist_yaw_joint", 150.0, 4.0),
        ("waist_roll_joint", 150.0, 4.0),
        ("waist_pitch_joint", 150.0, 4.0),
        ("shoulder_pitch_joint", 40.0, 5.0),
        ("shoulder_roll_joint", 40.0, 5.0),
        ("shoulder_yaw_joint", 40.0, 5.0),
        ("elbow_joint", 40.0, 5.0),
        ("wrist_roll_joint", 40.0, 5.0),
        ("wrist_pitch_joint", 40.0, 5.0),
        ("wrist_yaw_joint", 40.0, 5.0),
    ];
    let gain = |name: &str| {
        TABLE
            .iter()
            .find(|(s, _, _)| name.ends_with(s))
            .map(|&(_, kp, kd)| (kp, kd))
    };
    let (kp, kd) = model
        .joints
        .iter()
        .map(|j| gain(&j.name).unwrap_or((0.0, 0.0)))
        .unzip();
    PdGains {
        kp,
        kd,
        effort_limit_nm: model.joints.iter().map(|j| j.effort_nm).collect(),
    }
}

/// Stiff gains that hold the G1 standing in its default pose without a policy: the
/// legged-gym gains with legs and waist four times as stiff and twice as damped. Used by the
/// physics benchmark and the standing test; no policy was trained with them.
pub fn standing_gains(model: &RobotModel) -> PdGains {
    let mut g = legged_gym_gains(model);
    for (j, joint) in model.joints.iter().enumerate() {
        if ["hip", "knee", "ankle", "waist"]
            .iter()
            .any(|k| joint.name.contains(k))
        {
            g.kp[j] *= 4.0;
            g.kd[j] *= 2.0;
        }
    }
    g
}
