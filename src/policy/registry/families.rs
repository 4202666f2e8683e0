//! Every kind of policy a run can name, in one table: how it is spelled, what the user
//! supplies, the profile it runs under when none is named and which profiles it accepts,
//! how many environment slots a worker gives it, how it is built, and where it runs.
//! `thorarena policies` prints it and [`super::NamedPolicy`] reads every other column, so a
//! new family is one entry here (with its builder and profile rule, beside it in
//! `policies.rs`).

use super::parameters::Parameter;
use super::policies;
use super::trained_forces::{TrainedForces, FALCON_FORCES, SOFTMIMIC_FORCES};
use super::{NamedPolicy, RegistryError};
use crate::policy::Policy;
use crate::sim::profile::Profile;
use crate::sim::robot::RobotModel;

/// Where a family's policy runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Runs {
    /// In the simulator's process.
    InProcess,
    /// In its own process, any language, over shared memory (`thorarena-ipc`).
    OwnProcess,
}

/// What a family's argument holds after `name:`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Target {
    /// Nothing: the argument is the family's name (the built-ins).
    Nothing,
    /// A network file, optionally followed by `@KEY=VALUE,…` parameters.
    File,
    /// The session a policy process connects to.
    Session,
}

/// Builds a family's policy in process from its parsed argument, for `robot` under
/// `profile` (its default pose and action mapping).
pub type Build = fn(&NamedPolicy, &RobotModel, &Profile) -> Result<Box<dyn Policy>, RegistryError>;

/// Whether a profile is one a family's policy runs under; `Err` says why not.
pub type ProfileRule = fn(&Profile) -> Result<(), String>;

/// One kind of policy.
#[derive(Clone, Copy)]
pub struct PolicyFamily {
    /// Its name: the whole argument of a built-in, the prefix before `:` otherwise.
    pub name: &'static str,
    /// How a run names it.
    pub spelling: &'static str,
    /// What it is.
    pub what: &'static str,
    /// What the user supplies.
    pub supplies: &'static str,
    /// The bundled profile it runs under when none is named.
    pub profile: &'static str,
    /// Where it runs.
    pub runs: Runs,
    /// Environment slots per worker when a run names none: [`NETWORK_SLOTS_PER_WORKER`]
    /// for a network in process, else 1. Records do not depend on it.
    pub slots_per_worker: usize,
    /// What its argument holds after `name:`.
    pub target: Target,
    /// How it is built in process (`None`: a policy process the caller serves).
    pub build: Option<Build>,
    /// The profiles it runs under.
    pub profile_rule: ProfileRule,
    /// The parameters its argument may give after the file's `@` (none: any is refused).
    pub parameters: &'static [Parameter],
    /// A file to name when the argument lacks one (`twist2_1017_25k.onnx, TWIST2's
    /// released checkpoint`), for the error message.
    pub example: Option<&'static str>,
    /// The forces its networks were trained with on the robot: tables mark the cells
    /// outside them.
    pub trained_forces: TrainedForces,
}

impl std::fmt::Debug for PolicyFamily {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PolicyFamily")
            .field("name", &self.name)
            .finish_non_exhaustive()
    }
}

impl PartialEq for PolicyFamily {
    fn eq(&self, other: &Self) -> bool {
        self.name == other.name
    }
}

impl PolicyFamily {
    /// Whether policy argument `spec` names this family.
    pub fn names(&self, spec: &str) -> bool {
        match self.target {
            Target::Nothing => spec == self.name,
            Target::File | Target::Session => spec
                .strip_prefix(self.name)
                .is_some_and(|rest| rest.starts_with(':')),
        }
    }
}

/// Environment slots per worker by default for a network in process, which infers on
/// the workers (`eval/runner/free_running.rs`): a worker's `act` call has a fixed cost that
/// several slots share. Measured (`thorarena bench eval`, TWIST2, MuJoCo, 60 synthetic
/// sequences × 2 settings, 2 workers, two runs each): 1 slot per worker 12.7–14.1 s,
/// 4 slots 11.9–12.4 s.
pub const NETWORK_SLOTS_PER_WORKER: usize = 4;

