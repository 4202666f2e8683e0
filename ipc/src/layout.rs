//! The wire layout of one control step: an observation batch (simulator → policy) and an
//! action batch (policy → simulator), each one contiguous block of shared memory.
//!
//! Both blocks travel as iceoryx2 slices of `u64` words, so every block is 8-byte aligned
//! in every language. Inside, everything is native-endian, 8-byte aligned and free of
//! padding, which is what lets Python see the batch as one numpy structured array and C
//! see it through plain structs plus computed offsets.
//!
//! ```text
//! observation batch = BatchHeader (64 B) + n_envs × env block (env_stride B)
//!                     + policy inputs: n_envs × n_inputs f32, row-major, zero-padded to 8 B
//! env block         = EnvHeader (32 B)
//!                     + root_pos_w 3, root_quat_wxyz 4, root_lin_vel_w 3, root_ang_vel_w 3,
//!                       root_lin_vel_b 3, root_ang_vel_b 3, projected_gravity_b 3   (f64)
//!                     + q n, qd n, last_action n                                    (f64)
//!                     + n_refs × reference frame
//! reference frame   = time_s 1, root_pos_w 3, root_quat_wxyz 4, root_lin_vel_w 3,
//!                     root_ang_vel_w 3, joint_pos n, joint_vel n                    (f64)
//! action batch      = ActionHeader (32 B) + n_envs × n f64 (joint position targets'
//!                     raw actions, canonical joint order)
//! ```
//! Quaternions are (w, x, y, z); `_w` is the world frame, `_b` the root (base) frame.
//!
//! The policy-input block is there when the policy asked, in its hello, for a network input
//! the simulator builds (TWIST2's 1432 floats): one contiguous `[n_envs, n_inputs]` float32
//! array, the tensor the network takes, so a client in any language feeds it to its
//! network without building or copying anything. `n_inputs` is 0 otherwise.

use bytemuck::{Pod, Zeroable};

/// First word of every batch: "THOR" in ASCII, to catch a misrouted or torn block.
pub const MAGIC: u32 = 0x524f_4854;

/// `BatchHeader::command`: a control step; the policy must answer.
pub const COMMAND_STEP: u32 = 0;
/// `BatchHeader::command`: the run is over; no answer expected.
pub const COMMAND_END: u32 = 1;

/// `EnvHeader::flags`: this slot carries a live episode; act on it. Inactive slots are
/// padding (the run has fewer episodes left than slots) and their actions are ignored.
pub const FLAG_ACTIVE: u32 = 1;
/// `EnvHeader::flags`: first observation of a new episode (clear any history).
pub const FLAG_RESET: u32 = 2;
/// `EnvHeader::flags`: the slot's previous episode ended early (fall, deadline rule,
/// policy failure) rather than at the end of its reference.
pub const FLAG_PREVIOUS_TERMINATED: u32 = 4;

/// Head of an observation batch.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Pod, Zeroable)]
pub struct BatchHeader {
    /// [`MAGIC`].
    pub magic: u32,
    /// [`crate::PROTOCOL_VERSION`].
    pub protocol_version: u32,
    /// [`COMMAND_STEP`] or [`COMMAND_END`].
    pub command: u32,
    /// Environment slots in this batch (fixed for the session).
    pub n_envs: u32,
    /// Joints per environment.
    pub n_joints: u32,
    /// Reference frames per environment.
    pub n_refs: u32,
    /// Bytes per environment block.
    pub env_stride: u32,
    /// `f32` values per environment in the policy-input block (0: none).
    pub n_inputs: u32,
    /// Step counter of the session, echoed in the action batch.
    pub seq: u64,
    /// Environment slots flagged [`FLAG_ACTIVE`] in this batch, counted by the simulator
    /// as it publishes it: when it equals `n_envs` a client can take every slot as active
    /// without reading each slot's flags (at 64 slots, 64 cache lines another core wrote).
    pub n_active: u32,
    /// Reserved, zero.
    pub reserved0: u32,
    /// Reserved, zero.
    pub reserved: [u64; 2],
}

