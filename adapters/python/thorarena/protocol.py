"""The ThorArena wire protocol in Python: handshake messages, constants and the batch layout.

Everything here mirrors crate `thorarena-ipc` of this repository (`ipc/src/handshake.rs`,
`ipc/src/layout.rs`; protocol version 2). `ipc/layout.json`, generated
from the Rust types, is the ground truth that `tests/test_protocol.py` checks these
definitions against, byte for byte.

Layout of one control step (native-endian, 8-byte aligned, no padding)::

    observation batch = BatchHeader (64 B) + n_envs x env block (env_stride B)
                        + policy inputs: n_envs x n_inputs f32, row-major, padded to 8 B
    env block         = EnvHeader (32 B)
                        + root_pos_w 3, root_quat_wxyz 4, root_lin_vel_w 3, root_ang_vel_w 3,
                          root_lin_vel_b 3, root_ang_vel_b 3, projected_gravity_b 3   (f64)
                        + q n, qd n, last_action n                                    (f64)
                        + n_refs x reference frame
    reference frame   = time_s 1, root_pos_w 3, root_quat_wxyz 4, root_lin_vel_w 3,
                        root_ang_vel_w 3, joint_pos n, joint_vel n                    (f64)
    action batch      = ActionHeader (32 B) + n_envs x n f64 (raw actions, canonical order)

Quaternions are (w, x, y, z); `_w` is the world frame, `_b` the root (base) frame.
The policy-input block holds a network input the simulator builds when the policy asks
for one by name in its hello (`connect(..., input="twist2")`); `n_inputs` is 0 otherwise.
"""

from __future__ import annotations

import ctypes
import enum
import struct
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np

PROTOCOL_VERSION = 4
"""Version of the wire protocol (`thorarena_ipc::PROTOCOL_VERSION`)."""

MAGIC = 0x524F_4854
"""First word of every batch: "THOR" in ASCII."""
COMMAND_STEP = 0
"""`BatchHeader.command`: a control step; the policy must answer."""
COMMAND_END = 1
"""`BatchHeader.command`: the run is over; no answer expected."""

FLAG_ACTIVE = 1
"""`EnvHeader.flags`: the slot carries a live episode (inactive slots are padding)."""
FLAG_RESET = 2
"""`EnvHeader.flags`: first observation of a new episode (clear any history)."""
FLAG_PREVIOUS_TERMINATED = 4
"""`EnvHeader.flags`: the slot's previous episode ended early."""

MAX_JOINTS = 64
"""Most joints on the wire (the action mapping in `Welcome` is fixed-size)."""
MAX_REFERENCE_OFFSETS = 64
"""Most reference frames a policy may ask for."""
NAME_BYTES = 64
"""Bytes of the policy name in `Hello` (NUL-padded UTF-8)."""
MESSAGE_BYTES = 256
"""Bytes of the refusal message in `Welcome` (NUL-padded UTF-8)."""
INPUT_NAME_BYTES = 32
"""Bytes of the policy-input name in `Hello` (NUL-padded UTF-8)."""
PROFILE_NAME_BYTES = 32
"""Bytes of a declared profile's name in `Hello` (NUL-padded UTF-8)."""
WORD_BYTES = 8
"""Batches travel as iceoryx2 slices of u64 words."""

BATCH_HEADER_BYTES = 64
ENV_HEADER_BYTES = 32
ACTION_HEADER_BYTES = 32

G1_JOINT_NAMES: tuple[str, ...] = (
    "left_hip_pitch_joint",
    "left_hip_roll_joint",
    "left_hip_yaw_joint",
    "left_knee_joint",
    "left_ankle_pitch_joint",
    "left_ankle_roll_joint",
    "right_hip_pitch_joint",
    "right_hip_roll_joint",
    "right_hip_yaw_joint",
    "right_knee_joint",
    "right_ankle_pitch_joint",
    "right_ankle_roll_joint",
    "waist_yaw_joint",
    "waist_roll_joint",
    "waist_pitch_joint",
    "left_shoulder_pitch_joint",
    "left_shoulder_roll_joint",
    "left_shoulder_yaw_joint",
    "left_elbow_joint",
    "left_wrist_roll_joint",
    "left_wrist_pitch_joint",
    "left_wrist_yaw_joint",
    "right_shoulder_pitch_joint",
    "right_shoulder_roll_joint",
    "right_shoulder_yaw_joint",
    "right_elbow_joint",
    "right_wrist_roll_joint",
    "right_wrist_pitch_joint",
    "right_wrist_yaw_joint",
)
"""The Unitree G1 (29 DoF) in canonical order: `data/robots/g1_29dof/robot.toml` `joints`."""


