//! A force setting of an evaluation: replayed recorded forces under a coefficient, a
//! constant push, or a disturbance (force events, random impulses, payloads); every
//! sequence runs once per setting.

use crate::sim::disturbance::Disturbance;
use serde::{Deserialize, Serialize};

/// A force setting: a name, the replay coefficient, and an optional constant push or
/// disturbance.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Setting {
    /// `force`, `no-force`, `coef-<x>`, `push-<N>` or `push-<N>@<deg>`.
    pub name: String,
    /// Replay coefficient.
    pub coefficient: f64,
    /// A constant world-frame +x push on each hand, N, ramped in over
    /// [`crate::sim::replay::PUSH_RAMP_S`] (a sensitivity probe, as in SOURCES.md, TWIST2 in MuJoCo; recorded
    /// forces are not replayed with it).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub push_n: f64,
    /// The push's direction, degrees counter-clockwise from the reference's initial
    /// heading (`push:<N>@<deg>`; 90: from the robot's right); `None`: world +x.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub push_heading_deg: Option<f64>,
    /// Force events, random impulses or payloads instead of the recorded forces
    /// (`event:…`, `impulse:…`, `payload:…`; coefficient 0, no push).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub disturbance: Option<Disturbance>,
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

/// `v` when a setting's name can carry it ([`crate::sim::disturbance::fits_name`]).
fn short(v: f64) -> Option<f64> {
    crate::sim::disturbance::fits_name(v).then_some(v)
}

/// Why a text is no setting, naming it (cut to 80 characters, so a number of three
/// hundred digits is not echoed whole).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SettingError {
    /// A disturbance (`event:`, `impulse:`, `payload:`) spelled wrong.
    #[error("`{shown}`: {why} ({})", Disturbance::SYNTAX)]
    Disturbance {
        /// The text, as shown.
        shown: String,
        /// What is wrong with it.
        why: String,
    },
    /// No setting at all, or a number out of range or with too many digits.
    #[error("`{shown}` is not force, no-force, a replay coefficient within ±{}, push:<N>[@<deg>] with |N| ≤ {} and |deg| ≤ 360 (at most {} characters a number), or a disturbance ({})", Setting::MAX_COEFFICIENT, Setting::MAX_PUSH_N, crate::sim::disturbance::MAX_NUMBER_CHARS, Disturbance::SYNTAX)]
    Unknown {
        /// The text, as shown.
        shown: String,
    },
}

impl SettingError {
    /// Why `s` is no setting.
    fn of(s: &str) -> Self {
        let cut: String = s.chars().take(80).collect();
        let shown = format!(
            "{}{}",
            cut.escape_default(),
            if cut.len() < s.len() { "…" } else { "" }
        );
        match Disturbance::parse(s) {
            Some(Err(why)) => Self::Disturbance {
                shown,
                why: why.chars().take(120).collect(),
            },
            _ => Self::Unknown { shown },
        }
    }
}

impl Setting {
    /// True when both settings load the robot the same way, however spelled (`force` and
    /// `1`; `no-force` and `push:0`; a zero push in any direction).
    pub fn same_load(&self, other: &Self) -> bool {
        let heading = |s: &Self| {
            if s.push_n == 0.0 {
                None
            } else {
                Some(s.push_heading_deg.unwrap_or(0.0).rem_euclid(360.0))
            }
        };
        self.coefficient == other.coefficient
            && self.push_n == other.push_n
            && heading(self) == heading(other)
            && self.disturbance == other.disturbance
    }

    /// The replay coefficient of a setting that only replays recorded forces (`force`,
    /// `no-force`, a coefficient): `None` for a push or a disturbance.
    pub fn replay_only(&self) -> Option<f64> {
        (self.push_n == 0.0 && self.disturbance.is_none()).then_some(self.coefficient)
    }

    /// The push per hand of a setting that only pushes (`push:<N>`, `no-force` as a push
    /// of 0): `None` for a replay or a disturbance.
    pub fn push_only(&self) -> Option<f64> {
        (self.coefficient == 0.0 && self.disturbance.is_none()).then_some(self.push_n)
    }

    /// Largest |replay coefficient| accepted: ten times the recorded forces is already
    /// far beyond any interaction; larger values only make the physics diverge.
    pub const MAX_COEFFICIENT: f64 = 10.0;
    /// Largest |push| per hand accepted, N (the G1 weighs 33 kg; a probe beyond this
    /// measures nothing but divergence).
    pub const MAX_PUSH_N: f64 = 1000.0;

    /// Parses `force`, `no-force`, a replay coefficient (|c| ≤ [`Self::MAX_COEFFICIENT`]),
    /// `push:<N>` (|N| ≤ [`Self::MAX_PUSH_N`]) with an optional `@<deg>` direction from
    /// the reference's initial heading (−360 ≤ deg ≤ 360), or a disturbance
    /// ([`Disturbance::SYNTAX`]; named by its canonical spelling); a refusal says why once.
    pub fn parse(s: &str) -> Result<Self, SettingError> {
        Self::parse_known(s).ok_or_else(|| SettingError::of(s))
    }

