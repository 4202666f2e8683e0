//! The dynamics profile a policy process declares at connect — the gains, damping, action
//! mapping, periods and delay it was trained under — judged against the run's.
//!
//! A network trained in mjlab or Isaac Lab under its own gains, scored under another
//! profile's, is scored on dynamics it never met. In process each family runs under its
//! own profile and a contradiction is refused (`registry::families`); a policy process
//! says its own in its hello (`thorarena_ipc::DeclaredProfile`), and the run either takes
//! it ([`ProcessProfile::Declared`]: no `--profile` given) or holds it against the profile
//! it names ([`ProcessProfile::Named`]), refusing a contradiction unless told to run
//! anyway. A run whose profile nobody declares — neither the process nor the run — is
//! refused in the handshake, and the process hears both ways to fix it.

use crate::sim::profile::{bundled_profile_path, load_profile, profile_from_numbers};
use crate::sim::profile::{Profile, ProfileNumbers};
use crate::sim::robot::RobotModel;
use thorarena_ipc::{ActionMapping, DeclaredProfile, Refusal, Status};

/// How a run takes the profile of a policy process.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ProcessProfile {
    /// The run names its profile (`--profile`): a process that declares another is
    /// refused, unless `mismatch_ok` (then the run's profile stands, recorded as a
    /// mismatch). A process that declares none runs under the run's.
    Named {
        /// Run a contradicting declaration anyway (`--profile-mismatch-ok`).
        mismatch_ok: bool,
    },
    /// The run names none: it takes the profile the process declares, and refuses a
    /// process that declares none.
    Declared,
}

/// What a run made of a policy process's declaration: recorded with the run.
#[derive(Debug, Clone, PartialEq)]
pub struct ProfileDeclaration {
    /// The profile the process declared, resolved (`None`: it declared none, and the
    /// run's own profile stands).
    pub declared: Option<Profile>,
    /// The run takes this profile instead of the one it was planned with.
    pub adopted: bool,
    /// The declared profile contradicts the run's, and the run was told to run anyway.
    pub mismatch: bool,
}

impl ProfileDeclaration {
    /// The action mapping the welcome carries, when the run takes the declared profile.
    pub fn mapping(&self) -> Option<ActionMapping> {
        let p = self.declared.as_ref().filter(|_| self.adopted)?;
        Some(ActionMapping {
            control_dt_s: p.control_dt_s,
            action_offset_rad: p.action_offset_rad.clone(),
            action_scale: p.action_scale.clone(),
        })
    }
}

/// Whether two profiles give a policy the same dynamics: periods, delay, clip, action
/// mapping and gains (names and sources aside; torque limits too, which are the motors'
/// and which a declaration by numbers does not carry). `Err` names the first that differs.
pub fn same_dynamics(a: &Profile, b: &Profile) -> Result<(), String> {
    let fields: [(&str, bool); 7] = [
        ("control_dt_s", a.control_dt_s == b.control_dt_s),
        (
            "action_delay_steps",
            a.action_delay_steps == b.action_delay_steps,
        ),
        ("action_clip", a.action_clip == b.action_clip),
        ("action_scale", a.action_scale == b.action_scale),
        (
            "action_offset_rad",
            a.action_offset_rad == b.action_offset_rad,
        ),
        ("kp", a.gains.kp == b.gains.kp),
        ("kd", a.gains.kd == b.gains.kd),
    ];
    match fields.iter().find(|(_, same)| !same) {
        None => Ok(()),
        Some((field, _)) => Err(format!("its `{field}` differs")),
    }
}

/// The refusal of a process that declared no profile to a run that names none.
fn none_declared(policy: &str) -> Refusal {
    Refusal {
        status: Status::Profile,
        message: format!(
            "policy `{policy}` declared no profile and the run names none: declare the one it was trained under at connect (Python connect(profile=...), C options.profile_name or options.profile), or run with --profile NAME"
        ),
    }
}

/// The bundled profiles' names, sorted.
fn bundled_names() -> Vec<String> {
    let dir = bundled_profile_path("x");
    let mut names: Vec<String> = dir
        .parent()
        .and_then(|d| std::fs::read_dir(d).ok())
        .into_iter()
        .flatten()
        .filter_map(|e| {
            let name = e.ok()?.file_name().into_string().ok()?;
            name.strip_suffix(".toml").map(str::to_string)
        })
        .collect();
    names.sort();
    names
}

/// `declared` resolved for `robot`: a bundled profile by name, or the numbers.
pub fn resolve(declared: &DeclaredProfile, robot: &RobotModel) -> Result<Profile, String> {
    match declared {
        DeclaredProfile::Named(name) => {
            let path = bundled_profile_path(name);
            let plain = !name.is_empty()
                && name
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_');
            if !plain || !path.is_file() {
                return Err(format!(
                    "declared profile `{name}`: no bundled profile is named so (a process names one of {}, or declares the numbers)",
                    bundled_names().join(", ")
                ));
            }
            load_profile(&path, robot).map_err(|e| format!("declared profile `{name}`: {e}"))
        }
        DeclaredProfile::Content(c) => profile_from_numbers(
            ProfileNumbers {
                name: c.name.clone(),
                source: "declared by the policy process at connect".into(),
                control_dt_s: c.control_dt_s,
                physics_dt_s: c.physics_dt_s,
                action_delay_steps: c.action_delay_steps as usize,
                action_clip: c.action_clip,
                action_scale: c.action_scale.clone(),
                action_offset_rad: c.action_offset_rad.clone(),
                kp: c.kp.clone(),
                kd: c.kd.clone(),
            },
            "the profile the policy declared",
            robot,
        )
        .map_err(|e| e.to_string()),
    }
}

