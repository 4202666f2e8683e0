//! The command line's spellings of the library's choices: clap stays in the binary, so
//! the library's enums derive nothing from it. Each maps one to one onto the library's,
//! variant by variant of the same name.

use thorarena::eval::{EngineChoice, LatencyMode, MissRule};
use thorarena::sim::physics::PdForm;
use thorarena::sim::scenario::Scenario;

/// A value enum for `--flag` and its conversion into the library's enum of the same
/// variants (a variant missing on either side does not compile).
macro_rules! choice {
    ($(#[$doc:meta])* $arg:ident => $lib:ty { $($(#[$vdoc:meta])* $variant:ident,)+ }) => {
        $(#[$doc])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
        pub enum $arg {
            $($(#[$vdoc])* $variant,)+
        }

        impl From<$arg> for $lib {
            fn from(a: $arg) -> Self {
                match a {
                    $($arg::$variant => Self::$variant,)+
                }
            }
        }
    };
}

choice! {
    /// `--miss-rule`.
    MissRuleArg => MissRule {
        /// Keep applying the last action that reached the robot.
        Hold,
        /// Apply the zero action.
        Zero,
        /// End the episode (`deadline_miss` or `invalid_action`).
        Fail,
    }
}

choice! {
    /// `--latency-mode`.
    LatencyModeArg => LatencyMode {
        /// Actions act at the start of the control step (deterministic results).
        Ignore,
        /// The measured latency delays the action's effect in simulated time.
        Measured,
    }
}

choice! {
    /// `sim-trace --scenario`.
    ScenarioArg => Scenario {
        /// Pelvis welded 1 m above the ground, every joint sweeping a sine for 4 s.
        FixedBase,
        /// Free robot standing on flat ground, a smaller sweep for 2 s.
        Floating,
    }
}

choice! {
    /// `eval --engine`.
    EngineArg => EngineChoice {
        /// rapier3d multibody on the robot model.
        Rapier,
        /// MuJoCo on the MJCF given by --mjcf (a build with the `mujoco` feature).
        Mujoco,
    }
}

choice! {
    /// `sim trace --pd`.
    PdFormArg => PdForm {
        /// Explicit clamped kp torque, kd as implicit joint damping.
        Hybrid,
        /// Explicit clamped PD torque.
        Explicit,
    }
}

/// `--settings` and `--setting`: [`thorarena::eval::Setting::parse`], refusing a value with
/// its reason and the value cut short (clap's own message would echo it whole).
#[derive(Debug, Clone, Copy)]
pub struct SettingArg;

impl clap::builder::TypedValueParser for SettingArg {
    type Value = thorarena::eval::Setting;

    fn parse_ref(
        &self,
        cmd: &clap::Command,
        arg: Option<&clap::Arg>,
        value: &std::ffi::OsStr,
    ) -> Result<Self::Value, clap::Error> {
        let flag = arg.and_then(clap::Arg::get_long).unwrap_or("settings");
        let refused = |why: String| {
            clap::Error::raw(
                clap::error::ErrorKind::ValueValidation,
                format!("--{flag}: {why}\n"),
            )
            .with_cmd(cmd)
        };
        let text = value
            .to_str()
            .ok_or_else(|| refused("the value is not UTF-8".into()))?;
        thorarena::eval::Setting::parse(text).map_err(|why| refused(why.to_string()))
    }
}
