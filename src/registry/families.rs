//! Every kind of policy a run can name, in one table: how it is spelled, what the user
//! supplies, the profile it runs under when none is named, and where it runs.
//! `thorarena policies` prints it; [`super::policy`] builds from it, and
//! [`super::family_profile`] reads its profile column, so a new family is one entry here
//! plus its builder.

/// Where a family's policy runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Runs {
    /// In the simulator's process.
    InProcess,
    /// In its own process, any language, over shared memory (`thorarena-ipc`).
    OwnProcess,
}

/// One kind of policy.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
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
}

impl PolicyFamily {
    /// Whether policy argument `spec` names this family.
    pub fn names(&self, spec: &str) -> bool {
        if self.spelling.contains(':') {
            spec.strip_prefix(self.name)
                .is_some_and(|rest| rest.starts_with(':'))
        } else {
            spec == self.name
        }
    }
}

/// Environment slots per worker by default for a network in process, which infers on
/// the workers (`runner/free_running.rs`): a worker's `act` call has a fixed cost that
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
    },
    PolicyFamily {
        name: "replay",
        spelling: "replay",
        what: "sends the reference joint angles as PD targets (open loop)",
        supplies: "nothing",
        profile: "default",
        slots_per_worker: 1,
        runs: Runs::InProcess,
    },
    PolicyFamily {
        name: "balance",
        spelling: "balance",
        what: "the reference joint angles with ankle and hip feedback on the pelvis tilt (a stabiliser; it does not walk)",
        supplies: "nothing",
        profile: "default",
        slots_per_worker: 1,
        runs: Runs::InProcess,
    },
    PolicyFamily {
        name: "twist2",
        spelling: "twist2:FILE.onnx",
        what: "TWIST2's general motion tracker (arXiv 2511.02832), its ONNX network",
        supplies: "the network file (twist2_1017_25k.onnx is the released one)",
        profile: "twist2",
        slots_per_worker: NETWORK_SLOTS_PER_WORKER,
        runs: Runs::InProcess,
    },
    PolicyFamily {
        name: "beyondmimic",
        spelling: "beyondmimic:FILE.onnx",
        what: "a BeyondMimic-style tracker exported by mjlab, whole_body_tracking or holosoma",
        supplies: "the network file; for a file naming no observation terms, a profile that does (holosoma: --profile holosoma-wbt)",
        profile: "beyondmimic",
        slots_per_worker: BEYONDMIMIC_SLOTS_PER_WORKER,
        runs: Runs::InProcess,
    },
    PolicyFamily {
        name: "wbc-mjlab",
        spelling: "wbc-mjlab:FILE.onnx",
        what: "wbc-mjlab's general G1 tracker (a residual on the reference joints, 132 inputs), run as a BeyondMimic-family network",
        supplies: "the network file (wbc_g1_policy.onnx of wbc-mjlab/wbc-g1-deploy)",
        profile: "wbc-mjlab",
        slots_per_worker: BEYONDMIMIC_SLOTS_PER_WORKER,
        runs: Runs::InProcess,
    },
    PolicyFamily {
        name: "falcon",
        spelling: "falcon:FILE.onnx",
        what: "FALCON's force-adaptive loco-manipulation policy (RSS 2025), a command follower: velocity, height, stand and waist commands derived from the reference, arms residual on it",
        supplies: "the network file (g1_29dof_falcon.onnx of LeCAR-Lab/FALCON)",
        profile: "falcon",
        slots_per_worker: NETWORK_SLOTS_PER_WORKER,
        runs: Runs::InProcess,
    },
    PolicyFamily {
        name: "softmimic",
        spelling: "softmimic:FILE.onnx[@stiffness=N]",
        what: "SoftMimic's compliant trackers and their stiff baselines (arXiv:2510.17792), with a stiffness command in their input (10–1000 N/m as trained, up to 600 while the rotational one follows as N/60; default 60)",
        supplies: "the network file (onnx/*.onnx converted from SoftMimic's released TorchScript); optionally the stiffness, N/m",
        profile: "softmimic",
        slots_per_worker: NETWORK_SLOTS_PER_WORKER,
        runs: Runs::InProcess,
    },
    PolicyFamily {
        name: "ipc",
        spelling: "ipc:SESSION",
        what: "a policy process in any language (Rust, C, C++, Python clients) joining the session",
        supplies: "the session name the process connects to, and the process",
        profile: "default",
        slots_per_worker: 1,
        runs: Runs::OwnProcess,
    },
];

/// The family policy argument `spec` names, if any.
pub fn policy_family(spec: &str) -> Option<&'static PolicyFamily> {
    POLICY_FAMILIES.iter().find(|f| f.names(spec))
}

/// The family and the file of a policy argument naming a network file
/// (`twist2:FILE.onnx`, `beyondmimic:FILE.onnx`, …), so a sweep can resolve the path; a
/// family's parameters (`softmimic:FILE.onnx@stiffness=200`) are not part of the file.
pub fn policy_file(spec: &str) -> Option<(&'static PolicyFamily, &str)> {
    let family = policy_family(spec).filter(|f| f.spelling.contains(":FILE"))?;
    Some((family, split_parameters(&spec[family.name.len() + 1..]).0))
}

/// The parameters a policy argument names after its file (`stiffness=200` of
/// `softmimic:FILE.onnx@stiffness=200`), if any.
pub fn policy_parameters(spec: &str) -> Option<&str> {
    let family = policy_family(spec).filter(|f| f.spelling.contains(":FILE"))?;
    split_parameters(&spec[family.name.len() + 1..]).1
}

/// `FILE@KEY=VALUE,…` → (`FILE`, `Some("KEY=VALUE,…")`); a file with no `@` followed by a
/// `KEY=` → (it, `None`).
pub fn split_parameters(file_and_parameters: &str) -> (&str, Option<&str>) {
    match file_and_parameters.rsplit_once('@') {
        Some((file, params)) if params.contains('=') => (file, Some(params)),
        _ => (file_and_parameters, None),
    }
}

/// The family name and the network file's stem of a policy argument naming a network
/// file (`twist2:dir/twist2_1017_25k.onnx` → `("twist2", "twist2_1017_25k")`): how
/// labels and run directories name it.
pub fn policy_file_stem(spec: &str) -> Option<(&'static str, String)> {
    let (family, file) = policy_file(spec)?;
    let stem = std::path::Path::new(file)
        .file_stem()
        .map_or_else(|| file.to_string(), |s| s.to_string_lossy().into_owned());
    Some((family.name, stem))
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
    fn parameters_are_not_part_of_the_file() {
        let (_, file) = policy_file("softmimic:dir/a@b.onnx@stiffness=200").unwrap();
        assert_eq!(file, "dir/a@b.onnx");
        assert_eq!(policy_file("twist2:x@y.onnx").unwrap().1, "x@y.onnx");
        assert_eq!(
            policy_file_stem("softmimic:d/Pour-SoftMimic.onnx@stiffness=200"),
            Some(("softmimic", "Pour-SoftMimic".to_string()))
        );
    }

    #[test]
    fn every_default_profile_is_bundled() {
        let bundled = crate::registry::bundled_profile_names();
        for f in &POLICY_FAMILIES {
            assert!(bundled.iter().any(|b| b == f.profile), "{}", f.profile);
        }
    }
}
