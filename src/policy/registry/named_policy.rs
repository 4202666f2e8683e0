//! A policy argument (`--policy`, a sweep's `policy`, a leaderboard row), parsed once into
//! its family's entry and what follows the family's name. Every question about a policy
//! argument — its file, its parameters, its labels, the profile it runs under, how many
//! slots a worker gives it, how it is built — is a method here, read from the family's
//! entry in [`super::POLICY_FAMILIES`].

use super::families::{policy_family, PolicyFamily, Target, POLICY_FAMILIES};
use super::{
    did_you_mean, known_network, parse_parameters, ParameterValues, PolicyChoice, RegistryError,
};
use crate::sim::profile::Profile;
use crate::sim::robot::RobotModel;
use std::path::Path;

/// A parsed policy argument.
#[derive(Debug, Clone, PartialEq)]
pub struct NamedPolicy {
    /// As given.
    spec: String,
    family: &'static PolicyFamily,
    /// What follows `name:` without the parameters: a file or a session ("" for a
    /// built-in).
    target: String,
    /// `KEY=VALUE,…` after the file's `@`, as given.
    parameters: Option<String>,
    /// Those parameters read against the family's declaration, in the order given.
    values: ParameterValues,
}

impl NamedPolicy {
    /// Parses `spec`; an argument that names no family, or a family without its file or
    /// session, is refused with what it probably meant.
    pub fn parse(spec: &str) -> Result<Self, RegistryError> {
        let family = policy_family(spec)
            .ok_or_else(|| RegistryError::UnknownPolicy(unknown_policy(spec)))?;
        let rest = match family.target {
            Target::Nothing => "",
            Target::File | Target::Session => &spec[family.name.len() + 1..],
        };
        let (target, parameters) = match family.target {
            Target::File => split_parameters(rest),
            _ => (rest, None),
        };
        if family.target != Target::Nothing && target.is_empty() {
            return Err(RegistryError::UnknownPolicy(unknown_policy(spec)));
        }
        // A session's name is held to the wire's rule here, before anything is served.
        if family.target == Target::Session {
            thorarena_ipc::check_session_name(target).map_err(|e| {
                RegistryError::UnknownPolicy(format!("`{}`: {e}", spec.escape_default()))
            })?;
        }
        let values = match parameters {
            Some(text) => {
                parse_parameters(family.name, family.parameters, text).map_err(|why| {
                    RegistryError::Parameters {
                        policy: spec.to_string(),
                        why,
                    }
                })?
            }
            None => ParameterValues::new(),
        };
        Ok(Self {
            spec: spec.to_string(),
            family,
            target: target.to_string(),
            parameters: parameters.map(str::to_string),
            values,
        })
    }

    /// The argument of `family` with `target` after its name (a session's name; "" for a
    /// built-in), made without a string to parse: what [`super::PolicySource::builtin`]
    /// and [`super::PolicySource::on_session`] build.
    pub(super) fn of_family(family: &'static PolicyFamily, target: &str) -> Self {
        let spec = match family.target {
            Target::Nothing => family.name.to_string(),
            _ => format!("{}:{target}", family.name),
        };
        Self {
            spec,
            family,
            target: target.to_string(),
            parameters: None,
            values: ParameterValues::new(),
        }
    }

    /// The argument as given.
    pub fn as_str(&self) -> &str {
        &self.spec
    }

