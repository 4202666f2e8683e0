"""BeyondMimic (Liao et al. 2025) tracking policies exported to ONNX with metadata: the
160-dim observation of the G1 tracking task, joint order and action mapping read from the
file.

Sources (the upstream HybridRobotics/whole_body_tracking is not in the index searchable
here; mjlab's port of the same task is):
- Observation terms, in order, of the policy group (`tracking_env_cfg.py`
  `ObservationsCfg.PolicyCfg`): `command` (reference joint_pos ++ joint_vel, 58),
  `motion_anchor_pos_b` (3), `motion_anchor_ori_b` (6), `base_lin_vel` (3), `base_ang_vel`
  (3), `joint_pos` (q - default, 29), `joint_vel` (qd, 29), `actions` (last action, 29).
  Read in the fork Kartikgar/whole_body_tracking at 4b96b4e02a73
  (`source/whole_body_tracking/whole_body_tracking/tasks/tracking/tracking_env_cfg.py`) and
  in mujocolab/mjlab at 789c775f3f3a (`src/mjlab/tasks/tracking/tracking_env_cfg.py`, where
  the two anchor terms are briefly named `motion_ref_pos_b` / `motion_ref_ori_b`).
- The terms themselves: mujocolab/mjlab at 0cc4de3a9a8b, `src/mjlab/tasks/tracking/mdp/
  observations.py` and `commands.py`: the anchor terms are the reference anchor body's
  pose in the robot anchor body's frame (`subtract_frame_transforms`), the orientation as
  the first two columns of its rotation matrix, row by row (`mat[..., :2].reshape(n, -1)`);
  `command` is the reference at the current step. The anchor body of the G1 task is
  `torso_link` (`config/g1/flat_env_cfg.py`, `anchor_body_name = "torso_link"`).
- Metadata keys (`attach_onnx_metadata`: xiaohu-art/whole_body_tracking at 4ae1759453ec,
  `source/whole_body_tracking/whole_body_tracking/utils/exporter.py`; the same keys in
  mujocolab/mjlab at 789c775f3f3a, `src/mjlab/tasks/tracking/rl/exporter.py`):
  `joint_names`, `joint_stiffness`, `joint_damping`, `default_joint_pos`, `action_scale`,
  `command_names`, `observation_names`, `run_path`; lists as comma-separated text with 3
  decimals, `action_scale` possibly one number. The exported model takes `obs` [1, 160] and
  `time_step` [1, 1] (fixed batch 1, so the adapter runs one row at a time) and returns
  `actions` [1, 29] first, then the motion it was trained on (ignored here: the benchmark's
  reference comes over the wire).

holosoma's exports (amazon-far/holosoma, `inference/policies/wbt.py`) carry `dof_names`,
`kp` and `kd` as JSON lists and no observation, default-pose or scale keys: their
observation is holosoma's `wbt` layout (154; `config_values/observation.py`, its terms in
alphabetical order of holosoma's names, see `HOLOSOMA_TERMS`), chosen
here by the network's input width when the file names no terms, and their default pose and
action scale are the session's (the `holosoma-wbt` profile's).

The policy's joint order (IsaacLab's breadth-first order, or mjlab's) is mapped to the
canonical order by name, both ways. Actions: the policy means target = default_joint_pos +
action_scale · action (its own numbers, in its order); the adapter writes the raw action
that gives exactly that target under the session's mapping, (target - offset) / scale, and
inverts the same mapping to recover the policy's last action from the wire's `last_action`.
With the `beyondmimic` profile the two mappings agree to the metadata's 3 decimals.

`base_lin_vel` / `base_ang_vel` are the wire's root (pelvis frame origin) velocities in the
pelvis frame; IsaacLab's and mjlab's terms read the root link's, the same up to where the
velocity is taken on the pelvis (assumed equal here). `joint_vel` is qd (the default joint
velocity is 0).

The torso anchor is computed from the root (pelvis) pose and the waist joints with the G1's
kinematics (`data/robots/g1_29dof/g1_29dof.urdf`: waist_yaw about z at the pelvis origin,
waist_roll about x at (-0.0039635, 0, 0.044), waist_pitch about y at the same point), for
the robot from q and for the reference from its joint positions. An `anchor_body_name`
metadata key, when present, may also name `pelvis`.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from .base import Adapter, canonical_indices
from .rotations import rotation_about, world_from_body
from .runtime import OnnxPolicy, Policy

WAIST_YAW, WAIST_ROLL, WAIST_PITCH = 12, 13, 14
"""Canonical indices of the waist joints."""
WAIST_ROLL_ORIGIN = np.array([-0.0039635, 0.0, 0.044])
"""waist_roll_joint's origin in waist_yaw_link (= pelvis position at yaw 0), m."""
DEFAULT_TERMS = (
    "command",
    "motion_anchor_pos_b",
    "motion_anchor_ori_b",
    "base_lin_vel",
    "base_ang_vel",
    "joint_pos",
    "joint_vel",
    "actions",
)
"""The G1 tracking task's policy observation, in order (160 for 29 joints)."""
HOLOSOMA_TERMS = (
    "actions",
    "base_ang_vel",
    "joint_pos",
    "joint_vel",
    "command",
    "motion_anchor_ori_b",
)
"""holosoma's `wbt` observation (154 for 29 joints): its terms `actions`, `base_ang_vel`,
`dof_pos`, `dof_vel`, `motion_command`, `motion_ref_ori_b` in alphabetical order of those
names, as holosoma concatenates every observation group."""
MJLAB_NO_STATE_ESTIMATION_TERMS = (
    "command",
    "motion_anchor_ori_b",
    "base_ang_vel",
    "joint_pos",
    "joint_vel",
    "actions",
)
"""mjlab's G1 tracking observation without state estimation (154 for 29 joints): the
160-term layout less `motion_anchor_pos_b` and `base_lin_vel`, in the same order."""
KNOWN_LAYOUTS = {
    "mjlab / whole_body_tracking": DEFAULT_TERMS,
    "holosoma wbt (terms sorted by name)": HOLOSOMA_TERMS,
    "mjlab without state estimation": MJLAB_NO_STATE_ESTIMATION_TERMS,
}
"""Every layout a network without `observation_names` may have; two are 154 wide, so a
width alone never picks one."""
TERM_ALIASES = {
    "motion_ref_pos_b": "motion_anchor_pos_b",
    "motion_ref_ori_b": "motion_anchor_ori_b",
    "motion_command": "command",
    "dof_pos": "joint_pos",
    "dof_vel": "joint_vel",
}
ANCHOR_BODIES = ("torso_link", "pelvis")