class Status(enum.IntEnum):
    """`Welcome.status` (`thorarena_ipc::Status`)."""

    OK = 0
    PROTOCOL_VERSION = 1
    JOINT_COUNT = 2
    JOINT_NAMES = 3
    REFERENCE_OFFSETS = 4
    BUSY = 5
    REJECTED = 6
    INPUT = 7
    PROFILE = 8


class ProfileKind(enum.IntEnum):
    """`Hello.profile_kind` (`thorarena_ipc::ProfileKind`)."""

    NONE = 0
    NAMED = 1
    CONTENT = 2


@dataclass(frozen=True)
class Profile:
    """A dynamics profile by its numbers: what a policy declares it was trained under.

    Every per-joint sequence holds one value per joint in the robot's canonical order
    (`G1_JOINT_NAMES`). The simulator checks the numbers as it checks a profile file
    (`data/profiles/*.toml`); torque limits are the robot's. Declare a bundled profile
    by its name instead (`connect(..., profile="wbc-mjlab")`).
    """

    name: str
    control_dt_s: float
    physics_dt_s: float
    kp: Sequence[float]
    kd: Sequence[float]
    action_scale: Sequence[float]
    action_offset_rad: Sequence[float]
    action_delay_steps: int = 0
    action_clip: float | None = None


def declare_profile(hello: Any, profile: str | Profile | None, n_joints: int) -> None:
    """Writes the declaration `profile` (a bundled profile's name, the numbers, or None)
    into `hello` (`DeclaredProfile::write_into`); raises ValueError when it does not fit."""
    if profile is None:
        hello.profile_kind = ProfileKind.NONE
        return
    name = profile if isinstance(profile, str) else profile.name
    raw = name.encode("utf-8")
    if not raw or len(raw) >= PROFILE_NAME_BYTES:
        raise ValueError(f"profile name {name!r}: give 1 to {PROFILE_NAME_BYTES - 1} bytes")
    ctypes.memmove(hello.profile_name, to_fixed(name, PROFILE_NAME_BYTES), PROFILE_NAME_BYTES)
    if isinstance(profile, str):
        hello.profile_kind = ProfileKind.NAMED
        return
    for field in ("kp", "kd", "action_scale", "action_offset_rad"):
        values = [float(v) for v in getattr(profile, field)]
        if len(values) != n_joints:
            raise ValueError(
                f"profile {name!r}: {field} has {len(values)} values for {n_joints} joints"
            )
        getattr(hello, f"profile_{field}")[:n_joints] = values
    hello.profile_kind = ProfileKind.CONTENT
    hello.profile_control_dt_s = float(profile.control_dt_s)
    hello.profile_physics_dt_s = float(profile.physics_dt_s)
    hello.profile_action_delay_steps = int(profile.action_delay_steps)
    hello.profile_action_clip = float(profile.action_clip or 0.0)


class Hello(ctypes.Structure):
    """What the policy sends to join a session (`thorarena_ipc::Hello`)."""

    _fields_ = [
        ("protocol_version", ctypes.c_uint32),
        ("n_joints", ctypes.c_uint32),
        ("joint_names_hash", ctypes.c_uint64),
        ("pid", ctypes.c_uint32),
        ("n_refs", ctypes.c_uint32),
        ("reference_offsets_s", ctypes.c_double * MAX_REFERENCE_OFFSETS),
        ("name", ctypes.c_uint8 * NAME_BYTES),
        ("input", ctypes.c_uint8 * INPUT_NAME_BYTES),
        ("profile_kind", ctypes.c_uint32),
        ("profile_action_delay_steps", ctypes.c_uint32),
        ("profile_name", ctypes.c_uint8 * PROFILE_NAME_BYTES),
        ("profile_control_dt_s", ctypes.c_double),
        ("profile_physics_dt_s", ctypes.c_double),
        ("profile_action_clip", ctypes.c_double),
        ("profile_kp", ctypes.c_double * MAX_JOINTS),
        ("profile_kd", ctypes.c_double * MAX_JOINTS),
        ("profile_action_scale", ctypes.c_double * MAX_JOINTS),
        ("profile_action_offset_rad", ctypes.c_double * MAX_JOINTS),
    ]

    @staticmethod
    def type_name() -> str:
        """The iceoryx2 type name, the same as the Rust `#[type_name]`."""
        return "thorarena::Hello"