    /// Its family's entry.
    pub fn family(&self) -> &'static PolicyFamily {
        self.family
    }

    /// The network file of a file family (`twist2:FILE.onnx`).
    pub fn file(&self) -> Option<&Path> {
        (self.family.target == Target::File).then(|| Path::new(&self.target))
    }

    /// The session of `ipc:SESSION`.
    pub fn session(&self) -> Option<&str> {
        (self.family.target == Target::Session).then_some(self.target.as_str())
    }

    /// The parameters after the file (`stiffness=200` of `softmimic:F.onnx@stiffness=200`).
    pub fn parameters(&self) -> Option<&str> {
        self.parameters.as_deref()
    }

    /// The value the argument gives parameter `name` (declared by its family and checked
    /// against its range), if it gives one.
    pub fn parameter(&self, name: &str) -> Option<f64> {
        self.values
            .iter()
            .find_map(|&(n, v)| (n == name).then_some(v))
    }

    /// The network file's stem (`twist2_1017_25k`).
    pub fn file_stem(&self) -> Option<String> {
        let file = self.file()?;
        Some(
            file.file_stem()
                .map_or_else(|| self.target.clone(), |s| s.to_string_lossy().into_owned()),
        )
    }

    /// The same argument with its file taken against `dir` (a sweep spec's or a policy
    /// file's directory); itself when it names no file.
    pub fn with_file_in(&self, dir: &Path) -> Self {
        match self.file() {
            Some(file) if file.is_relative() => self.with_file(&dir.join(file)),
            _ => self.clone(),
        }
    }

    fn with_file(&self, file: &Path) -> Self {
        let params = self
            .parameters
            .as_ref()
            .map_or_else(String::new, |p| format!("@{p}"));
        let spec = format!("{}:{}{params}", self.family.name, file.display());
        Self {
            spec,
            target: file.display().to_string(),
            ..self.clone()
        }
    }

    /// The same argument with `parameters` (`stiffness=40`) after its file, held to the
    /// family's declaration; refused for a family without a file, or an argument that
    /// names parameters already.
    pub fn with_parameters(&self, parameters: &str) -> Result<Self, String> {
        if self.file().is_none() {
            return Err(format!(
                "`{}` takes no parameters: only a network file's family does",
                self.spec
            ));
        }
        if self.parameters.is_some() {
            return Err(format!(
                "`{}` names its parameters already: give them in `parameters` or in the argument, not both",
                self.spec
            ));
        }
        let values = parse_parameters(self.family.name, self.family.parameters, parameters)?;
        Ok(Self {
            spec: format!("{}@{parameters}", self.spec),
            parameters: Some(parameters.to_string()),
            values,
            ..self.clone()
        })
    }

    /// `family:stem[@parameters]` for a network (`twist2:twist2_1017_25k`), the argument
    /// itself otherwise: a sweep's label.
    pub fn label(&self) -> String {
        self.stem_joined(":", "@")
    }

    /// `family (stem[, parameters])` for a network (`twist2 (twist2_1017_25k)`), the
    /// argument itself otherwise: how a table names it.
    pub fn table_label(&self) -> String {
        match (self.file_stem(), &self.parameters) {
            (Some(stem), Some(p)) => format!("{} ({stem}, {p})", self.family.name),
            (Some(stem), None) => format!("{} ({stem})", self.family.name),
            (None, _) => self.spec.clone(),
        }
    }

    /// `family-stem[-parameters]` for a network (`wbc-mjlab-wbc_g1_policy`), the argument
    /// itself otherwise: the base of a run directory's name.
    pub fn dir_label(&self) -> String {
        self.stem_joined("-", "-")
    }

    fn stem_joined(&self, after_family: &str, before_params: &str) -> String {
        match self.file_stem() {
            Some(stem) => format!(
                "{}{after_family}{stem}{}",
                self.family.name,
                self.parameters
                    .as_ref()
                    .map_or_else(String::new, |p| format!("{before_params}{p}"))
            ),
            None => self.spec.clone(),
        }
    }

    /// The profile it runs under when none is named: a published network's own (known by
    /// the file's content, which is read and hashed here: call it once per run) when this
    /// family runs that network, else its family's.
    pub fn default_profile(&self) -> &'static str {
        self.file()
            .and_then(known_network)
            .filter(|known| known.families.contains(&self.family.name))
            .map_or(self.family.profile, |known| known.profile)
    }

    /// Environment slots per worker when a run names none.
    pub fn slots_per_worker(&self) -> usize {
        self.family.slots_per_worker
    }

    /// Whether `profile` is one its family runs under; `Err` says why not.
    pub fn check_profile(&self, profile: &Profile) -> Result<(), String> {
        (self.family.profile_rule)(profile)
    }

    /// Builds it for `robot` under `profile` (its default pose and action mapping), or
    /// says which session a policy process should connect to.
    pub fn load(
        &self,
        robot: &RobotModel,
        profile: &Profile,
    ) -> Result<PolicyChoice<'_>, RegistryError> {
        match (self.family.build, self.session()) {
            (Some(build), _) => Ok(PolicyChoice::InProcess(build(self, robot, profile)?)),
            (None, Some(session)) => Ok(PolicyChoice::Session(session)),
            (None, None) => unreachable!("a family without a builder serves a session"),
        }
    }
}