/// Environment slots per worker by default for a BeyondMimic-family network (and
/// wbc-mjlab's): one whole network call per worker step
/// ([`crate::policy::beyondmimic::INFERENCE_BATCH`] rows), so no row of a call is padding.
/// Measured (`thorarena bench eval`, wbc-mjlab, rapier, 60 synthetic sequences × 2
/// settings, 2 workers): 8 slots per worker and 8 rows per call 68.7 s, run ÷ floor 1.08;
/// 4 and 4, 69.4–70.9 s, 1.10.
pub const BEYONDMIMIC_SLOTS_PER_WORKER: usize = crate::policy::beyondmimic::INFERENCE_BATCH;

/// SoftMimic's stiffness command: what its networks were trained on
/// (`compliant_motion_augmentation/constants.py` of robodreamer/softmimic@458f475).
pub const SOFTMIMIC_PARAMETERS: [Parameter; 2] = {
    use crate::policy::softmimic::{ROTATIONAL_RANGE, STIFFNESS_RANGE};
    [
        Parameter {
            name: "stiffness",
            unit: "N/m",
            range: STIFFNESS_RANGE,
            what: "the commanded linear stiffness of both wrists; default 60",
        },
        Parameter {
            name: "rotational_stiffness",
            unit: "N·m/rad",
            range: ROTATIONAL_RANGE,
            what: "the commanded rotational stiffness; default stiffness / 60",
        },
    ]
};

/// FALCON's parameters: ablations of its arms' residual and of the three ways the
/// benchmark's commands leave training's distribution (`policy::falcon::commands`).
pub const FALCON_PARAMETERS: [Parameter; 4] = [
    Parameter {
        name: "arm_residual",
        unit: "×",
        range: (0.0, 1.0),
        what: "scale of the arms' residual on their commanded joints; default 1 (as trained), 0 holds the arms at the reference (an ablation)",
    },
    Parameter {
        name: "min_speed",
        unit: "m/s",
        range: (0.0, 1.0),
        what: "velocity commands at or under this speed are zeroed; default 0, training 0.2",
    },
    Parameter {
        name: "yaw_ff",
        unit: "×",
        range: (0.0, 1.0),
        what: "scale of the reference's yaw rate fed forward on the heading feedback; default 1, training 0",
    },
    Parameter {
        name: "hold",
        unit: "s",
        range: (0.0, 10.0),
        what: "a command sample is held this long (heading feedback and arms still every step); default 0 (every step), training 10",
    },
];

