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

    #[test]
    fn message_sizes_are_stable() {
        assert_eq!(
            std::mem::size_of::<Hello>(),
            24 + 8 * MAX_REFERENCE_OFFSETS + NAME_BYTES + INPUT_NAME_BYTES
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