/// Head of one environment's block.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct EnvHeader {
    /// Unique per episode within a run (its index in the run's schedule).
    pub episode_id: u64,
    /// Control step within the episode (0 on the first observation).
    pub step: u64,
    /// `FLAG_*` bits.
    pub flags: u32,
    /// Reserved, zero.
    pub reserved: u32,
    /// Time since the episode started, s.
    pub time_s: f64,
}

/// Head of an action batch.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Pod, Zeroable)]
pub struct ActionHeader {
    /// [`MAGIC`].
    pub magic: u32,
    /// [`crate::PROTOCOL_VERSION`].
    pub protocol_version: u32,
    /// Environment slots (as in the request).
    pub n_envs: u32,
    /// Joints per environment.
    pub n_joints: u32,
    /// The `seq` of the observation batch this answers.
    pub seq: u64,
    /// Reserved, zero.
    pub reserved: u64,
}

/// The `f64` arrays of an environment block after its [`EnvHeader`], in wire order, with
/// their lengths in units of `n_joints` (`per_joint`) or fixed (`fixed`).
pub const ENV_ARRAYS: [(&str, usize, usize); 10] = [
    ("root_pos_w", 3, 0),
    ("root_quat_wxyz", 4, 0),
    ("root_lin_vel_w", 3, 0),
    ("root_ang_vel_w", 3, 0),
    ("root_lin_vel_b", 3, 0),
    ("root_ang_vel_b", 3, 0),
    ("projected_gravity_b", 3, 0),
    ("q", 0, 1),
    ("qd", 0, 1),
    ("last_action", 0, 1),
];

/// The `f64` arrays of one reference frame, in wire order (same convention).
pub const REF_ARRAYS: [(&str, usize, usize); 7] = [
    ("time_s", 1, 0),
    ("root_pos_w", 3, 0),
    ("root_quat_wxyz", 4, 0),
    ("root_lin_vel_w", 3, 0),
    ("root_ang_vel_w", 3, 0),
    ("joint_pos", 0, 1),
    ("joint_vel", 0, 1),
];

/// One named field of the layout: byte offset within its block and element count.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Field {
    /// Field name (as in [`ENV_ARRAYS`] / [`REF_ARRAYS`], reference fields prefixed with
    /// `reference[i].`).
    pub name: String,
    /// Byte offset from the start of the environment block.
    pub offset: usize,
    /// Number of `f64` elements.
    pub len: usize,
}

/// Sizes and offsets of a session's batches, computed once from its shape.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Layout {
    /// Environment slots.
    pub n_envs: usize,
    /// Joints per environment.
    pub n_joints: usize,
    /// Reference frames per environment.
    pub n_refs: usize,
    /// `f32` values per environment in the policy-input block (0: none).
    pub n_inputs: usize,
}

const F64: usize = 8;
const F32: usize = 4;

impl Layout {
    /// Bytes of one reference frame.
    pub fn ref_stride(&self) -> usize {
        F64 * REF_ARRAYS
            .iter()
            .map(|&(_, fixed, per)| fixed + per * self.n_joints)
            .sum::<usize>()
    }

    /// Byte offset of the first reference frame within an environment block.
    pub fn ref_offset(&self) -> usize {
        std::mem::size_of::<EnvHeader>()
            + F64
                * ENV_ARRAYS
                    .iter()
                    .map(|&(_, fixed, per)| fixed + per * self.n_joints)
                    .sum::<usize>()
    }

    /// Bytes of one environment block.
    pub fn env_stride(&self) -> usize {
        self.ref_offset() + self.n_refs * self.ref_stride()
    }

    /// Byte offset of the policy-input block within an observation batch.
    pub fn inputs_offset(&self) -> usize {
        std::mem::size_of::<BatchHeader>() + self.n_envs * self.env_stride()
    }

