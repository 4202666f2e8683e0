//! What a published network was trained with, against the profile it is about to run
//! under: the sanity check's wiring step reports every contradiction (`Policy::wiring`),
//! so a network under another family's gains or mapping is refused before it scores.

use crate::sim::profile::Profile;

/// What a network was trained with: its family's name in messages, its control period,
/// one action scale for every joint, and its default pose (canonical order).
pub struct TrainedWith<'a> {
    /// The family, as messages name it (`FALCON`, `SoftMimic`).
    pub family: &'a str,
    /// Control period, s.
    pub control_dt_s: f64,
    /// Action scale of every joint.
    pub action_scale: f64,
    /// Default pose, rad, canonical order.
    pub default_pose: &'a [f64],
}

impl TrainedWith<'_> {
    /// One sentence per quantity `profile` contradicts (the first joint that differs).
    pub fn contradictions(&self, profile: &Profile) -> Vec<String> {
        let family = self.family;
        let mut out = Vec::new();
        if (profile.control_dt_s - self.control_dt_s).abs() > 1e-9 {
            out.push(format!(
                "{family} runs every {} s; the profile `{}` controls every {} s",
                self.control_dt_s, profile.name, profile.control_dt_s
            ));
        }
        let differs = |a: &[f64], b: &dyn Fn(usize) -> f64| {
            (0..a.len()).find(|&j| (a[j] - b(j)).abs() > 1e-9)
        };
        if let Some(j) = differs(&profile.action_scale, &|_| self.action_scale) {
            out.push(format!(
                "{family}'s action scale is {}; the profile `{}` scales joint {j} by {}",
                self.action_scale, profile.name, profile.action_scale[j]
            ));
        }
        if let Some(j) = differs(&profile.action_offset_rad, &|j| self.default_pose[j]) {
            out.push(format!(
                "{family}'s default pose has joint {j} at {} rad; the profile `{}` offsets it to {}",
                self.default_pose[j], profile.name, profile.action_offset_rad[j]
            ));
        }
        out
    }
}
