//! The session handshake: the policy says what it is and what it needs (`Hello`), the
//! simulator answers with the session's shape or a typed refusal (`Welcome`).
//!
//! Both are fixed-size `#[repr(C)]` messages with stable iceoryx2 type names, mirrored
//! field for field by the C header and the Python ctypes structures.
//!
//! `Hello` carries the protocol version, the joint count and a hash of the joint names,
//! the reference offsets the policy wants to see, its pid and name, and the name of a
//! network input for the simulator to build. `Welcome` answers with the batch's shape,
//! the control step, the budget, the action mapping (`action_offset_rad`, `action_scale`,
//! so a policy answers in actions without knowing the profile) and the input's width — or
//! a status and a message saying why the policy was refused.

use iceoryx2::prelude::ZeroCopySend;

/// Most reference frames a policy may ask for (GMT needs 20).
pub const MAX_REFERENCE_OFFSETS: usize = 64;
/// Most joints a robot may have on the wire (the action mapping in `Welcome` is fixed-size).
pub const MAX_JOINTS: usize = 64;
/// Bytes of a policy name in `Hello` (NUL-padded UTF-8).
pub const NAME_BYTES: usize = 64;
/// Bytes of the refusal message in `Welcome` (NUL-padded UTF-8).
pub const MESSAGE_BYTES: usize = 256;
/// Bytes of a policy-input name in `Hello` (NUL-padded UTF-8).
pub const INPUT_NAME_BYTES: usize = 32;
/// Bytes of a declared profile's name in `Hello` (NUL-padded UTF-8).
pub const PROFILE_NAME_BYTES: usize = 32;

/// `Hello::profile_kind` values: how the policy declares the dynamics profile it was
/// trained under.
#[repr(u32)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ProfileKind {
    /// None declared: the run must name one (`--profile`), or it refuses the policy.
    None = 0,
    /// A profile the simulator bundles, by name (`profile_name`).
    Named = 1,
    /// The profile's numbers (`profile_*` fields), named `profile_name`.
    Content = 2,
}

/// What the policy sends to join a session.
#[repr(C)]
#[derive(Debug, Clone, Copy, ZeroCopySend)]
#[type_name("thorarena::Hello")]
pub struct Hello {
    /// The policy's [`crate::PROTOCOL_VERSION`].
    pub protocol_version: u32,
    /// Joints the policy controls.
    pub n_joints: u32,
    /// [`joint_names_hash`] of the joint order the policy assumes.
    pub joint_names_hash: u64,
    /// The policy's process id (the simulator watches it to detect a crash at once).
    pub pid: u32,
    /// Entries used in `reference_offsets_s`.
    pub n_refs: u32,
    /// Times ahead of each control step at which the policy wants reference frames, s.
    pub reference_offsets_s: [f64; MAX_REFERENCE_OFFSETS],
    /// The policy's name, for results (NUL-padded UTF-8).
    pub name: [u8; NAME_BYTES],
    /// A network input the simulator should build for the policy, by name (`twist2`:
    /// TWIST2's 1432 floats), or empty: the simulator writes it into the batch's
    /// policy-input block (`layout`), so a client in a slow language only runs its network.
    /// The simulator refuses a name it does not offer ([`Status::Input`]).
    pub input: [u8; INPUT_NAME_BYTES],
    /// A [`ProfileKind`]: whether and how the policy declares its profile.
    pub profile_kind: u32,
    /// Control steps between an action and its effect (`ProfileKind::Content`).
    pub profile_action_delay_steps: u32,
    /// The bundled profile's name (`Named`) or the declared profile's own (`Content`),
    /// NUL-padded UTF-8.
    pub profile_name: [u8; PROFILE_NAME_BYTES],
    /// Control period, s (`Content`).
    pub profile_control_dt_s: f64,
    /// Physics step, s (`Content`); must divide the control period.
    pub profile_physics_dt_s: f64,
    /// Raw actions are clipped to ±this before scaling (`Content`; 0: no clip).
    pub profile_action_clip: f64,
    /// PD stiffness per joint in the robot's canonical order, N·m/rad (`Content`; first
    /// `n_joints` entries used).
    pub profile_kp: [f64; MAX_JOINTS],
    /// PD damping per joint, N·m·s/rad (`Content`).
    pub profile_kd: [f64; MAX_JOINTS],
    /// Action scale per joint: target = offset + scale · action (`Content`).
    pub profile_action_scale: [f64; MAX_JOINTS],
    /// Action offset per joint (the policy's default pose), rad (`Content`).
    pub profile_action_offset_rad: [f64; MAX_JOINTS],
}