class Welcome(ctypes.Structure):
    """The simulator's answer (`thorarena_ipc::Welcome`)."""

    _fields_ = [
        ("protocol_version", ctypes.c_uint32),
        ("status", ctypes.c_uint32),
        ("n_joints", ctypes.c_uint32),
        ("n_envs", ctypes.c_uint32),
        ("joint_names_hash", ctypes.c_uint64),
        ("control_dt_s", ctypes.c_double),
        ("budget_s", ctypes.c_double),
        ("n_refs", ctypes.c_uint32),
        ("pid", ctypes.c_uint32),
        ("n_inputs", ctypes.c_uint32),
        ("reserved", ctypes.c_uint32),
        ("action_offset_rad", ctypes.c_double * MAX_JOINTS),
        ("action_scale", ctypes.c_double * MAX_JOINTS),
        ("message", ctypes.c_uint8 * MESSAGE_BYTES),
    ]

    @staticmethod
    def type_name() -> str:
        """The iceoryx2 type name, the same as the Rust `#[type_name]`."""
        return "thorarena::Welcome"


def to_fixed(text: str, size: int) -> bytes:
    """`text` as NUL-padded UTF-8 of `size` bytes, cut at a character boundary (`to_fixed`)."""
    raw = text.encode("utf-8")[: size - 1]
    while raw:
        try:
            raw.decode("utf-8")
            break
        except UnicodeDecodeError:
            raw = raw[:-1]
    return raw.ljust(size, b"\0")


def from_fixed(raw: Iterable[int]) -> str:
    """The string in a NUL-padded fixed buffer (`from_fixed`)."""
    data = bytes(raw)
    end = data.find(b"\0")
    return data[: end if end >= 0 else len(data)].decode("utf-8", errors="replace")


_FNV_OFFSET = 0xCBF2_9CE4_8422_2325
_FNV_PRIME = 0x0000_0100_0000_01B3
_U64 = (1 << 64) - 1


def joint_names_hash(names: Iterable[str]) -> int:
    """FNV-1a (64 bit) of the joint names joined by `\\n` (`thorarena_ipc::joint_names_hash`)."""
    h = _FNV_OFFSET
    for byte in "\n".join(names).encode("utf-8"):
        h = ((h ^ byte) * _FNV_PRIME) & _U64
    return h


# Wire order of the f64 arrays: (name, fixed length, length per joint); `ENV_ARRAYS` and
# `REF_ARRAYS` of `ipc/src/layout.rs`.
ENV_ARRAYS: tuple[tuple[str, int, int], ...] = (
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
)
REF_ARRAYS: tuple[tuple[str, int, int], ...] = (
    ("time_s", 1, 0),
    ("root_pos_w", 3, 0),
    ("root_quat_wxyz", 4, 0),
    ("root_lin_vel_w", 3, 0),
    ("root_ang_vel_w", 3, 0),
    ("joint_pos", 0, 1),
    ("joint_vel", 0, 1),
)


class BatchHeader(ctypes.Structure):
    """Head of an observation batch (`thorarena_ipc::BatchHeader`, 64 B)."""

    _fields_ = [
        ("magic", ctypes.c_uint32),
        ("protocol_version", ctypes.c_uint32),
        ("command", ctypes.c_uint32),
        ("n_envs", ctypes.c_uint32),
        ("n_joints", ctypes.c_uint32),
        ("n_refs", ctypes.c_uint32),
        ("env_stride", ctypes.c_uint32),
        ("n_inputs", ctypes.c_uint32),
        ("seq", ctypes.c_uint64),
        ("n_active", ctypes.c_uint32),
        ("reserved0", ctypes.c_uint32),
        ("reserved", ctypes.c_uint64 * 2),
    ]


