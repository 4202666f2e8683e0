//! The rules every policy of a comparison is held to: when an episode has failed, and
//! what the runner does with a policy's late or unusable answers. They are part of a
//! run's identity (`run.json`), so runs under other rules are never merged or compared
//! as one.

pub use crate::files::names::short_number;
use serde::{Deserialize, Serialize};
use std::time::Duration;

/// When an episode counts as failed (the same rule for every policy; README, "What the scores mean").
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TerminationRule {
    /// Torso height off its reference by more than this, m.
    pub max_torso_height_error_m: f64,
    /// Torso tilt (angle between robot and reference projected gravity) above this, rad.
    pub max_torso_tilt_error_rad: f64,
}

impl TerminationRule {
    /// Why a run under this rule holds no benchmark scores, if it does not: FATS and
    /// survival are defined with the benchmark's termination, and a looser one lets a
    /// robot that fell (lying on its back) count as surviving and score.
    pub fn not_the_benchmarks(&self) -> Option<String> {
        let benchmark = Self::default();
        if *self == benchmark {
            return None;
        }
        let looser = self.max_torso_height_error_m > benchmark.max_torso_height_error_m
            || self.max_torso_tilt_error_rad > benchmark.max_torso_tilt_error_rad;
        Some(format!(
            "termination is not the benchmark's (torso height error > {} m or tilt error > {} rad){}: these are not benchmark scores",
            benchmark.max_torso_height_error_m,
            benchmark.max_torso_tilt_error_rad,
            if looser {
                ", and looser: a robot that fell can count as surviving and score"
            } else {
                ""
            }
        ))
    }
}

impl Default for TerminationRule {
    fn default() -> Self {
        Self {
            max_torso_height_error_m: 0.25,
            max_torso_tilt_error_rad: 0.8,
        }
    }
}

/// The rules of the policy's answers: the same for every policy of a comparison, so they
/// are part of the run's identity (`run.json`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PolicyIoRules {
    /// Deadline-miss (and invalid-action) rule.
    pub miss_rule: MissRule,
    /// When actions take effect in simulated time.
    pub latency_mode: LatencyMode,
    /// Largest usable |raw action| (units of the profile's action); beyond it, or
    /// non-finite, an action is invalid and the miss rule applies.
    pub max_abs_action: f64,
    /// Latency budget per step, s (`None`: lock-step). Enforced by remote policies.
    pub budget_s: Option<f64>,
}

impl Default for PolicyIoRules {
    fn default() -> Self {
        Self {
            miss_rule: MissRule::Hold,
            latency_mode: LatencyMode::Ignore,
            max_abs_action: 100.0,
            budget_s: None,
        }
    }
}

/// What happens to an environment whose action missed the deadline or was unusable
/// (non-finite, or beyond the profile's `max_abs_action`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MissRule {
    /// Keep applying the last action that reached the robot.
    #[default]
    Hold,
    /// Apply the zero action (the profile's default pose for offset-style profiles).
    Zero,
    /// End the episode (`deadline_miss` or `invalid_action`).
    Fail,
}

/// When a policy's action takes effect in simulated time.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LatencyMode {
    /// At the start of the control step, whatever the policy took (lock-step; results are
    /// deterministic).
    #[default]
    Ignore,
    /// Deployment-faithful: the measured policy latency delays the action's effect,
    /// rounded to physics steps and capped at one control period; the previous targets
    /// act until then. Results then depend on the machine.
    Measured,
}

/// A latency budget per step; `None` is pure lock-step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Budget(pub Option<Duration>);

/// The shortest budget a run takes: below a microsecond no round trip through shared
/// memory can answer, and a budget printed as "0ns" would say nothing.
pub const MIN_BUDGET: Duration = Duration::from_micros(1);

/// The longest budget a run takes: a per-step deadline beyond a minute is no deadline.
pub const MAX_BUDGET: Duration = Duration::from_secs(60);

/// A budget of `secs` s checked against [`MIN_BUDGET`] and [`MAX_BUDGET`]: the one check
/// of a budget, whether it came as `--budget`, a request file's `io.budget_s` or a sweep's
/// latency rule.
pub fn check_budget_s(secs: f64) -> Result<Duration, String> {
    if !secs.is_finite() || secs < MIN_BUDGET.as_secs_f64() || secs > MAX_BUDGET.as_secs_f64() {
        return Err(format!(
            "a budget is 1 us to 60 s (or none), not {}",
            short_number(secs)
        ));
    }
    Ok(Duration::from_secs_f64(secs))
}

/// Parses `--budget` (`none`, `2ms`, `500us`, `0.004s`); shared with the sweep, whose
/// latency curves put budgets on an axis.
pub fn parse_budget(s: &str) -> Result<Budget, String> {
    if s == "none" {
        return Ok(Budget(None));
    }
    let (num, unit) = s
        .find(|c: char| c.is_ascii_alphabetic())
        .map(|i| s.split_at(i))
        .ok_or_else(|| format!("`{s}`: give a unit (us, ms, s) or `none`"))?;
    let v: f64 = num
        .parse()
        .map_err(|_| format!("`{s}`: `{num}` is not a number"))?;
    let secs = match unit {
        "us" | "µs" => v * 1e-6,
        "ms" => v * 1e-3,
        "s" => v,
        _ => return Err(format!("`{s}`: unknown unit `{unit}` (us, ms, s)")),
    };
    check_budget_s(secs)
        .map(|d| Budget(Some(d)))
        .map_err(|why| format!("`{}`: {why}", s.chars().take(24).collect::<String>()))
}

#[cfg(test)]
mod tests {
    use super::TerminationRule;

    #[test]
    fn only_the_benchmarks_termination_gives_benchmark_scores() {
        assert_eq!(TerminationRule::default().not_the_benchmarks(), None);
        let opened = TerminationRule {
            max_torso_height_error_m: 100.0,
            max_torso_tilt_error_rad: 100.0,
        };
        let why = opened.not_the_benchmarks().unwrap();
        assert!(
            why.contains("not benchmark scores") && why.contains("surviving"),
            "{why}"
        );
        let stricter = TerminationRule {
            max_torso_height_error_m: 0.1,
            ..TerminationRule::default()
        };
        let why = stricter.not_the_benchmarks().unwrap();
        assert!(
            why.contains("not benchmark scores") && !why.contains("surviving"),
            "{why}"
        );
    }
}