    /// Bytes of the policy-input block, padding included.
    pub fn inputs_bytes(&self) -> usize {
        (F32 * self.n_envs * self.n_inputs).next_multiple_of(8)
    }

    /// Bytes of an observation batch.
    pub fn obs_bytes(&self) -> usize {
        self.inputs_offset() + self.inputs_bytes()
    }

    /// Bytes of an action batch.
    pub fn action_bytes(&self) -> usize {
        std::mem::size_of::<ActionHeader>() + self.n_envs * self.n_joints * F64
    }

    /// `u64` words of an observation batch (the iceoryx2 slice length).
    pub fn obs_words(&self) -> usize {
        self.obs_bytes() / 8
    }

    /// `u64` words of an action batch.
    pub fn action_words(&self) -> usize {
        self.action_bytes() / 8
    }

    /// Every `f64` field of an environment block, in wire order, with offsets relative to
    /// the block. The C header, the Python dtype and the tests are all checked against this.
    pub fn env_fields(&self) -> Vec<Field> {
        let mut fields = Vec::new();
        let mut offset = std::mem::size_of::<EnvHeader>();
        for &(name, fixed, per) in &ENV_ARRAYS {
            let len = fixed + per * self.n_joints;
            fields.push(Field {
                name: name.into(),
                offset,
                len,
            });
            offset += F64 * len;
        }
        for i in 0..self.n_refs {
            for &(name, fixed, per) in &REF_ARRAYS {
                let len = fixed + per * self.n_joints;
                fields.push(Field {
                    name: format!("reference[{i}].{name}"),
                    offset,
                    len,
                });
                offset += F64 * len;
            }
        }
        debug_assert_eq!(offset, self.env_stride());
        fields
    }

    /// Byte offset of a named environment array (an [`ENV_ARRAYS`] name).
    fn env_array(&self, name: &str) -> (usize, usize) {
        let mut offset = std::mem::size_of::<EnvHeader>();
        for &(n, fixed, per) in &ENV_ARRAYS {
            let len = fixed + per * self.n_joints;
            if n == name {
                return (offset, len);
            }
            offset += F64 * len;
        }
        unreachable!("unknown env array {name}")
    }

    /// Byte offset of a named reference array within reference frame `i`.
    fn ref_array(&self, i: usize, name: &str) -> (usize, usize) {
        let mut offset = self.ref_offset() + i * self.ref_stride();
        for &(n, fixed, per) in &REF_ARRAYS {
            let len = fixed + per * self.n_joints;
            if n == name {
                return (offset, len);
            }
            offset += F64 * len;
        }
        unreachable!("unknown reference array {name}")
    }
}

/// Why a received block could not be read.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum LayoutError {
    /// The block is shorter than the session's layout says.
    #[error("batch of {got} bytes, the session's layout needs {want}")]
    Size {
        /// Bytes received.
        got: usize,
        /// Bytes expected.
        want: usize,
    },
    /// The magic word is wrong: not a ThorArena batch.
    #[error("bad magic word {0:#x}: not a ThorArena batch")]
    Magic(u32),
    /// The header disagrees with the session's shape.
    #[error("batch header says {what} = {got}, the session has {want}")]
    Shape {
        /// Which field.
        what: &'static str,
        /// Header value.
        got: u64,
        /// Session value.
        want: u64,
    },
}

fn f64s(bytes: &[u8]) -> &[f64] {
    bytemuck::cast_slice(bytes)
}

fn f64s_mut(bytes: &mut [u8]) -> &mut [f64] {
    bytemuck::cast_slice_mut(bytes)
}

/// A read-only view of an observation batch.
#[derive(Clone, Copy)]
pub struct ObsBatch<'a> {
    layout: Layout,
    bytes: &'a [u8],
}