/// Every policy family, built-ins first.
pub const POLICY_FAMILIES: [PolicyFamily; 9] = [
    PolicyFamily {
        name: "hold",
        spelling: "hold",
        what: "holds the profile's default pose (a floor: no tracking at all)",
        supplies: "nothing",
        profile: "default",
        slots_per_worker: 1,
        runs: Runs::InProcess,
        target: Target::Nothing,
        build: Some(policies::builtin),
        profile_rule: policies::any_profile,
        parameters: &[],
        example: None,
        trained_forces: TrainedForces::Untrained,
    },
    PolicyFamily {
        name: "replay",
        spelling: "replay",
        what: "sends the reference joint angles as PD targets (open loop)",
        supplies: "nothing",
        profile: "default",
        slots_per_worker: 1,
        runs: Runs::InProcess,
        target: Target::Nothing,
        build: Some(policies::builtin),
        profile_rule: policies::any_profile,
        parameters: &[],
        example: None,
        trained_forces: TrainedForces::Untrained,
    },
    PolicyFamily {
        name: "balance",
        spelling: "balance",
        what: "the reference joint angles with ankle and hip feedback on the pelvis tilt (a stabiliser; it does not walk)",
        supplies: "nothing",
        profile: "default",
        slots_per_worker: 1,
        runs: Runs::InProcess,
        target: Target::Nothing,
        build: Some(policies::builtin),
        profile_rule: policies::any_profile,
        parameters: &[],
        example: None,
        trained_forces: TrainedForces::Untrained,
    },
    PolicyFamily {
        name: "twist2",
        spelling: "twist2:FILE.onnx",
        what: "TWIST2's general motion tracker (arXiv 2511.02832), its ONNX network",
        supplies: "the network file (twist2_1017_25k.onnx is the released one)",
        profile: "twist2",
        slots_per_worker: NETWORK_SLOTS_PER_WORKER,
        runs: Runs::InProcess,
        target: Target::File,
        build: Some(policies::twist2),
        profile_rule: policies::twist2_profile,
        parameters: &[],
        example: Some("twist2_1017_25k.onnx, TWIST2's released checkpoint"),
        trained_forces: TrainedForces::Blind,
    },
    PolicyFamily {
        name: "beyondmimic",
        spelling: "beyondmimic:FILE.onnx",
        what: "a BeyondMimic-style tracker exported by mjlab, whole_body_tracking or holosoma",
        supplies: "the network file; for a file naming no observation terms, a profile that does (holosoma: the profile holosoma-wbt)",
        profile: "beyondmimic",
        slots_per_worker: BEYONDMIMIC_SLOTS_PER_WORKER,
        runs: Runs::InProcess,
        target: Target::File,
        build: Some(policies::beyondmimic),
        profile_rule: policies::beyondmimic_profile,
        parameters: &[],
        example: Some("policy.onnx, an mjlab or holosoma G1 export"),
        trained_forces: TrainedForces::Unknown,
    },
    PolicyFamily {
        name: "wbc-mjlab",
        spelling: "wbc-mjlab:FILE.onnx",
        what: "wbc-mjlab's general G1 tracker (a residual on the reference joints, 132 inputs), run as a BeyondMimic-family network",
        supplies: "the network file (wbc_g1_policy.onnx of wbc-mjlab/wbc-g1-deploy)",
        profile: "wbc-mjlab",
        slots_per_worker: BEYONDMIMIC_SLOTS_PER_WORKER,
        runs: Runs::InProcess,
        target: Target::File,
        build: Some(policies::wbc_mjlab),
        profile_rule: policies::wbc_mjlab_profile,
        parameters: &[],
        example: Some("wbc_g1_policy.onnx, wbc-mjlab's general G1 tracker"),
        trained_forces: TrainedForces::Blind,
    },
    PolicyFamily {
        name: "falcon",
        spelling: "falcon:FILE.onnx[@arm_residual=X,min_speed=V,yaw_ff=X,hold=S]",
        what: "FALCON's force-adaptive loco-manipulation policy (RSS 2025), a command follower: velocity, height, stand and waist commands derived from the reference, arms residual on it",
        supplies: "the network file (g1_29dof_falcon.onnx of LeCAR-Lab/FALCON)",
        profile: "falcon",
        slots_per_worker: NETWORK_SLOTS_PER_WORKER,
        runs: Runs::InProcess,
        target: Target::File,
        build: Some(policies::falcon),
        profile_rule: policies::falcon_profile,
        parameters: &FALCON_PARAMETERS,
        example: Some("g1_29dof_falcon.onnx, FALCON's released G1 network"),
        trained_forces: FALCON_FORCES,
    },
    PolicyFamily {
        name: "softmimic",
        spelling: "softmimic:FILE.onnx[@stiffness=N]",
        what: "SoftMimic's compliant trackers and their stiff baselines (arXiv:2510.17792), with a stiffness command in their input (10–1000 N/m as trained, up to 600 while the rotational one follows as N/60; default 60)",
        supplies: "the network file (onnx/*.onnx converted from SoftMimic's released TorchScript); optionally the stiffness, N/m",
        profile: "softmimic",
        slots_per_worker: NETWORK_SLOTS_PER_WORKER,
        runs: Runs::InProcess,
        target: Target::File,
        build: Some(policies::softmimic),
        profile_rule: policies::softmimic_profile,
        parameters: &SOFTMIMIC_PARAMETERS,
        example: Some("StaticStand-SoftMimic.onnx@stiffness=60, a SoftMimic network and its stiffness in N/m"),
        trained_forces: SOFTMIMIC_FORCES,
    },
    PolicyFamily {
        name: "ipc",
        spelling: "ipc:SESSION",
        what: "a policy process in any language (Rust, C, C++, Python clients) joining the session",
        supplies: "the session name the process connects to, and the process",
        profile: "default",
        slots_per_worker: 1,
        runs: Runs::OwnProcess,
        target: Target::Session,
        build: None,
        profile_rule: policies::any_profile,
        parameters: &[],
        example: None,
        trained_forces: TrainedForces::Unknown,
    },
];