impl std::fmt::Display for NamedPolicy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.spec)
    }
}

/// `FILE@KEY=VALUE,…` → (`FILE`, `Some("KEY=VALUE,…")`); a file with no `@` followed by a
/// `KEY=` → (it, `None`). A file's own `@` stays in the file: what follows the last `@`
/// is no parameter list when it ends in `.onnx` (`sm@stiffness=200.onnx` is a file's
/// name), and a trailing `@` ends the file's name with no parameters (`FILE@`), so any
/// name can be given.
fn split_parameters(file_and_parameters: &str) -> (&str, Option<&str>) {
    match file_and_parameters.rsplit_once('@') {
        Some((file, "")) => (file, None),
        Some((_, params)) if params.ends_with(".onnx") => (file_and_parameters, None),
        Some((file, params)) if params.contains('=') => (file, Some(params)),
        _ => (file_and_parameters, None),
    }
}

/// Why `spec` names no policy, with what it probably meant.
fn unknown_policy(spec: &str) -> String {
    let name = spec.split(':').next().unwrap_or_default();
    if let Some(f) = POLICY_FAMILIES.iter().find(|f| f.name == name) {
        match (f.target, f.example) {
            (Target::File, Some(example)) => {
                return format!("`{spec}` needs the network's file: `{name}:FILE.onnx` (e.g. {name}:{example})")
            }
            (Target::Session, _) => {
                return format!("`{spec}` needs a session name: `{name}:NAME`, the name the policy process connects to")
            }
            _ => {}
        }
    }
    let names: Vec<String> = POLICY_FAMILIES
        .iter()
        .map(|f| match f.target {
            Target::Nothing => f.name.to_string(),
            _ => format!("{}:", f.name),
        })
        .collect();
    // A typo is in the family's name: compare that part (`twist3:` of `twist3:a.onnx`).
    let typed = match spec.split_once(':') {
        Some((name, _)) => format!("{name}:"),
        None => spec.to_string(),
    };
    let hint = did_you_mean(&typed, names.iter().map(String::as_str));
    let spellings: Vec<&str> = POLICY_FAMILIES.iter().map(|f| f.spelling).collect();
    format!(
        "unknown policy `{spec}`{hint}: give one of {}",
        spellings.join(", ")
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parameters_are_not_part_of_the_file() {
        let arg = NamedPolicy::parse("softmimic:dir/a@b.onnx@stiffness=200").unwrap();
        assert_eq!(arg.file(), Some(Path::new("dir/a@b.onnx")));
        assert_eq!(arg.parameters(), Some("stiffness=200"));
        let twist = NamedPolicy::parse("twist2:x@y.onnx").unwrap();
        assert_eq!(twist.file(), Some(Path::new("x@y.onnx")));
        assert_eq!(twist.parameters(), None);
        // A file whose own name holds `@key=value`: named as it is, or ended by `@`.
        let sm = NamedPolicy::parse("softmimic:sm@stiffness=200.onnx").unwrap();
        assert_eq!(sm.file(), Some(Path::new("sm@stiffness=200.onnx")));
        assert_eq!(sm.parameters(), None);
        let odd = NamedPolicy::parse("softmimic:net@stiffness=200@").unwrap();
        assert_eq!(odd.file(), Some(Path::new("net@stiffness=200")));
        assert_eq!(odd.parameters(), None);
        let pour = NamedPolicy::parse("softmimic:d/Pour-SoftMimic.onnx@stiffness=200").unwrap();
        assert_eq!(pour.label(), "softmimic:Pour-SoftMimic@stiffness=200");
        assert_eq!(
            pour.table_label(),
            "softmimic (Pour-SoftMimic, stiffness=200)"
        );
        assert_eq!(pour.dir_label(), "softmimic-Pour-SoftMimic-stiffness=200");
    }

    #[test]
    fn parameters_are_held_to_the_family_declaration() {
        for (spec, says) in [
            (
                "falcon:F.onnx@stiffness=5",
                "`falcon` has no parameter `stiffness`",
            ),
            ("twist2:F.onnx@stiffness=5", "`twist2` takes no parameters"),
            ("wbc-mjlab:F.onnx@x=1", "`wbc-mjlab` takes no parameters"),
            (
                "softmimic:F.onnx@stiffness=100,stiffness=200",
                "given twice",
            ),
            (
                "softmimic:F.onnx@stifness=100",
                "(did you mean `stiffness`?)",
            ),
            ("softmimic:F.onnx@stiffness=5", "outside 10 to 1000 N/m"),
        ] {
            let e = NamedPolicy::parse(spec).unwrap_err().to_string();
            assert!(e.contains(says), "{spec}: {e}");
        }
        let ok =
            NamedPolicy::parse("softmimic:F.onnx@stiffness=200,rotational_stiffness=2").unwrap();
        assert_eq!(ok.parameter("rotational_stiffness"), Some(2.0));
        assert_eq!(ok.parameter("stiffness"), Some(200.0));
    }

    #[test]
    fn an_argument_names_its_family_and_what_it_needs() {
        assert_eq!(NamedPolicy::parse("hold").unwrap().family().name, "hold");
        assert_eq!(
            NamedPolicy::parse("ipc:demo").unwrap().session(),
            Some("demo")
        );
        for (spec, says) in [
            ("twist2:", "needs the network's file"),
            ("ipc:", "needs a session name"),
            ("holdx", "unknown policy"),
            ("twist2", "needs the network's file"),
            (
                "twist3:a.onnx",
                "unknown policy `twist3:a.onnx` (did you mean",
            ),
        ] {
            let e = NamedPolicy::parse(spec).unwrap_err().to_string();
            assert!(e.contains(says), "{spec}: {e}");
        }
    }

    #[test]
    fn a_relative_file_is_taken_against_a_directory_with_its_parameters() {
        let arg = NamedPolicy::parse("softmimic:n/S.onnx@stiffness=60").unwrap();
        let moved = arg.with_file_in(Path::new("/specs"));
        assert_eq!(moved.as_str(), "softmimic:/specs/n/S.onnx@stiffness=60");
        assert_eq!(moved.parameters(), Some("stiffness=60"));
        let varied = NamedPolicy::parse("softmimic:S.onnx")
            .unwrap()
            .with_parameters("stiffness=40")
            .unwrap();
        assert_eq!(varied.as_str(), "softmimic:S.onnx@stiffness=40");
        assert_eq!(varied.parameter("stiffness"), Some(40.0));
        // A sweep's axis over a parameter the family lacks is refused where it is made.
        assert!(NamedPolicy::parse("twist2:F.onnx")
            .unwrap()
            .with_parameters("stiffness=40")
            .unwrap_err()
            .contains("takes no parameters"));
        assert!(varied.with_parameters("stiffness=50").is_err());
        assert!(NamedPolicy::parse("hold")
            .unwrap()
            .with_parameters("x=1")
            .is_err());
    }
}