impl Hello {
    /// A hello of zeros (no joints, no offsets, no name, no profile): a base to fill.
    pub fn blank() -> Self {
        Self {
            protocol_version: 0,
            n_joints: 0,
            joint_names_hash: 0,
            pid: 0,
            n_refs: 0,
            reference_offsets_s: [0.0; MAX_REFERENCE_OFFSETS],
            name: [0; NAME_BYTES],
            input: [0; INPUT_NAME_BYTES],
            profile_kind: ProfileKind::None as u32,
            profile_action_delay_steps: 0,
            profile_name: [0; PROFILE_NAME_BYTES],
            profile_control_dt_s: 0.0,
            profile_physics_dt_s: 0.0,
            profile_action_clip: 0.0,
            profile_kp: [0.0; MAX_JOINTS],
            profile_kd: [0.0; MAX_JOINTS],
            profile_action_scale: [0.0; MAX_JOINTS],
            profile_action_offset_rad: [0.0; MAX_JOINTS],
        }
    }
}

/// The dynamics profile a policy says it was trained under, as it travels in [`Hello`].
#[derive(Debug, Clone, PartialEq)]
pub enum DeclaredProfile {
    /// A profile the simulator bundles, by name (`wbc-mjlab`, `default`).
    Named(String),
    /// The profile's numbers.
    Content(ProfileContent),
}

/// A profile declared by its numbers, per joint in the robot's canonical order.
#[derive(Debug, Clone, PartialEq)]
pub struct ProfileContent {
    /// Its name, for results.
    pub name: String,
    /// Control period, s.
    pub control_dt_s: f64,
    /// Physics step, s.
    pub physics_dt_s: f64,
    /// Control steps between an action and its effect.
    pub action_delay_steps: u32,
    /// Raw actions are clipped to ±this before scaling (`None`: no clip).
    pub action_clip: Option<f64>,
    /// PD stiffness, N·m/rad.
    pub kp: Vec<f64>,
    /// PD damping, N·m·s/rad.
    pub kd: Vec<f64>,
    /// Target = offset + scale · action.
    pub action_scale: Vec<f64>,
    /// The action offset (default pose), rad.
    pub action_offset_rad: Vec<f64>,
}

impl DeclaredProfile {
    /// The profile's name (the bundled one's, or the content's own).
    pub fn name(&self) -> &str {
        match self {
            Self::Named(name) => name,
            Self::Content(c) => &c.name,
        }
    }

    /// Writes the declaration into `hello` (whose `n_joints` is set); `Err` says why it
    /// does not fit the message.
    pub fn write_into(declared: Option<&Self>, hello: &mut Hello) -> Result<(), String> {
        let fits_name = |name: &str| {
            if name.is_empty() || name.len() >= PROFILE_NAME_BYTES {
                Err(format!(
                    "profile name {name:?}: give 1 to {} bytes",
                    PROFILE_NAME_BYTES - 1
                ))
            } else {
                Ok(to_fixed::<PROFILE_NAME_BYTES>(name))
            }
        };
        match declared {
            None => hello.profile_kind = ProfileKind::None as u32,
            Some(Self::Named(name)) => {
                hello.profile_kind = ProfileKind::Named as u32;
                hello.profile_name = fits_name(name)?;
            }
            Some(Self::Content(c)) => {
                let n = hello.n_joints as usize;
                for (field, v) in [
                    ("kp", &c.kp),
                    ("kd", &c.kd),
                    ("action_scale", &c.action_scale),
                    ("action_offset_rad", &c.action_offset_rad),
                ] {
                    if v.len() != n {
                        return Err(format!(
                            "profile `{}`: {field} has {} values for {n} joints",
                            c.name,
                            v.len()
                        ));
                    }
                }
                hello.profile_kind = ProfileKind::Content as u32;
                hello.profile_name = fits_name(&c.name)?;
                hello.profile_control_dt_s = c.control_dt_s;
                hello.profile_physics_dt_s = c.physics_dt_s;
                hello.profile_action_delay_steps = c.action_delay_steps;
                hello.profile_action_clip = c.action_clip.unwrap_or(0.0);
                hello.profile_kp[..n].copy_from_slice(&c.kp);
                hello.profile_kd[..n].copy_from_slice(&c.kd);
                hello.profile_action_scale[..n].copy_from_slice(&c.action_scale);
                hello.profile_action_offset_rad[..n].copy_from_slice(&c.action_offset_rad);
            }
        }
        Ok(())
    }