impl<'a> ObsBatch<'a> {
    /// Checks size, magic and shape against the session's layout.
    pub fn new(layout: Layout, bytes: &'a [u8]) -> Result<Self, LayoutError> {
        if bytes.len() < layout.obs_bytes() {
            return Err(LayoutError::Size {
                got: bytes.len(),
                want: layout.obs_bytes(),
            });
        }
        let batch = Self {
            layout,
            bytes: &bytes[..layout.obs_bytes()],
        };
        let h = batch.header();
        if h.magic != MAGIC {
            return Err(LayoutError::Magic(h.magic));
        }
        let checks = [
            (
                "protocol_version",
                h.protocol_version as u64,
                crate::PROTOCOL_VERSION as u64,
            ),
            ("n_envs", h.n_envs as u64, layout.n_envs as u64),
            ("n_joints", h.n_joints as u64, layout.n_joints as u64),
            ("n_refs", h.n_refs as u64, layout.n_refs as u64),
            ("n_inputs", h.n_inputs as u64, layout.n_inputs as u64),
            (
                "env_stride",
                h.env_stride as u64,
                layout.env_stride() as u64,
            ),
        ];
        for (what, got, want) in checks {
            if got != want {
                return Err(LayoutError::Shape { what, got, want });
            }
        }
        Ok(batch)
    }

    /// The batch header.
    pub fn header(&self) -> BatchHeader {
        bytemuck::pod_read_unaligned(&self.bytes[..std::mem::size_of::<BatchHeader>()])
    }

    /// The whole block (for copying or hashing).
    pub fn bytes(&self) -> &'a [u8] {
        self.bytes
    }

    /// Number of environment slots.
    pub fn n_envs(&self) -> usize {
        self.layout.n_envs
    }

    /// The policy-input block: `n_envs × n_inputs` values, row-major (empty when the
    /// policy asked for none).
    pub fn policy_inputs(&self) -> &'a [f32] {
        let start = self.layout.inputs_offset();
        let len = self.layout.n_envs * self.layout.n_inputs;
        bytemuck::cast_slice(&self.bytes[start..start + F32 * len])
    }

    /// Environment slot `i`.
    pub fn env(&self, i: usize) -> EnvObs<'a> {
        let s = self.layout.env_stride();
        let start = std::mem::size_of::<BatchHeader>() + i * s;
        EnvObs {
            layout: self.layout,
            bytes: &self.bytes[start..start + s],
        }
    }
}

/// A read-only view of one environment's block.
#[derive(Clone, Copy)]
pub struct EnvObs<'a> {
    layout: Layout,
    bytes: &'a [u8],
}

impl<'a> EnvObs<'a> {
    /// The block header.
    pub fn header(&self) -> EnvHeader {
        bytemuck::pod_read_unaligned(&self.bytes[..std::mem::size_of::<EnvHeader>()])
    }

    /// True when the slot carries a live episode.
    pub fn is_active(&self) -> bool {
        self.header().flags & FLAG_ACTIVE != 0
    }

    /// A named array of [`ENV_ARRAYS`].
    pub fn array(&self, name: &str) -> &'a [f64] {
        let (off, len) = self.layout.env_array(name);
        f64s(&self.bytes[off..off + F64 * len])
    }

    /// A named array of [`REF_ARRAYS`] of reference frame `i`.
    pub fn reference(&self, i: usize, name: &str) -> &'a [f64] {
        let (off, len) = self.layout.ref_array(i, name);
        f64s(&self.bytes[off..off + F64 * len])
    }
}

/// A writable view of an observation batch (the simulator fills it in shared memory).
pub struct ObsBatchMut<'a> {
    layout: Layout,
    bytes: &'a mut [u8],
}