BATCH_HEADER_WORDS = struct.Struct("<8IQI")
"""`BatchHeader` from `magic` to `n_active` as one struct: a client reads every batch's
header in one call (`unpack_from` on the shared memory) instead of a field at a time."""


class EnvHeader(ctypes.Structure):
    """Head of one environment block (`thorarena_ipc::EnvHeader`, 32 B)."""

    _fields_ = [
        ("episode_id", ctypes.c_uint64),
        ("step", ctypes.c_uint64),
        ("flags", ctypes.c_uint32),
        ("reserved", ctypes.c_uint32),
        ("time_s", ctypes.c_double),
    ]


class ActionHeader(ctypes.Structure):
    """Head of an action batch (`thorarena_ipc::ActionHeader`, 32 B)."""

    _fields_ = [
        ("magic", ctypes.c_uint32),
        ("protocol_version", ctypes.c_uint32),
        ("n_envs", ctypes.c_uint32),
        ("n_joints", ctypes.c_uint32),
        ("seq", ctypes.c_uint64),
        ("reserved", ctypes.c_uint64),
    ]


def _dtype_of(structure: type[ctypes.Structure]) -> np.dtype:
    """The numpy dtype of a ctypes structure of integers, floats and their arrays."""
    dtype = np.dtype(structure)
    assert dtype.itemsize == ctypes.sizeof(structure)
    return dtype


BATCH_HEADER_DTYPE = _dtype_of(BatchHeader)
"""`BatchHeader` as a numpy dtype."""
ENV_HEADER_DTYPE = _dtype_of(EnvHeader)
"""`EnvHeader` as a numpy dtype (the first fields of `Layout.env_dtype`)."""
ACTION_HEADER_DTYPE = _dtype_of(ActionHeader)
"""`ActionHeader` as a numpy dtype."""


def _f64_fields(arrays: Sequence[tuple[str, int, int]], n_joints: int) -> list[tuple[Any, ...]]:
    fields: list[tuple[Any, ...]] = []
    for name, fixed, per_joint in arrays:
        length = fixed + per_joint * n_joints
        # A one-element array (a reference frame's `time_s`) reads as a scalar.
        fields.append((name, "=f8") if length == 1 and per_joint == 0 else (name, "=f8", (length,)))
    return fields


@dataclass(frozen=True, kw_only=True)
class Field:
    """One named `f64` field of an environment block (as in `layout.json`)."""

    name: str
    """Field name; reference fields read `reference[i].<name>`."""
    offset: int
    """Byte offset from the start of the environment block."""
    len: int
    """Number of f64 elements."""