    /// [`Self::parse`] without the reason.
    fn parse_known(s: &str) -> Option<Self> {
        let plain = |name: String, coefficient: f64| Self {
            name,
            coefficient,
            push_n: 0.0,
            push_heading_deg: None,
            disturbance: None,
        };
        if let Some(d) = Disturbance::parse(s) {
            let d = d.ok()?;
            return Some(Self {
                disturbance: Some(d.clone()),
                ..plain(d.name(), 0.0)
            });
        }
        match s {
            "force" => Some(plain("force".into(), 1.0)),
            "no-force" => Some(plain("no-force".into(), 0.0)),
            other => {
                if let Some(spec) = other.strip_prefix("push:") {
                    let (n, deg) = match spec.split_once('@') {
                        Some((n, deg)) => (n, Some(deg)),
                        None => (spec, None),
                    };
                    let n: f64 = n
                        .parse()
                        .ok()
                        .filter(|n: &f64| n.is_finite() && n.abs() <= Self::MAX_PUSH_N)
                        .and_then(short)?;
                    let deg: Option<f64> = match deg {
                        Some(d) => Some(
                            d.parse()
                                .ok()
                                .filter(|d: &f64| d.is_finite() && d.abs() <= 360.0)
                                .and_then(short)?,
                        ),
                        None => None,
                    };
                    return Some(Self {
                        name: match deg {
                            Some(d) => format!("push-{n}@{d}"),
                            None => format!("push-{n}"),
                        },
                        coefficient: 0.0,
                        push_n: n,
                        push_heading_deg: deg,
                        disturbance: None,
                    });
                }
                other
                    .parse::<f64>()
                    .ok()
                    .filter(|c| c.is_finite() && c.abs() <= Self::MAX_COEFFICIENT)
                    .and_then(short)
                    .map(|c| plain(format!("coef-{c}"), c))
            }
        }
    }
}

impl Setting {
    /// `no-force`: the reference tracked with no force on the robot.
    pub fn no_force() -> Self {
        Self {
            name: "no-force".into(),
            coefficient: 0.0,
            push_n: 0.0,
            push_heading_deg: None,
            disturbance: None,
        }
    }

    /// `force`: the recorded hand forces replayed as recorded.
    pub fn force() -> Self {
        Self {
            name: "force".into(),
            coefficient: 1.0,
            ..Self::no_force()
        }
    }

    /// The text [`Self::parse`] reads back as this setting: `force`, `no-force`, the
    /// coefficient, `push:<N>[@<deg>]`, or the disturbance's canonical spelling. A request
    /// file, a sweep plan and `eval --settings` spell a setting so.
    pub fn spelling(&self) -> String {
        if self.disturbance.is_some() || self.name == "force" || self.name == "no-force" {
            return self.name.clone();
        }
        if self.push_n != 0.0 || self.name.starts_with("push-") {
            return match self.push_heading_deg {
                Some(d) => format!("push:{}@{d}", self.push_n),
                None => format!("push:{}", self.push_n),
            };
        }
        format!("{}", self.coefficient)
    }
}

impl std::str::FromStr for Setting {
    type Err = SettingError;
    fn from_str(s: &str) -> Result<Self, SettingError> {
        Self::parse(s)
    }
}

/// Serde for settings held where a person writes them — a request file, a sweep plan —
/// as their [`Setting::spelling`], each parsed once on reading with its reason on refusal
/// (`#[serde(with = "crate::eval::setting::spelled")]` on a `Vec<Setting>`). `run.json`
/// keeps the full record ([`Setting`]'s own serde).
pub mod spelled {
    use super::Setting;
    use serde::{de::Error as _, Deserialize, Deserializer, Serializer};

    /// Writes each setting as its spelling.
    pub fn serialize<S: Serializer>(settings: &[Setting], s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(settings.iter().map(Setting::spelling))
    }

    /// Reads each spelling as a setting, refusing the first that is none.
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<Setting>, D::Error> {
        Vec::<String>::deserialize(d)?
            .iter()
            .map(|s| Setting::parse(s).map_err(D::Error::custom))
            .collect()
    }

    /// The same for one setting (a sweep cell's).
    pub mod one {
        use super::super::Setting;
        use serde::{de::Error as _, Deserialize, Deserializer, Serializer};

        /// Writes the setting as its spelling.
        pub fn serialize<S: Serializer>(setting: &Setting, s: S) -> Result<S::Ok, S::Error> {
            s.serialize_str(&setting.spelling())
        }

        /// Reads a spelling as a setting.
        pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Setting, D::Error> {
            Setting::parse(&String::deserialize(d)?).map_err(D::Error::custom)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Setting;

    #[test]
    fn every_kind_of_setting_reads_back_from_its_spelling() {
        for s in [
            "force",
            "no-force",
            "0.5",
            "-2",
            "0",
            "1",
            "push:20",
            "push:0",
            "push:-7.5@90",
            "push:30@-45",
            "event:20@0:hand=both",
            "impulse:10-30:on=hands:dur=0.2:every=1-2:seed=3",
            "payload:2",
        ] {
            let setting = Setting::parse(s).unwrap_or_else(|e| panic!("{s}: {e}"));
            let again = Setting::parse(&setting.spelling())
                .unwrap_or_else(|e| panic!("{s} spelled {}: {e}", setting.spelling()));
            assert_eq!(again, setting, "{s} spelled {}", setting.spelling());
        }
        assert_eq!(Setting::no_force(), Setting::parse("no-force").unwrap());
        assert_eq!(Setting::force(), Setting::parse("force").unwrap());
        let defaults: Vec<Setting> = crate::eval::DEFAULT_SETTINGS
            .iter()
            .map(|s| Setting::parse(s).unwrap())
            .collect();
        assert_eq!(defaults, [Setting::force(), Setting::no_force()]);
    }
}
