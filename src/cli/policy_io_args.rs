//! `--policy` and the policy-I/O options shared by `eval`, `serve` and `bench`: a built-in
//! baseline, or `ipc:<session>` for a policy process connecting over shared memory.

use super::choices::{LatencyModeArg, MissRuleArg};
use thorarena::eval::{parse_budget, Budget, PolicyIoRules};
use thorarena::policy::{SessionOptions, SessionOptionsError};

/// Options of a policy's answers (all policies) and of the session (remote ones).
#[derive(Debug, Clone, clap::Args)]
pub struct PolicyIoArgs {
    /// Environment slots stepped in lock-step; one batch of this many observations goes to
    /// the policy each control step [default: one per worker; a network in process more
    /// per worker, its family's count (TWIST2 4, BeyondMimic family 8), which its calls
    /// share. Records do not depend on it].
    #[arg(long)]
    pub envs: Option<usize>,
    /// 2: split the slots in two halves and step one half's physics while the policy
    /// answers for the other, so neither the cores nor the policy wait (records are the
    /// same as with 1, lock-step). Not with --budget or --latency-mode measured: the
    /// policy then shares the cores with physics and its timing is not its own. Networks
    /// run in process already overlap (each worker runs its own copy).
    #[arg(long, default_value_t = 1)]
    pub pipeline_depth: usize,
    /// Latency budget per control step for a remote policy, from publishing the
    /// observations to receiving the actions: `2ms`, `500us`, `0.004s`, or `none` for pure
    /// lock-step (wait as long as the policy process lives).
    #[arg(long, default_value = "none", value_parser = parse_budget)]
    pub budget: Budget,
    /// What a missed deadline or an unusable action (non-finite, or beyond
    /// --max-abs-action) does: hold the last action, apply zero, or fail the episode.
    #[arg(long, value_enum, default_value = "hold")]
    pub miss_rule: MissRuleArg,
    /// `measured`: the policy's measured latency delays its action's effect in simulated
    /// time (rounded to physics steps), so slow inference costs tracking as on a robot.
    /// `ignore`: actions act at once (deterministic results).
    #[arg(long, value_enum, default_value = "ignore")]
    pub latency_mode: LatencyModeArg,
    /// Largest usable |raw action| (the profile's action units).
    #[arg(long, default_value_t = PolicyIoRules::default().max_abs_action)]
    pub max_abs_action: f64,
    /// Remote policy: seconds to wait for it to connect (also after a failure); 0 waits
    /// forever.
    #[arg(long, default_value_t = 0.0)]
    pub connect_timeout: f64,
    /// Remote policy: when its process dies mid-run, `end` the run (finished episodes are
    /// kept; `--resume` runs the rest) or `wait` for a policy to reconnect.
    #[arg(long, value_enum, default_value_t = OnPolicyFailure::End)]
    pub on_policy_failure: OnPolicyFailure,
    /// Remote policy: busy-poll this many µs for the actions before blocking (the low-
    /// latency path; 0 blocks at once and leaves the core to the policy).
    #[arg(long, default_value_t = 50)]
    pub spin_us: u64,
}

/// What a run does when its policy process dies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum OnPolicyFailure {
    /// End the run cleanly.
    End,
    /// Wait for a policy to reconnect, then go on.
    Wait,
}

impl PolicyIoArgs {
    /// How a policy process is served, checked, with the run's latency budget (s; its
    /// checked [`PolicyIoRules::budget_s`], which a request file may give instead of
    /// `--budget`).
    pub fn session_options(
        &self,
        budget_s: Option<f64>,
    ) -> Result<SessionOptions, SessionOptionsError> {
        SessionOptions::checked(
            budget_s,
            self.spin_us,
            self.connect_timeout,
            self.on_policy_failure == OnPolicyFailure::Wait,
        )
    }

    /// The rules recorded in `run.json` (checked with the rest of the evaluation by
    /// [`thorarena::eval::EvalSpec::load`]).
    pub fn rules(&self) -> PolicyIoRules {
        PolicyIoRules {
            miss_rule: self.miss_rule.into(),
            latency_mode: self.latency_mode.into(),
            max_abs_action: self.max_abs_action,
            budget_s: self.budget.0.map(|b| b.as_secs_f64()),
        }
    }
}