impl<'a> ObsBatchMut<'a> {
    /// Wraps a block of at least `layout.obs_bytes()` bytes and writes its header.
    pub fn new(layout: Layout, bytes: &'a mut [u8], command: u32, seq: u64) -> Self {
        let header = BatchHeader {
            magic: MAGIC,
            protocol_version: crate::PROTOCOL_VERSION,
            command,
            n_envs: layout.n_envs as u32,
            n_joints: layout.n_joints as u32,
            n_refs: layout.n_refs as u32,
            env_stride: layout.env_stride() as u32,
            n_inputs: layout.n_inputs as u32,
            seq,
            n_active: 0,
            reserved0: 0,
            reserved: [0; 2],
        };
        let bytes = &mut bytes[..layout.obs_bytes()];
        bytes[..std::mem::size_of::<BatchHeader>()].copy_from_slice(bytemuck::bytes_of(&header));
        // The padding after the inputs, so no stale bytes of an earlier step go out.
        let end = layout.inputs_offset() + F32 * layout.n_envs * layout.n_inputs;
        bytes[end..].fill(0);
        Self { layout, bytes }
    }

    /// Counts the slots whose block is flagged [`FLAG_ACTIVE`] into the header's
    /// `n_active`; the session calls it once the batch is filled, before publishing.
    pub fn count_active(&mut self) {
        let s = self.layout.env_stride();
        let head = std::mem::size_of::<BatchHeader>();
        let n_active = (0..self.layout.n_envs)
            .filter(|i| {
                let block = &self.bytes[head + i * s..][..std::mem::size_of::<EnvHeader>()];
                bytemuck::pod_read_unaligned::<EnvHeader>(block).flags & FLAG_ACTIVE != 0
            })
            .count() as u32;
        let at = std::mem::offset_of!(BatchHeader, n_active);
        self.bytes[at..at + 4].copy_from_slice(&n_active.to_ne_bytes());
    }

    /// Slot `i`'s row of the policy-input block, writable (empty when the policy asked for
    /// none).
    pub fn policy_input(&mut self, i: usize) -> &mut [f32] {
        let n = self.layout.n_inputs;
        let start = self.layout.inputs_offset() + F32 * i * n;
        bytemuck::cast_slice_mut(&mut self.bytes[start..start + F32 * n])
    }

    /// Environment slot `i`, writable.
    pub fn env(&mut self, i: usize) -> EnvObsMut<'_> {
        let s = self.layout.env_stride();
        let start = std::mem::size_of::<BatchHeader>() + i * s;
        EnvObsMut {
            layout: self.layout,
            bytes: &mut self.bytes[start..start + s],
        }
    }
}

/// A writable view of one environment's block.
pub struct EnvObsMut<'a> {
    layout: Layout,
    bytes: &'a mut [u8],
}

impl EnvObsMut<'_> {
    /// Writes the block header.
    pub fn set_header(&mut self, header: &EnvHeader) {
        self.bytes[..std::mem::size_of::<EnvHeader>()].copy_from_slice(bytemuck::bytes_of(header));
    }

    /// A named array of [`ENV_ARRAYS`], writable.
    pub fn array(&mut self, name: &str) -> &mut [f64] {
        let (off, len) = self.layout.env_array(name);
        f64s_mut(&mut self.bytes[off..off + F64 * len])
    }

    /// A named array of reference frame `i`, writable.
    pub fn reference(&mut self, i: usize, name: &str) -> &mut [f64] {
        let (off, len) = self.layout.ref_array(i, name);
        f64s_mut(&mut self.bytes[off..off + F64 * len])
    }

    /// Marks the slot inactive and zeroes its data (a padding slot).
    pub fn clear(&mut self, flags: u32) {
        self.bytes.fill(0);
        self.set_header(&EnvHeader {
            flags,
            ..Zeroable::zeroed()
        });
    }
}

/// A read-only view of an action batch.
pub struct ActionBatch<'a> {
    layout: Layout,
    bytes: &'a [u8],
}