def known_layout_of_width(width: int | None, sizes: Mapping[str, int]) -> tuple[str, ...]:
    """The one known layout `width` inputs wide; none or several is an error naming them
    (two layouts of one width order the same numbers differently, and a network fed the
    other still runs)."""
    fits = {
        name: terms
        for name, terms in KNOWN_LAYOUTS.items()
        if sum(sizes[t] for t in terms) == width
    }
    if len(fits) == 1:
        return next(iter(fits.values()))
    if not fits:
        widths = {name: sum(sizes[t] for t in terms) for name, terms in KNOWN_LAYOUTS.items()}
        raise ValueError(
            f"no observation_names in the metadata and no known layout is {width} inputs wide "
            f"({widths})"
        )
    listed = "; ".join(f"{name}: [{', '.join(terms)}]" for name, terms in fits.items())
    raise ValueError(
        f"no observation_names in the metadata, and its input width {width} fits "
        f"{len(fits)} known layouts that order the inputs differently — {listed}; "
        "name the terms in order (observation_names)"
    )


def term_sizes(n_joints: int) -> dict[str, int]:
    """Width of each observation term the adapter can build, for `n_joints` joints."""
    n = n_joints
    return {
        "command": 2 * n,
        "motion_anchor_pos_b": 3,
        "motion_anchor_ori_b": 6,
        "base_lin_vel": 3,
        "base_ang_vel": 3,
        "joint_pos": n,
        "joint_vel": n,
        "actions": n,
    }


def _items(text: str) -> list[str]:
    """A metadata value as a list: a JSON array (holosoma), else comma-separated text."""
    try:
        value = json.loads(text)
    except ValueError:
        value = None
    if isinstance(value, list):
        return [v if isinstance(v, str) else json.dumps(v) for v in value]
    return [v.strip() for v in text.split(",") if v.strip()]


def _floats(text: str) -> np.ndarray:
    return np.array([float(v) for v in _items(text)], dtype=np.float64)


def _names(text: str) -> tuple[str, ...]:
    return tuple(_items(text))