    /// The declaration `hello` carries (`None`: none); `Err` says what is malformed.
    /// The numbers are the simulator's to judge: here they are only read.
    pub fn read_from(hello: &Hello) -> Result<Option<Self>, String> {
        let n = (hello.n_joints as usize).min(MAX_JOINTS);
        let name = from_fixed(&hello.profile_name);
        let kind = [ProfileKind::None, ProfileKind::Named, ProfileKind::Content]
            .into_iter()
            .find(|k| *k as u32 == hello.profile_kind)
            .ok_or_else(|| {
                format!(
                    "profile kind {} is none of 0 (none), 1 (by name), 2 (by content)",
                    hello.profile_kind
                )
            })?;
        if kind != ProfileKind::None && name.is_empty() {
            return Err("a declared profile needs a name".into());
        }
        Ok(match kind {
            ProfileKind::None => None,
            ProfileKind::Named => Some(Self::Named(name)),
            ProfileKind::Content => Some(Self::Content(ProfileContent {
                name,
                control_dt_s: hello.profile_control_dt_s,
                physics_dt_s: hello.profile_physics_dt_s,
                action_delay_steps: hello.profile_action_delay_steps,
                action_clip: Some(hello.profile_action_clip).filter(|c| *c != 0.0),
                kp: hello.profile_kp[..n].to_vec(),
                kd: hello.profile_kd[..n].to_vec(),
                action_scale: hello.profile_action_scale[..n].to_vec(),
                action_offset_rad: hello.profile_action_offset_rad[..n].to_vec(),
            })),
        })
    }
}

/// `Welcome::status` values; also the C ABI's error codes for a refused session.
#[repr(u32)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    /// Accepted.
    Ok = 0,
    /// Different protocol versions.
    ProtocolVersion = 1,
    /// Different joint counts.
    JointCount = 2,
    /// Same count, different joint names or order.
    JointNames = 3,
    /// More than [`MAX_REFERENCE_OFFSETS`] offsets, or an offset that is negative or not finite.
    ReferenceOffsets = 4,
    /// Another policy is already connected.
    Busy = 5,
    /// The run refused this policy (its name, or a resumed run that was another
    /// policy's); the message says why.
    Rejected = 6,
    /// The simulator builds no policy input of the name asked for, or not from the
    /// reference offsets asked for; the message lists what it offers.
    Input = 7,
    /// The profile the policy declared is unknown, malformed or not the run's, or it
    /// declared none and the run names none; the message says which and what to do.
    Profile = 8,
}

impl Status {
    /// From the wire value.
    pub fn from_u32(v: u32) -> Option<Self> {
        [
            Self::Ok,
            Self::ProtocolVersion,
            Self::JointCount,
            Self::JointNames,
            Self::ReferenceOffsets,
            Self::Busy,
            Self::Rejected,
            Self::Input,
            Self::Profile,
        ]
        .into_iter()
        .find(|s| *s as u32 == v)
    }
}

/// The simulator's answer.
#[repr(C)]
#[derive(Debug, Clone, Copy, ZeroCopySend)]
#[type_name("thorarena::Welcome")]
pub struct Welcome {
    /// The simulator's [`crate::PROTOCOL_VERSION`].
    pub protocol_version: u32,
    /// A [`Status`].
    pub status: u32,
    /// Joints per environment.
    pub n_joints: u32,
    /// Environment slots per batch.
    pub n_envs: u32,
    /// [`joint_names_hash`] of the simulator's canonical joint order.
    pub joint_names_hash: u64,
    /// Control period, s.
    pub control_dt_s: f64,
    /// Latency budget per step, s (0: none, pure lock-step).
    pub budget_s: f64,
    /// Reference frames per environment (as asked).
    pub n_refs: u32,
    /// The simulator's process id.
    pub pid: u32,
    /// `f32` values per environment in the batch's policy-input block (0: none asked).
    pub n_inputs: u32,
    /// Reserved, zero.
    pub reserved: u32,
    /// How a raw action becomes a PD target under the session's dynamics profile:
    /// `target_j = action_offset_rad[j] + action_scale[j] · action_j` (first `n_joints`
    /// entries used). Lets a policy that thinks in joint targets answer in actions.
    pub action_offset_rad: [f64; MAX_JOINTS],
    /// See `action_offset_rad`.
    pub action_scale: [f64; MAX_JOINTS],
    /// Why the session was refused (NUL-padded UTF-8), empty when accepted.
    pub message: [u8; MESSAGE_BYTES],
}