impl<'a> ActionBatch<'a> {
    /// Checks size, magic and shape.
    pub fn new(layout: Layout, bytes: &'a [u8]) -> Result<Self, LayoutError> {
        if bytes.len() < layout.action_bytes() {
            return Err(LayoutError::Size {
                got: bytes.len(),
                want: layout.action_bytes(),
            });
        }
        let batch = Self {
            layout,
            bytes: &bytes[..layout.action_bytes()],
        };
        let h = batch.header();
        if h.magic != MAGIC {
            return Err(LayoutError::Magic(h.magic));
        }
        for (what, got, want) in [
            (
                "protocol_version",
                h.protocol_version as u64,
                crate::PROTOCOL_VERSION as u64,
            ),
            ("n_envs", h.n_envs as u64, layout.n_envs as u64),
            ("n_joints", h.n_joints as u64, layout.n_joints as u64),
        ] {
            if got != want {
                return Err(LayoutError::Shape { what, got, want });
            }
        }
        Ok(batch)
    }

    /// The batch header.
    pub fn header(&self) -> ActionHeader {
        bytemuck::pod_read_unaligned(&self.bytes[..std::mem::size_of::<ActionHeader>()])
    }

    /// The action of slot `i`.
    pub fn env(&self, i: usize) -> &'a [f64] {
        let n = self.layout.n_joints;
        let start = std::mem::size_of::<ActionHeader>() + i * n * F64;
        f64s(&self.bytes[start..start + n * F64])
    }
}

/// A writable view of an action batch (the policy fills it in shared memory).
pub struct ActionBatchMut<'a> {
    layout: Layout,
    bytes: &'a mut [u8],
}

impl<'a> ActionBatchMut<'a> {
    /// Wraps a block of at least `layout.action_bytes()` bytes and writes its header.
    pub fn new(layout: Layout, bytes: &'a mut [u8], seq: u64) -> Self {
        let header = ActionHeader {
            magic: MAGIC,
            protocol_version: crate::PROTOCOL_VERSION,
            n_envs: layout.n_envs as u32,
            n_joints: layout.n_joints as u32,
            seq,
            reserved: 0,
        };
        let bytes = &mut bytes[..layout.action_bytes()];
        bytes[..std::mem::size_of::<ActionHeader>()].copy_from_slice(bytemuck::bytes_of(&header));
        Self { layout, bytes }
    }

    /// The header's bytes, writable: for fault injection only (`thorarena client
    /// --bad-header-at-step`, which tests what the simulator does with a policy that
    /// breaks the protocol).
    #[doc(hidden)]
    pub fn header_bytes_mut(&mut self) -> &mut [u8] {
        &mut self.bytes[..std::mem::size_of::<ActionHeader>()]
    }

    /// All actions, `n_envs × n_joints`, row-major.
    pub fn all(&mut self) -> &mut [f64] {
        f64s_mut(&mut self.bytes[std::mem::size_of::<ActionHeader>()..])
    }