@dataclass(frozen=True, kw_only=True)
class BeyondMimicMetadata:
    """What the adapter needs from the ONNX file's metadata, in the policy's joint order."""

    joint_names: tuple[str, ...]
    """The policy's joint order."""
    default_joint_pos: np.ndarray | None = None
    """rad, the action offset and the zero of the `joint_pos` term (None: the session's)."""
    action_scale: np.ndarray | None = None
    """rad per unit action (None: the session's)."""
    joint_stiffness: np.ndarray | None = None
    """kp the policy was trained with, N·m/rad (the simulator's profile sets the real one)."""
    joint_damping: np.ndarray | None = None
    """kd, N·m·s/rad."""
    observation_names: tuple[str, ...] | None = DEFAULT_TERMS
    """Observation terms in order (None: the known layout of the network's input width)."""
    anchor_body_name: str = "torso_link"

    @classmethod
    def from_onnx(cls, metadata: Mapping[str, str]) -> BeyondMimicMetadata:
        """Reads the keys `attach_onnx_metadata` (mjlab, whole_body_tracking) or holosoma
        write; the joint order (`joint_names` or `dof_names`) is required."""
        names_key = next((k for k in ("joint_names", "dof_names") if k in metadata), None)
        if names_key is None:
            raise ValueError(
                "not a BeyondMimic export: metadata lacks joint_names / dof_names "
                f"(has {sorted(metadata)})"
            )
        names = _names(metadata[names_key])
        n = len(names)

        def optional(*keys: str) -> np.ndarray | None:
            key = next((k for k in keys if k in metadata), None)
            return _floats(metadata[key]) if key is not None else None

        scale = optional("action_scale")
        if scale is not None and len(scale) == 1:
            scale = np.full(n, scale[0])
        terms = (
            tuple(TERM_ALIASES.get(t, t) for t in _names(metadata["observation_names"]))
            if "observation_names" in metadata
            else None
        )
        anchor = metadata.get("anchor_body_name", "torso_link")
        with contextlib.suppress(ValueError):
            anchor = str(json.loads(anchor))
        return cls(
            joint_names=names,
            default_joint_pos=optional("default_joint_pos"),
            action_scale=scale,
            joint_stiffness=optional("joint_stiffness", "kp"),
            joint_damping=optional("joint_damping", "kd"),
            observation_names=terms,
            anchor_body_name=anchor,
        )