/// FNV-1a (64 bit) of the joint names joined by `\n`: cheap to compute in any language,
/// and enough to catch a different joint order.
pub fn joint_names_hash<S: AsRef<str>>(names: &[S]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for (i, name) in names.iter().enumerate() {
        if i > 0 {
            h = (h ^ u64::from(b'\n')).wrapping_mul(0x0000_0100_0000_01b3);
        }
        for b in name.as_ref().bytes() {
            h = (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    h
}

/// Copies `s` into a NUL-padded fixed buffer, truncating at a character boundary.
pub fn to_fixed<const N: usize>(s: &str) -> [u8; N] {
    let mut out = [0u8; N];
    let mut end = s.len().min(N - 1);
    while !s.is_char_boundary(end) {
        end -= 1;
    }
    out[..end].copy_from_slice(&s.as_bytes()[..end]);
    out
}

/// The string in a NUL-padded fixed buffer.
pub fn from_fixed(b: &[u8]) -> String {
    let end = b.iter().position(|&c| c == 0).unwrap_or(b.len());
    String::from_utf8_lossy(&b[..end]).into_owned()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fnv1a_matches_known_vectors() {
        // FNV-1a 64 of "a" and of "foobar" (published test vectors).
        assert_eq!(joint_names_hash(&["a"]), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(joint_names_hash(&["foobar"]), 0x8594_4171_f739_67e8);
        assert_eq!(
            joint_names_hash(&["foo", "bar"]),
            joint_names_hash(&["foo\nbar"])
        );
        assert_ne!(joint_names_hash(&["a", "b"]), joint_names_hash(&["b", "a"]));
    }

    #[test]
    fn fixed_strings_round_trip_and_truncate_on_char_boundaries() {
        let b: [u8; 8] = to_fixed("twist2");
        assert_eq!(from_fixed(&b), "twist2");
        let b: [u8; 4] = to_fixed("héé");
        assert_eq!(from_fixed(&b), "hé");
    }

    fn blank_hello(n_joints: u32) -> Hello {
        Hello {
            n_joints,
            ..Hello::blank()
        }
    }

    #[test]
    fn a_declared_profile_round_trips_through_the_hello() {
        let content = ProfileContent {
            name: "mine".into(),
            control_dt_s: 0.02,
            physics_dt_s: 0.005,
            action_delay_steps: 1,
            action_clip: Some(10.0),
            kp: vec![40.0, 99.0],
            kd: vec![2.0, 5.0],
            action_scale: vec![0.25, 0.5],
            action_offset_rad: vec![-0.1, 0.3],
        };
        for declared in [
            None,
            Some(DeclaredProfile::Named("wbc-mjlab".into())),
            Some(DeclaredProfile::Content(content.clone())),
        ] {
            let mut hello = blank_hello(2);
            DeclaredProfile::write_into(declared.as_ref(), &mut hello).unwrap();
            assert_eq!(DeclaredProfile::read_from(&hello).unwrap(), declared);
        }
        let mut hello = blank_hello(3);
        let short = DeclaredProfile::Content(content);
        assert!(DeclaredProfile::write_into(Some(&short), &mut hello)
            .unwrap_err()
            .contains("2 values for 3 joints"));
        hello.profile_kind = 7;
        assert!(DeclaredProfile::read_from(&hello)
            .unwrap_err()
            .contains("profile kind 7"));
    }

    #[test]
    fn message_sizes_are_stable() {
        assert_eq!(
            std::mem::size_of::<Hello>(),
            24 + 8 * MAX_REFERENCE_OFFSETS
                + NAME_BYTES
                + INPUT_NAME_BYTES
                + 8
                + PROFILE_NAME_BYTES
                + 24
                + 4 * 8 * MAX_JOINTS
        );
        assert_eq!(
            std::mem::size_of::<Welcome>(),
            56 + 16 * MAX_JOINTS + MESSAGE_BYTES
        );
        assert_eq!(
            unsafe { <Hello as ZeroCopySend>::type_name() },
            "thorarena::Hello"
        );
    }
}