/// Judges what policy `policy` declared against the run's `profile` and `rule`: what the
/// run makes of it, or the refusal the process hears.
pub fn judge(
    policy: &str,
    declared: Option<&DeclaredProfile>,
    profile: &Profile,
    rule: ProcessProfile,
    robot: &RobotModel,
) -> Result<ProfileDeclaration, Refusal> {
    let refuse = |message: String| Refusal {
        status: Status::Profile,
        message,
    };
    let Some(declared) = declared else {
        return match rule {
            ProcessProfile::Declared => Err(none_declared(policy)),
            ProcessProfile::Named { .. } => Ok(ProfileDeclaration {
                declared: None,
                adopted: false,
                mismatch: false,
            }),
        };
    };
    let resolved = resolve(declared, robot).map_err(refuse)?;
    match rule {
        ProcessProfile::Declared => Ok(ProfileDeclaration {
            declared: Some(resolved),
            adopted: true,
            mismatch: false,
        }),
        ProcessProfile::Named { mismatch_ok } => match same_dynamics(&resolved, profile) {
            Ok(()) => Ok(ProfileDeclaration {
                declared: Some(resolved),
                adopted: false,
                mismatch: false,
            }),
            Err(_) if mismatch_ok => Ok(ProfileDeclaration {
                declared: Some(resolved),
                adopted: false,
                mismatch: true,
            }),
            Err(why) => Err(refuse(format!(
                "policy `{policy}` declares profile `{}`, which contradicts the run's `--profile {}` ({why}): leave out `--profile` to run under the declared one, or give `--profile-mismatch-ok` to run it anyway (recorded)",
                declared.name(),
                profile.name
            ))),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use thorarena_ipc::ProfileContent;

    fn robot() -> RobotModel {
        crate::sim::robot::load_bundled("g1_29dof").unwrap()
    }

    fn bundled(name: &str, robot: &RobotModel) -> Profile {
        load_profile(&bundled_profile_path(name), robot).unwrap()
    }

    fn content_of(p: &Profile, name: &str) -> DeclaredProfile {
        DeclaredProfile::Content(ProfileContent {
            name: name.into(),
            control_dt_s: p.control_dt_s,
            physics_dt_s: p.physics_dt_s,
            action_delay_steps: p.action_delay_steps as u32,
            action_clip: p.action_clip,
            kp: p.gains.kp.clone(),
            kd: p.gains.kd.clone(),
            action_scale: p.action_scale.clone(),
            action_offset_rad: p.action_offset_rad.clone(),
        })
    }

    #[test]
    fn a_run_that_names_none_takes_the_declaration_and_refuses_none() {
        let robot = robot();
        let default = bundled("default", &robot);
        let named = DeclaredProfile::Named("wbc-mjlab".into());
        let taken = judge(
            "p",
            Some(&named),
            &default,
            ProcessProfile::Declared,
            &robot,
        )
        .unwrap();
        assert!(taken.adopted);
        assert_eq!(taken.declared.as_ref().unwrap().name, "wbc-mjlab");
        assert_eq!(
            taken.mapping().unwrap().action_scale,
            taken.declared.as_ref().unwrap().action_scale
        );
        let refused = judge("p", None, &default, ProcessProfile::Declared, &robot).unwrap_err();
        assert_eq!(refused.status, Status::Profile);
        assert!(
            refused.message.contains("--profile") && refused.message.contains("profile="),
            "{}",
            refused.message
        );
    }

    #[test]
    fn a_named_profile_holds_against_a_contradicting_declaration() {
        let robot = robot();
        let default = bundled("default", &robot);
        let wbc = bundled("wbc-mjlab", &robot);
        let rule = ProcessProfile::Named { mismatch_ok: false };
        // The same numbers under another name are the same profile.
        let same = judge(
            "p",
            Some(&content_of(&default, "mine")),
            &default,
            rule,
            &robot,
        );
        assert!(!same.unwrap().adopted);
        let other = content_of(&wbc, "mine");
        let refused = judge("p", Some(&other), &default, rule, &robot).unwrap_err();
        assert!(
            refused.message.contains("contradicts") && refused.message.contains("differs"),
            "{}",
            refused.message
        );
        let anyway = ProcessProfile::Named { mismatch_ok: true };
        let ran = judge("p", Some(&other), &default, anyway, &robot).unwrap();
        assert!(ran.mismatch && !ran.adopted);
    }

    #[test]
    fn declared_numbers_are_checked_as_a_file_is() {
        let robot = robot();
        let default = bundled("default", &robot);
        let DeclaredProfile::Content(mut c) = content_of(&default, "mine") else {
            unreachable!()
        };
        c.kp[3] = 1e300;
        let why = resolve(&DeclaredProfile::Content(c.clone()), &robot).unwrap_err();
        assert!(why.contains("kp"), "{why}");
        c.kp[3] = 40.0;
        c.control_dt_s = 0.021;
        let why = resolve(&DeclaredProfile::Content(c), &robot).unwrap_err();
        assert!(why.contains("control_dt_s"), "{why}");
        let why = resolve(&DeclaredProfile::Named("../x.toml".into()), &robot).unwrap_err();
        assert!(why.contains("no bundled profile"), "{why}");
        assert!(why.contains("wbc-mjlab"), "{why}");
    }
}