def anchor_pose(
    anchor_body: str, root_pos: np.ndarray, root_quat_wxyz: np.ndarray, joint_pos: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """World position (n, 3) and rotation matrix (n, 3, 3) of the anchor body, from the root
    pose and the canonical joint positions."""
    world_from_root = world_from_body(root_quat_wxyz)
    if anchor_body == "pelvis":
        return root_pos, world_from_root
    world_from_yaw = world_from_root @ rotation_about("z", joint_pos[:, WAIST_YAW])
    pos = root_pos + world_from_yaw @ WAIST_ROLL_ORIGIN
    world_from_torso = (
        world_from_yaw
        @ rotation_about("x", joint_pos[:, WAIST_ROLL])
        @ rotation_about("y", joint_pos[:, WAIST_PITCH])
    )
    return pos, world_from_torso


class BeyondMimicAdapter(Adapter):
    """A BeyondMimic-style tracking policy; everything policy-specific from its metadata."""

    name: ClassVar[str] = "beyondmimic"
    profile = "beyondmimic"
    reference_offsets_s: ClassVar[tuple[float, ...]] = (0.0,)

    def __init__(self, policy: Policy | None, metadata: BeyondMimicMetadata | None = None) -> None:
        super().__init__(policy)
        if metadata is None:
            if not isinstance(policy, OnnxPolicy):
                raise ValueError("without an ONNX policy, pass the metadata explicitly")
            metadata = BeyondMimicMetadata.from_onnx(policy.metadata)
        n = len(self.joint_names)
        if len(metadata.joint_names) != n:
            raise ValueError(f"the policy has {len(metadata.joint_names)} joints, the G1 has {n}")
        for key in ("default_joint_pos", "action_scale"):
            value = getattr(metadata, key)
            if value is not None and value.shape != (n,):
                raise ValueError(f"metadata {key} has {len(value)} entries, not {n}")
        if metadata.anchor_body_name not in ANCHOR_BODIES:
            raise ValueError(
                f"anchor body {metadata.anchor_body_name!r}: the adapter knows {ANCHOR_BODIES}"
            )
        self.metadata = metadata
        self.to_canonical = canonical_indices(metadata.joint_names)
        """Canonical index of each policy joint: `canonical[:, to_canonical]` is in policy order."""
        sizes = term_sizes(n)
        terms = metadata.observation_names
        if terms is None:
            width = policy.input_dim if policy is not None else None
            terms = known_layout_of_width(width, sizes)
        unknown = [t for t in terms if t not in sizes]
        if unknown:
            raise ValueError(f"observation terms the adapter cannot build: {unknown}")
        self.terms: tuple[str, ...] = terms
        """Observation terms in order."""
        self.obs_dim = sum(sizes[t] for t in terms)

    @classmethod
    def from_onnx(
        cls,
        path: str | os.PathLike[str],
        *,
        intra_op_threads: int = 1,
        observation_names: Sequence[str] | None = None,
    ) -> BeyondMimicAdapter:
        """The adapter for an exported ONNX file, metadata included; `observation_names`
        names the terms of a file that does not (holosoma's exports: the
        `[beyondmimic] observation_names` of the simulator's profile)."""
        policy = OnnxPolicy(path, intra_op_threads=intra_op_threads)
        metadata = BeyondMimicMetadata.from_onnx(policy.metadata)
        if observation_names is not None:
            metadata = dataclasses.replace(
                metadata,
                observation_names=tuple(TERM_ALIASES.get(t, t) for t in observation_names),
            )
        return cls(policy, metadata)

    def canonical(self, policy_order: np.ndarray) -> np.ndarray:
        """A per-joint array (last axis) from the policy's order into the canonical order."""
        out = np.empty_like(policy_order)
        out[..., self.to_canonical] = policy_order
        return out

    def default_joint_pos(self) -> np.ndarray:
        """The policy's default pose, its order: the metadata's, else the session's offset."""
        if self.metadata.default_joint_pos is not None:
            return self.metadata.default_joint_pos
        return np.asarray(self.action_offset_rad[self.to_canonical], dtype=np.float64)

    def policy_action_scale(self) -> np.ndarray:
        """The policy's action scale, its order: the metadata's, else the session's."""
        if self.metadata.action_scale is not None:
            return self.metadata.action_scale
        return np.asarray(self.action_scale[self.to_canonical], dtype=np.float64)

    def mapping_mismatch(self) -> float:
        """Largest difference, rad, between the target the policy means and the one the
        session's mapping gives the same action, over actions in [-1, 1]: how far the
        session's profile is from the metadata (0 when they agree)."""
        offset = self.canonical(self.default_joint_pos())
        scale = self.canonical(self.policy_action_scale())
        return float(
            np.max(np.abs(offset - self.action_offset_rad) + np.abs(scale - self.action_scale))
        )

    def observe(self, records: np.ndarray, slots: np.ndarray) -> np.ndarray:
        p = self.to_canonical
        default = self.default_joint_pos()
        ref = records["reference"][:, 0]
        target = self.action_offset_rad + self.action_scale * records["last_action"]
        last_action = (target[:, p] - default) / self.policy_action_scale()
        last_action[records["step"] == 0] = 0.0  # exactly 0, as in training, at a start
        terms = {
            "command": np.concatenate([ref["joint_pos"][:, p], ref["joint_vel"][:, p]], axis=1),
            "base_lin_vel": records["root_lin_vel_b"],
            "base_ang_vel": records["root_ang_vel_b"],
            "joint_pos": records["q"][:, p] - default,
            "joint_vel": records["qd"][:, p],
            "actions": last_action,
        }
        names = self.terms
        if "motion_anchor_pos_b" in names or "motion_anchor_ori_b" in names:
            pos_b, rot_b = self.reference_anchor_in_robot_anchor(records)
            terms["motion_anchor_pos_b"] = pos_b
            terms["motion_anchor_ori_b"] = rot_b[..., :2].reshape(len(records), 6)
        return np.concatenate([terms[t] for t in names], axis=1).astype(np.float32)

    def reference_anchor_in_robot_anchor(
        self, records: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """The reference anchor body's position (n, 3) and rotation (n, 3, 3) in the robot
        anchor body's frame (`subtract_frame_transforms(robot, reference)`)."""
        body = self.metadata.anchor_body_name
        ref = records["reference"][:, 0]
        robot_pos, world_from_robot = anchor_pose(
            body, records["root_pos_w"], records["root_quat_wxyz"], records["q"]
        )
        ref_pos, world_from_ref = anchor_pose(
            body, ref["root_pos_w"], ref["root_quat_wxyz"], ref["joint_pos"]
        )
        robot_from_world = np.swapaxes(world_from_robot, -1, -2)
        pos_b = (robot_from_world @ (ref_pos - robot_pos)[..., None])[..., 0]
        return pos_b, robot_from_world @ world_from_ref

    def actions_from_outputs(self, outputs: np.ndarray, records: np.ndarray) -> np.ndarray:
        target = self.canonical(self.default_joint_pos() + self.policy_action_scale() * outputs)
        return (target - self.action_offset_rad) / self.action_scale