    /// The action of slot `i`, writable.
    pub fn env(&mut self, i: usize) -> &mut [f64] {
        let n = self.layout.n_joints;
        let start = std::mem::size_of::<ActionHeader>() + i * n * F64;
        f64s_mut(&mut self.bytes[start..start + n * F64])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_sizes_are_the_documented_ones() {
        assert_eq!(std::mem::size_of::<BatchHeader>(), 64);
        assert_eq!(std::mem::size_of::<EnvHeader>(), 32);
        assert_eq!(std::mem::size_of::<ActionHeader>(), 32);
    }

    #[test]
    fn g1_layout_sizes() {
        let l = Layout {
            n_envs: 2,
            n_joints: 29,
            n_refs: 2,
            n_inputs: 0,
        };
        // 32 B header + (22 + 3·29) f64 + 2 · (14 + 2·29) f64
        assert_eq!(l.ref_offset(), 32 + 8 * (22 + 87));
        assert_eq!(l.ref_stride(), 8 * (14 + 58));
        assert_eq!(l.env_stride(), 32 + 8 * 109 + 2 * 8 * 72);
        assert_eq!(l.obs_bytes(), 64 + 2 * l.env_stride());
        assert_eq!(l.action_bytes(), 32 + 2 * 29 * 8);
        let fields = l.env_fields();
        assert_eq!(fields[0].name, "root_pos_w");
        assert_eq!(fields[0].offset, 32);
        let last = fields.last().unwrap();
        assert_eq!(last.name, "reference[1].joint_vel");
        assert_eq!(last.offset + 8 * last.len, l.env_stride());
    }

    #[test]
    fn writes_read_back_through_the_views() {
        let l = Layout {
            n_envs: 3,
            n_joints: 4,
            n_refs: 2,
            n_inputs: 3,
        };
        let mut words = vec![0u64; l.obs_words()];
        {
            let mut b = ObsBatchMut::new(l, bytemuck::cast_slice_mut(&mut words), COMMAND_STEP, 7);
            let mut e = b.env(2);
            e.set_header(&EnvHeader {
                episode_id: 11,
                step: 5,
                flags: FLAG_ACTIVE | FLAG_RESET,
                reserved: 0,
                time_s: 0.1,
            });
            e.array("qd").copy_from_slice(&[1.0, 2.0, 3.0, 4.0]);
            e.reference(1, "joint_vel")
                .copy_from_slice(&[5.0, 6.0, 7.0, 8.0]);
            b.policy_input(1).copy_from_slice(&[0.5, -1.5, 2.5]);
        }
        let b = ObsBatch::new(l, bytemuck::cast_slice(&words)).unwrap();
        assert_eq!(b.header().seq, 7);
        let e = b.env(2);
        assert!(e.is_active());
        assert_eq!(e.header().episode_id, 11);
        assert_eq!(e.array("qd"), &[1.0, 2.0, 3.0, 4.0]);
        assert_eq!(e.reference(1, "joint_vel"), &[5.0, 6.0, 7.0, 8.0]);
        assert!(!b.env(0).is_active());
        // The policy inputs: one [n_envs, n_inputs] f32 array after the environment blocks,
        // 9 floats padded to 40 bytes.
        assert_eq!(l.inputs_bytes(), 40);
        assert_eq!(l.obs_bytes(), 64 + 3 * l.env_stride() + 40);
        let inputs = b.policy_inputs();
        assert_eq!(inputs.len(), 9);
        assert_eq!(&inputs[3..6], &[0.5, -1.5, 2.5]);
        assert_eq!(b.header().n_inputs, 3);
        // The named field table agrees with the accessors.
        let f = l
            .env_fields()
            .into_iter()
            .find(|f| f.name == "reference[1].joint_vel")
            .unwrap();
        let start = 64 + 2 * l.env_stride() + f.offset;
        let raw: &[f64] =
            bytemuck::cast_slice(&bytemuck::cast_slice::<u64, u8>(&words)[start..start + 32]);
        assert_eq!(raw, &[5.0, 6.0, 7.0, 8.0]);
    }

    #[test]
    fn shape_mismatch_is_an_error_not_a_misread() {
        let l = Layout {
            n_envs: 1,
            n_joints: 29,
            n_refs: 1,
            n_inputs: 0,
        };
        let mut words = vec![0u64; l.obs_words()];
        ObsBatchMut::new(l, bytemuck::cast_slice_mut(&mut words), COMMAND_STEP, 0);
        let wider = Layout { n_inputs: 2, ..l };
        // The simulator's batch has no inputs where the policy expects some: a shape error
        // (the missing block also makes it short, which is checked first).
        assert!(ObsBatch::new(wider, bytemuck::cast_slice(&words)).is_err());
        let other = Layout { n_joints: 23, ..l };
        let err = ObsBatch::new(other, bytemuck::cast_slice(&words))
            .err()
            .unwrap();
        assert!(
            matches!(
                err,
                LayoutError::Shape {
                    what: "n_joints",
                    ..
                }
            ),
            "{err}"
        );
        let short = &bytemuck::cast_slice::<u64, u8>(&words)[..100];
        assert!(matches!(
            ObsBatch::new(l, short),
            Err(LayoutError::Size { .. })
        ));
    }
}
