//! The wire layout as one JSON document (`ipc/layout.json`): the ground truth that the C
//! header, the Python ctypes structures and numpy dtypes are tested against, so every
//! language checks itself against the same bytes rather than against a second hand-written
//! description.

use crate::handshake::{
    Hello, Welcome, INPUT_NAME_BYTES, MAX_JOINTS, MAX_REFERENCE_OFFSETS, MESSAGE_BYTES, NAME_BYTES,
    PROFILE_NAME_BYTES,
};
use crate::layout::{
    ActionHeader, BatchHeader, EnvHeader, Layout, COMMAND_END, COMMAND_STEP, ENV_ARRAYS,
    FLAG_ACTIVE, FLAG_PREVIOUS_TERMINATED, FLAG_RESET, MAGIC, REF_ARRAYS,
};
use std::fmt::Write;
use std::mem::{align_of, offset_of, size_of};

/// (field name, byte offset, byte size) of one struct.
type Fields = Vec<(&'static str, usize, usize)>;

macro_rules! fields {
    ($t:ty { $($f:ident : $ft:ty),* $(,)? }) => {
        vec![$((stringify!($f), offset_of!($t, $f), size_of::<$ft>())),*]
    };
}

fn structs() -> Vec<(&'static str, &'static str, usize, usize, Fields)> {
    vec![
        (
            "Hello",
            "thorarena::Hello",
            size_of::<Hello>(),
            align_of::<Hello>(),
            fields!(Hello {
                protocol_version: u32,
                n_joints: u32,
                joint_names_hash: u64,
                pid: u32,
                n_refs: u32,
                reference_offsets_s: [f64; MAX_REFERENCE_OFFSETS],
                name: [u8; NAME_BYTES],
                input: [u8; INPUT_NAME_BYTES],
                profile_kind: u32,
                profile_action_delay_steps: u32,
                profile_name: [u8; PROFILE_NAME_BYTES],
                profile_control_dt_s: f64,
                profile_physics_dt_s: f64,
                profile_action_clip: f64,
                profile_kp: [f64; MAX_JOINTS],
                profile_kd: [f64; MAX_JOINTS],
                profile_action_scale: [f64; MAX_JOINTS],
                profile_action_offset_rad: [f64; MAX_JOINTS],
            }),
        ),
        (
            "Welcome",
            "thorarena::Welcome",
            size_of::<Welcome>(),
            align_of::<Welcome>(),
            fields!(Welcome {
                protocol_version: u32,
                status: u32,
                n_joints: u32,
                n_envs: u32,
                joint_names_hash: u64,
                control_dt_s: f64,
                budget_s: f64,
                n_refs: u32,
                pid: u32,
                n_inputs: u32,
                reserved: u32,
                action_offset_rad: [f64; MAX_JOINTS],
                action_scale: [f64; MAX_JOINTS],
                message: [u8; MESSAGE_BYTES],
            }),
        ),
        (
            "BatchHeader",
            "",
            size_of::<BatchHeader>(),
            align_of::<BatchHeader>(),
            fields!(BatchHeader {
                magic: u32,
                protocol_version: u32,
                command: u32,
                n_envs: u32,
                n_joints: u32,
                n_refs: u32,
                env_stride: u32,
                n_inputs: u32,
                seq: u64,
                n_active: u32,
                reserved0: u32,
                reserved: [u64; 2],
            }),
        ),
        (
            "EnvHeader",
            "",
            size_of::<EnvHeader>(),
            align_of::<EnvHeader>(),
            fields!(EnvHeader {
                episode_id: u64,
                step: u64,
                flags: u32,
                reserved: u32,
                time_s: f64,
            }),
        ),
        (
            "ActionHeader",
            "",
            size_of::<ActionHeader>(),
            align_of::<ActionHeader>(),
            fields!(ActionHeader {
                magic: u32,
                protocol_version: u32,
                n_envs: u32,
                n_joints: u32,
                seq: u64,
                reserved: u64,
            }),
        ),
    ]
}

/// The layout document: protocol constants, the fixed structs (size, alignment, field
/// offsets), the array lists, and a worked example for the G1 (29 joints, 2 reference
/// frames, 2 environments, TWIST2's 1432 policy inputs) with every field's offset.
pub fn layout_json() -> String {
    let mut s = String::from("{\n");
    let _ = writeln!(s, "  \"protocol_version\": {},", crate::PROTOCOL_VERSION);
    let _ = writeln!(s, "  \"constants\": {{");
    let constants: [(&str, u64); 13] = [
        ("MAGIC", u64::from(MAGIC)),
        ("COMMAND_STEP", u64::from(COMMAND_STEP)),
        ("COMMAND_END", u64::from(COMMAND_END)),
        ("FLAG_ACTIVE", u64::from(FLAG_ACTIVE)),
        ("FLAG_RESET", u64::from(FLAG_RESET)),
        (
            "FLAG_PREVIOUS_TERMINATED",
            u64::from(FLAG_PREVIOUS_TERMINATED),
        ),
        ("MAX_JOINTS", MAX_JOINTS as u64),
        ("MAX_REFERENCE_OFFSETS", MAX_REFERENCE_OFFSETS as u64),
        ("NAME_BYTES", NAME_BYTES as u64),
        ("MESSAGE_BYTES", MESSAGE_BYTES as u64),
        ("INPUT_NAME_BYTES", INPUT_NAME_BYTES as u64),
        ("PROFILE_NAME_BYTES", PROFILE_NAME_BYTES as u64),
        ("WORD_BYTES", 8),
    ];
    for (i, (k, v)) in constants.iter().enumerate() {
        let comma = if i + 1 < constants.len() { "," } else { "" };
        let _ = writeln!(s, "    \"{k}\": {v}{comma}");
    }
    let _ = writeln!(s, "  }},");
    let _ = writeln!(s, "  \"structs\": {{");
    let all = structs();
    for (i, (name, type_name, size, align, fields)) in all.iter().enumerate() {
        let _ = writeln!(
            s,
            "    \"{name}\": {{\"type_name\": \"{type_name}\", \"size\": {size}, \"align\": {align}, \"fields\": ["
        );
        for (j, (f, off, sz)) in fields.iter().enumerate() {
            let comma = if j + 1 < fields.len() { "," } else { "" };
            let _ = writeln!(
                s,
                "      {{\"name\": \"{f}\", \"offset\": {off}, \"size\": {sz}}}{comma}"
            );
        }
        let comma = if i + 1 < all.len() { "," } else { "" };
        let _ = writeln!(s, "    ]}}{comma}");
    }
    let _ = writeln!(s, "  }},");
    for (key, arrays) in [
        ("env_arrays", &ENV_ARRAYS[..]),
        ("ref_arrays", &REF_ARRAYS[..]),
    ] {
        let _ = writeln!(s, "  \"{key}\": [");
        for (i, (name, fixed, per_joint)) in arrays.iter().enumerate() {
            let comma = if i + 1 < arrays.len() { "," } else { "" };
            let _ = writeln!(
                s,
                "    {{\"name\": \"{name}\", \"fixed\": {fixed}, \"per_joint\": {per_joint}}}{comma}"
            );
        }
        let _ = writeln!(s, "  ],");
    }
    let g1 = Layout {
        n_envs: 2,
        n_joints: 29,
        n_refs: 2,
        // TWIST2's network input, built by the simulator.
        n_inputs: 1432,
    };
    let _ = writeln!(s, "  \"example\": {{");
    let _ = writeln!(
        s,
        "    \"n_envs\": {}, \"n_joints\": {}, \"n_refs\": {}, \"n_inputs\": {},",
        g1.n_envs, g1.n_joints, g1.n_refs, g1.n_inputs
    );
    let _ = writeln!(
        s,
        "    \"ref_offset\": {}, \"ref_stride\": {}, \"env_stride\": {}, \"inputs_offset\": {}, \"inputs_bytes\": {}, \"obs_bytes\": {}, \"action_bytes\": {},",
        g1.ref_offset(),
        g1.ref_stride(),
        g1.env_stride(),
        g1.inputs_offset(),
        g1.inputs_bytes(),
        g1.obs_bytes(),
        g1.action_bytes()
    );
    let _ = writeln!(s, "    \"env_fields\": [");
    let fields = g1.env_fields();
    for (i, f) in fields.iter().enumerate() {
        let comma = if i + 1 < fields.len() { "," } else { "" };
        let _ = writeln!(
            s,
            "      {{\"name\": \"{}\", \"offset\": {}, \"len\": {}}}{comma}",
            f.name, f.offset, f.len
        );
    }
    let _ = writeln!(s, "    ]");
    let _ = writeln!(s, "  }}");
    s.push_str("}\n");
    s
}