@dataclass(frozen=True, kw_only=True)
class Layout:
    """Sizes and offsets of a session's batches (`thorarena_ipc::Layout`)."""

    n_envs: int
    """Environment slots per batch."""
    n_joints: int
    """Joints per environment."""
    n_refs: int
    """Reference frames per environment."""
    n_inputs: int = 0
    """float32 values per environment in the policy-input block (0: none)."""

    @cached_property
    def ref_stride(self) -> int:
        """Bytes of one reference frame."""
        return 8 * sum(fixed + per * self.n_joints for _, fixed, per in REF_ARRAYS)

    @cached_property
    def ref_offset(self) -> int:
        """Byte offset of the first reference frame within an environment block."""
        return ENV_HEADER_BYTES + 8 * sum(
            fixed + per * self.n_joints for _, fixed, per in ENV_ARRAYS
        )

    @cached_property
    def env_stride(self) -> int:
        """Bytes of one environment block."""
        return self.ref_offset + self.n_refs * self.ref_stride

    @cached_property
    def inputs_offset(self) -> int:
        """Byte offset of the policy-input block within an observation batch."""
        return BATCH_HEADER_BYTES + self.n_envs * self.env_stride

    @cached_property
    def inputs_bytes(self) -> int:
        """Bytes of the policy-input block, padding to 8 bytes included."""
        return -(-4 * self.n_envs * self.n_inputs // 8) * 8

    @cached_property
    def obs_bytes(self) -> int:
        """Bytes of an observation batch."""
        return self.inputs_offset + self.inputs_bytes

    @cached_property
    def action_bytes(self) -> int:
        """Bytes of an action batch."""
        return ACTION_HEADER_BYTES + self.n_envs * self.n_joints * 8

    @cached_property
    def obs_words(self) -> int:
        """u64 words of an observation batch (the iceoryx2 slice length)."""
        return self.obs_bytes // WORD_BYTES

    @cached_property
    def action_words(self) -> int:
        """u64 words of an action batch."""
        return self.action_bytes // WORD_BYTES

    @cached_property
    def ref_dtype(self) -> np.dtype:
        """One reference frame as a numpy structured dtype."""
        dtype = np.dtype(_f64_fields(REF_ARRAYS, self.n_joints))
        assert dtype.itemsize == self.ref_stride
        return dtype

    @cached_property
    def env_dtype(self) -> np.dtype:
        """One environment block as a numpy structured dtype: the `EnvHeader` fields, the
        named f64 arrays, and `reference`, `n_refs` frames of `ref_dtype`."""
        assert ENV_HEADER_DTYPE.fields is not None
        header = [(name, sub[0]) for name, sub in ENV_HEADER_DTYPE.fields.items()]
        fields = header + _f64_fields(ENV_ARRAYS, self.n_joints)
        fields.append(("reference", self.ref_dtype, (self.n_refs,)))
        dtype = np.dtype(fields)
        assert dtype.itemsize == self.env_stride
        return dtype

    def env_fields(self) -> list[Field]:
        """Every f64 field of an environment block, in wire order (`Layout::env_fields`)."""
        fields: list[Field] = []
        offset = ENV_HEADER_BYTES
        frames = [("", ENV_ARRAYS)] + [(f"reference[{i}].", REF_ARRAYS) for i in range(self.n_refs)]
        for prefix, arrays in frames:
            for name, fixed, per in arrays:
                length = fixed + per * self.n_joints
                fields.append(Field(name=prefix + name, offset=offset, len=length))
                offset += 8 * length
        return fields

    def obs_view(self, buffer: Any) -> np.ndarray:
        """The `n_envs` environment blocks of an observation batch, zero-copy, read-only."""
        view = np.frombuffer(
            buffer, dtype=self.env_dtype, count=self.n_envs, offset=BATCH_HEADER_BYTES
        )
        view.flags.writeable = False
        return view

    def inputs_view(self, buffer: Any) -> np.ndarray:
        """The policy-input block of an observation batch, zero-copy, read-only, float32
        of shape (n_envs, n_inputs): the tensor the network takes."""
        flat = np.frombuffer(
            buffer, dtype="=f4", count=self.n_envs * self.n_inputs, offset=self.inputs_offset
        )
        flat.flags.writeable = False
        return flat.reshape(self.n_envs, self.n_inputs)

    def action_view(self, buffer: Any) -> np.ndarray:
        """The actions of an action batch, zero-copy, writable, shape (n_envs, n_joints)."""
        flat = np.frombuffer(
            buffer, dtype="=f8", count=self.n_envs * self.n_joints, offset=ACTION_HEADER_BYTES
        )
        return flat.reshape(self.n_envs, self.n_joints)

    @cached_property
    def batch_shape(self) -> tuple[int, ...]:
        """`(n_envs, n_joints, n_refs, env_stride, n_inputs)` in the batch header's order
        (`BATCH_HEADER_WORDS` fields 3 to 7)."""
        return (self.n_envs, self.n_joints, self.n_refs, self.env_stride, self.n_inputs)

    def check_batch_header(self, header: BatchHeader) -> str | None:
        """Why `header` does not belong to this layout, or None when it does."""
        if header.magic != MAGIC:
            return f"bad magic word {header.magic:#x}: not a ThorArena batch"
        for what, got, want in (
            ("n_envs", header.n_envs, self.n_envs),
            ("n_joints", header.n_joints, self.n_joints),
            ("n_refs", header.n_refs, self.n_refs),
            ("n_inputs", header.n_inputs, self.n_inputs),
            ("env_stride", header.env_stride, self.env_stride),
        ):
            if got != want:
                return f"batch header says {what} = {got}, the session has {want}"
        return None