/// `--policy`'s help, from the table: every family's spelling, so the help follows the
/// registry (`tests/cli.rs` holds every command's help to it). `in_process_only`: for the
/// commands that run the policy themselves (no `ipc:` session).
pub fn policy_help(in_process_only: bool) -> String {
    let spellings: Vec<&str> = POLICY_FAMILIES
        .iter()
        .filter(|f| !in_process_only || f.runs == Runs::InProcess)
        .map(|f| f.spelling)
        .collect();
    format!(
        "The policy: {} (`thorarena policies` says what each is, what you supply and the profile it runs under)",
        spellings.join(", ")
    )
}

/// `--profile`'s help, from the table: how the profile is chosen when none is named.
pub fn profile_help() -> String {
    let mut by_family: Vec<String> = Vec::new();
    for f in &POLICY_FAMILIES {
        let entry = format!("`{}` for {}", f.profile, f.name);
        if !by_family.contains(&entry) {
            by_family.push(entry);
        }
    }
    format!(
        "Dynamics profile: a bundled name (data/profiles) or a .toml path. Default: a published network known by content runs under its own (`thorarena policies` lists them), a policy process (`ipc:`, a command) under the one it declares at connect (one that declares none is refused unless this is given), any other policy under its family's: {}. A profile the family, or the process's declaration, contradicts is refused",
        by_family.iter().filter(|e| !e.ends_with("for ipc")).cloned().collect::<Vec<_>>().join(", ")
    )
}

/// The family policy argument `spec` names, if any.
pub fn policy_family(spec: &str) -> Option<&'static PolicyFamily> {
    POLICY_FAMILIES.iter().find(|f| f.names(spec))
}

/// Every family a run can name and every published network known by content, as the
/// Markdown tables `thorarena policies` prints: what a user supplies for each, the
/// profile it runs under when none is named, and where it runs.
pub fn families_text() -> String {
    let mut text = String::from(
        "| `option.policy` | what it is | you supply | profile by default | runs |\n|---|---|---|---|---|\n",
    );
    for f in &POLICY_FAMILIES {
        let runs = match f.runs {
            Runs::InProcess => "in process",
            Runs::OwnProcess => "its own process",
        };
        let profile = match f.runs {
            Runs::InProcess => format!("`{}`", f.profile),
            Runs::OwnProcess => "the one it declares at connect".to_string(),
        };
        text += &format!(
            "| `{}` | {} | {} | {profile} | {runs} |\n",
            f.spelling, f.what, f.supplies
        );
    }
    text += "\nForces in training (tables mark a cell whose forces lie outside them):\n\n| family | trained with |\n|---|---|\n";
    for f in &POLICY_FAMILIES {
        text += &format!("| `{}` | {} |\n", f.name, f.trained_forces.describe());
    }
    text += "\nPublished networks known by content (SHA-256): each runs under its own profile when no `option.profile` is named, whatever the file is called.\n\n| file | profile | source |\n|---|---|---|\n";
    for n in &super::KNOWN_NETWORKS {
        text += &format!("| `{}` | `{}` | {} |\n", n.file, n.profile, n.source);
    }
    text += "\nProfiles: data/profiles/*.toml (or a .toml path with `option.profile`); `client` runs a built-in as a policy process.\n";
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_argument_names_at_most_one_family() {
        for (spec, family) in [
            ("hold", Some("hold")),
            ("twist2:a.onnx", Some("twist2")),
            ("beyondmimic:dir/b.onnx", Some("beyondmimic")),
            ("wbc-mjlab:w.onnx", Some("wbc-mjlab")),
            ("ipc:demo", Some("ipc")),
            ("falcon:f.onnx", Some("falcon")),
            ("softmimic:s.onnx@stiffness=200", Some("softmimic")),
            ("twist2", None),
            ("holdx", None),
            ("beyondmimicx:f.onnx", None),
        ] {
            assert_eq!(policy_family(spec).map(|f| f.name), family, "{spec}");
            assert!(POLICY_FAMILIES.iter().filter(|f| f.names(spec)).count() <= 1);
        }
    }

    #[test]
    fn every_default_profile_is_bundled() {
        let bundled = crate::policy::registry::bundled_profile_names();
        for f in &POLICY_FAMILIES {
            assert!(bundled.iter().any(|b| b == f.profile), "{}", f.profile);
        }
    }
}
