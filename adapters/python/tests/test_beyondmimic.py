"""The BeyondMimic adapter reads joint order, default pose and action scale from the export's
metadata, maps IsaacLab's joint order to the canonical one both ways, builds the 160-dim
observation (command, torso anchor pose in the robot's torso frame, base velocities, joint
terms, last action in the policy's own units) and writes raw actions that give exactly the
policy's targets under the session's mapping. A tiny ONNX export with metadata, made in the
test (skipped without the `onnx` package or onnxruntime), checks the file path end to end."""

from __future__ import annotations

import dataclasses
import importlib.util
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import thorarena as ta
from thorarena.adapters import BeyondMimicAdapter, BeyondMimicMetadata, canonical_indices
from thorarena.adapters.beyondmimic import DEFAULT_TERMS, HOLOSOMA_TERMS, WAIST_ROLL_ORIGIN

ISAACLAB_ORDER = [
    "left_hip_pitch_joint",
    "right_hip_pitch_joint",
    "waist_yaw_joint",
    "left_hip_roll_joint",
    "right_hip_roll_joint",
    "waist_roll_joint",
    "left_hip_yaw_joint",
    "right_hip_yaw_joint",
    "waist_pitch_joint",
    "left_knee_joint",
    "right_knee_joint",
    "left_shoulder_pitch_joint",
    "right_shoulder_pitch_joint",
    "left_ankle_pitch_joint",
    "right_ankle_pitch_joint",
    "left_shoulder_roll_joint",
    "right_shoulder_roll_joint",
    "left_ankle_roll_joint",
    "right_ankle_roll_joint",
    "left_shoulder_yaw_joint",
    "right_shoulder_yaw_joint",
    "left_elbow_joint",
    "right_elbow_joint",
    "left_wrist_roll_joint",
    "right_wrist_roll_joint",
    "left_wrist_pitch_joint",
    "right_wrist_pitch_joint",
    "left_wrist_yaw_joint",
    "right_wrist_yaw_joint",
]
"""The G1 in IsaacLab's breadth-first order, as BeyondMimic's exports list it."""
PERM = canonical_indices(ISAACLAB_ORDER)
BM_DEFAULT = {"hip_pitch": -0.312, "knee": 0.669, "ankle_pitch": -0.363, "elbow": 0.6}
BM_DEFAULT |= {"shoulder_pitch": 0.2, "left_shoulder_roll": 0.2, "right_shoulder_roll": -0.2}


def default_of(name: str) -> float:
    base = name.removesuffix("_joint")
    side_free = base.removeprefix("left_").removeprefix("right_")
    return BM_DEFAULT.get(base, BM_DEFAULT.get(side_free, 0.0))


DEFAULT_POLICY = np.array([default_of(n) for n in ISAACLAB_ORDER])
SCALE_POLICY = np.round(np.linspace(0.07, 0.55, 29), 3)


def metadata_map(**override: str) -> dict[str, str]:
    """Metadata as `attach_onnx_metadata` writes it (lists as CSV with 3 decimals)."""

    def csv(values: np.ndarray) -> str:
        return ",".join(f"{v:.3f}" for v in values)

    meta = {
        "run_path": "someone/project/run",
        "joint_names": ",".join(ISAACLAB_ORDER),
        "joint_stiffness": csv(np.linspace(14.0, 99.0, 29)),
        "joint_damping": csv(np.linspace(0.9, 6.3, 29)),
        "default_joint_pos": csv(DEFAULT_POLICY),
        "command_names": "motion",
        "observation_names": "command,motion_anchor_pos_b,motion_anchor_ori_b,base_lin_vel,"
        "base_ang_vel,joint_pos,joint_vel,actions",
        "action_scale": csv(SCALE_POLICY),
    }
    meta.update(override)
    return meta


# The session's mapping: close to the metadata, but not equal (as a profile with more decimals).
SESSION_OFFSET = np.empty(29)
SESSION_OFFSET[PERM] = DEFAULT_POLICY + 0.0004
SESSION_SCALE = np.empty(29)
SESSION_SCALE[PERM] = SCALE_POLICY * 1.001


def adapter(n_envs: int = 1, policy: Any = None, **override: str) -> BeyondMimicAdapter:
    meta = BeyondMimicMetadata.from_onnx(metadata_map(**override))
    a = BeyondMimicAdapter(policy, meta)
    a.bind(n_envs=n_envs, action_offset_rad=SESSION_OFFSET, action_scale=SESSION_SCALE)
    return a


def batch(n_envs: int = 1) -> np.ndarray:
    obs = np.zeros(n_envs, dtype=ta.Layout(n_envs=n_envs, n_joints=29, n_refs=1).env_dtype)
    obs["flags"] = ta.FLAG_ACTIVE
    obs["root_quat_wxyz"] = [1.0, 0.0, 0.0, 0.0]
    obs["root_pos_w"][:, 2] = 0.79
    obs["reference"]["root_quat_wxyz"] = [1.0, 0.0, 0.0, 0.0]
    obs["reference"]["root_pos_w"][..., 2] = 0.79
    return obs


def observe(a: BeyondMimicAdapter, obs: np.ndarray) -> np.ndarray:
    return a.act(obs, np.zeros((len(obs), 29)))


COMMAND, ANCHOR_POS, ANCHOR_ORI = slice(0, 58), slice(58, 61), slice(61, 67)
BASE_LIN, BASE_ANG = slice(67, 70), slice(70, 73)
JOINT_POS, JOINT_VEL, ACTIONS = slice(73, 102), slice(102, 131), slice(131, 160)


def test_metadata_is_read_as_the_exporter_writes_it() -> None:
    meta = BeyondMimicMetadata.from_onnx(metadata_map(action_scale="0.5"))
    assert meta.joint_names == tuple(ISAACLAB_ORDER)
    assert meta.default_joint_pos is not None
    np.testing.assert_allclose(meta.default_joint_pos, DEFAULT_POLICY)
    np.testing.assert_array_equal(meta.action_scale, np.full(29, 0.5))
    assert meta.joint_stiffness is not None and meta.joint_stiffness[0] == 14.0
    assert meta.anchor_body_name == "torso_link"
    old_names = "command,motion_ref_pos_b,motion_ref_ori_b,base_lin_vel,base_ang_vel,joint_pos"
    meta = BeyondMimicMetadata.from_onnx(metadata_map(observation_names=old_names))
    assert meta.observation_names is not None
    assert meta.observation_names[1:3] == ("motion_anchor_pos_b", "motion_anchor_ori_b")
    with pytest.raises(ValueError, match="not a BeyondMimic export"):
        BeyondMimicMetadata.from_onnx({"kp": "[1.0]"})


def test_holosoma_metadata_json_lists_and_no_layout_keys() -> None:
    """holosoma writes `dof_names`, `kp`, `kd` as JSON and nothing else the adapter reads:
    the default pose and scale are then the session's, the terms named by the caller."""
    names = json.dumps(list(ISAACLAB_ORDER))
    meta = BeyondMimicMetadata.from_onnx({"dof_names": names, "kp": json.dumps([14.0] * 29)})
    assert meta.joint_names == tuple(ISAACLAB_ORDER)
    assert meta.joint_stiffness is not None and meta.joint_stiffness[0] == 14.0
    assert meta.default_joint_pos is None and meta.action_scale is None
    assert meta.observation_names is None


def test_the_observation_is_160_values_in_the_term_order() -> None:
    a = adapter()
    assert a.obs_dim == 160
    x = observe(a, batch())
    assert x.shape == (1, 160) and x.dtype == np.float32


def test_isaaclab_joint_order_is_mapped_by_name() -> None:
    assert ISAACLAB_ORDER[2] == "waist_yaw_joint" and PERM[2] == 12
    obs = batch()
    obs["reference"]["joint_pos"][0, 0] = np.arange(29) * 0.1
    obs["reference"]["joint_vel"][0, 0] = np.arange(29) * -1.0
    obs["q"][0] = SESSION_OFFSET + np.arange(29) * 0.01
    obs["qd"][0] = np.arange(29) * 2.0
    x = observe(adapter(), obs)[0]
    np.testing.assert_allclose(x[COMMAND][:29], PERM * 0.1, atol=1e-6)
    np.testing.assert_allclose(x[COMMAND][29:], PERM * -1.0, atol=1e-6)
    np.testing.assert_allclose(x[JOINT_POS], PERM * 0.01 + 0.0004, atol=1e-6)
    np.testing.assert_allclose(x[JOINT_VEL], PERM * 2.0, atol=1e-5)


def test_base_velocities_are_the_root_body_frame_ones() -> None:
    obs = batch()
    obs["root_lin_vel_b"][0] = [0.1, 0.2, 0.3]
    obs["root_ang_vel_b"][0] = [-1.0, -2.0, -3.0]
    obs["root_lin_vel_w"][0] = [9.0, 9.0, 9.0]
    x = observe(adapter(), obs)[0]
    assert x[BASE_LIN] == pytest.approx([0.1, 0.2, 0.3])
    assert x[BASE_ANG] == pytest.approx([-1.0, -2.0, -3.0])


def test_a_reference_on_the_robot_gives_a_zero_offset_and_an_identity_orientation() -> None:
    obs = batch()
    obs["q"][0, 12:15] = [0.3, -0.1, 0.2]
    obs["reference"]["joint_pos"][0, 0, 12:15] = [0.3, -0.1, 0.2]
    x = observe(adapter(), obs)[0]
    assert x[ANCHOR_POS] == pytest.approx([0.0, 0.0, 0.0], abs=1e-6)
    assert x[ANCHOR_ORI] == pytest.approx([1.0, 0.0, 0.0, 1.0, 0.0, 0.0], abs=1e-6)


def test_the_anchor_offset_is_in_the_robot_torso_frame() -> None:
    obs = batch()
    yaw_90 = [math.cos(math.pi / 4), 0.0, 0.0, math.sin(math.pi / 4)]
    obs["root_quat_wxyz"][0] = yaw_90
    obs["reference"]["root_quat_wxyz"][0, 0] = yaw_90
    obs["reference"]["root_pos_w"][0, 0] = [1.0, 0.0, 0.79]
    x = observe(adapter(), obs)[0]
    assert x[ANCHOR_POS] == pytest.approx([0.0, -1.0, 0.0], abs=1e-6), "world +x is -y at yaw 90°"


def test_the_torso_anchor_follows_the_waist_joints() -> None:
    obs = batch()
    obs["q"][0, 12] = math.pi / 2  # the robot's waist turned 90°, the reference's not
    x = observe(adapter(), obs)[0]
    # torso origins: robot (0, -0.0039635, 0.044), reference (-0.0039635, 0, 0.044) from the
    # pelvis; their difference in the robot torso frame (turned 90°):
    d = WAIST_ROLL_ORIGIN[0]
    assert x[ANCHOR_POS] == pytest.approx([-d, -d, 0.0], abs=1e-6)
    # reference torso in the robot torso frame: a -90° yaw, first two columns row by row
    assert x[ANCHOR_ORI] == pytest.approx([0.0, 1.0, -1.0, 0.0, 0.0, 0.0], abs=1e-6)


def test_a_pelvis_anchor_ignores_the_waist() -> None:
    obs = batch()
    obs["q"][0, 12] = math.pi / 2
    x = observe(adapter(anchor_body_name="pelvis"), obs)[0]
    assert x[ANCHOR_POS] == pytest.approx([0.0, 0.0, 0.0], abs=1e-6)
    assert x[ANCHOR_ORI] == pytest.approx([1.0, 0.0, 0.0, 1.0, 0.0, 0.0], abs=1e-6)


class Fixed:
    """A stand-in network answering the same policy-order action for every row."""

    input_dim = 160
    output_dim = 29

    def __init__(self, action: np.ndarray) -> None:
        self.action = action

    def __call__(self, inputs: np.ndarray, *, steps: np.ndarray) -> np.ndarray:
        return np.tile(self.action, (len(inputs), 1))


def test_actions_give_the_policys_targets_and_come_back_as_its_last_action() -> None:
    policy_action = np.linspace(-1.0, 1.0, 29)
    a = adapter(1, Fixed(policy_action))
    obs = batch()
    actions = np.zeros((1, 29))
    a.act(obs, actions)
    target = SESSION_OFFSET + SESSION_SCALE * actions[0]  # what the simulator does
    want = np.empty(29)
    want[PERM] = DEFAULT_POLICY + SCALE_POLICY * policy_action
    np.testing.assert_allclose(target, want, atol=1e-12)
    obs["last_action"][0] = actions[0]
    obs["step"] = 1
    x = a.act(obs, actions)[0]
    np.testing.assert_allclose(x[ACTIONS], policy_action, atol=1e-6)
    assert a.mapping_mismatch() == pytest.approx(0.0004 + 0.001 * SCALE_POLICY.max(), rel=1e-6)
    obs["step"] = 0  # a new episode: the wire's zeros are exactly 0 for the policy too
    obs["last_action"][0] = 0.0
    assert not a.act(obs, actions)[0][ACTIONS].any()


def test_the_observation_follows_the_listed_terms() -> None:
    names = "command,motion_anchor_ori_b,base_ang_vel,joint_pos,joint_vel,actions"
    a = adapter(observation_names=names)
    assert a.obs_dim == 154
    obs = batch()
    obs["root_ang_vel_b"][0] = [7.0, 8.0, 9.0]
    x = observe(a, obs)[0]
    assert x[64:67] == pytest.approx([7.0, 8.0, 9.0])
    with pytest.raises(ValueError, match="cannot build"):
        adapter(observation_names="command,projected_gravity")


def test_joints_the_g1_lacks_are_refused() -> None:
    with pytest.raises(ValueError, match="not on the G1"):
        adapter(joint_names=",".join(["head_joint", *ISAACLAB_ORDER[1:]]))


def make_export(path: Path, metadata: dict[str, str]) -> None:
    """A stand-in for a BeyondMimic export: `obs` [1, 160] and `time_step` [1, 1] in,
    `actions` [1, 29] = the command's first 29 values + 0.001 · time_step, then an extra
    output as the exporter adds the motion."""
    import onnx
    from onnx import TensorProto, helper, numpy_helper

    weights = np.zeros((160, 29), dtype=np.float32)
    weights[np.arange(29), np.arange(29)] = 1.0
    nodes = [
        helper.make_node("MatMul", ["obs", "w"], ["picked"]),
        helper.make_node("Mul", ["time_step", "c"], ["t"]),
        helper.make_node("Add", ["picked", "t"], ["actions"]),
        helper.make_node("Identity", ["time_step"], ["joint_pos"]),
    ]
    graph = helper.make_graph(
        nodes,
        "beyondmimic_stand_in",
        [
            helper.make_tensor_value_info("obs", TensorProto.FLOAT, [1, 160]),
            helper.make_tensor_value_info("time_step", TensorProto.FLOAT, [1, 1]),
        ],
        [
            helper.make_tensor_value_info("actions", TensorProto.FLOAT, [1, 29]),
            helper.make_tensor_value_info("joint_pos", TensorProto.FLOAT, [1, 1]),
        ],
        [
            numpy_helper.from_array(weights, "w"),
            numpy_helper.from_array(np.full((1, 29), 0.001, dtype=np.float32), "c"),
        ],
    )
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 11)])
    model.ir_version = 7
    for key, value in metadata.items():
        entry = model.metadata_props.add()
        entry.key, entry.value = key, value
    onnx.save(model, str(path))


def test_an_export_with_metadata_runs_one_row_at_a_time_with_its_time_step(
    tmp_path: Path,
) -> None:
    if importlib.util.find_spec("onnx") is None or importlib.util.find_spec("onnxruntime") is None:
        pytest.skip("needs the onnx and onnxruntime packages to make and run a model")
    path = tmp_path / "policy.onnx"
    make_export(path, metadata_map())
    a = BeyondMimicAdapter.from_onnx(str(path))
    assert a.metadata.joint_names == tuple(ISAACLAB_ORDER) and a.obs_dim == 160
    a.bind(n_envs=3, action_offset_rad=SESSION_OFFSET, action_scale=SESSION_SCALE)
    obs = batch(3)
    obs["flags"][1] = 0
    obs["step"] = [5, 0, 40]
    obs["reference"]["joint_pos"][:, 0] = np.arange(29) * 0.01 + np.arange(3)[:, None]
    actions = np.zeros((3, 29))
    a.act(obs, actions)
    assert not actions[1].any()
    for slot, step in ((0, 5), (2, 40)):
        policy_action = PERM * 0.01 + slot + 0.001 * step  # command = reference in policy order
        target = SESSION_OFFSET + SESSION_SCALE * actions[slot]
        want = np.empty(29)
        want[PERM] = DEFAULT_POLICY + SCALE_POLICY * policy_action
        np.testing.assert_allclose(target, want, atol=1e-5)


class Wide:
    """A stand-in network `input_dim` inputs wide."""

    output_dim = 29

    def __init__(self, input_dim: int) -> None:
        self.input_dim = input_dim

    def __call__(self, inputs: np.ndarray, *, steps: np.ndarray) -> np.ndarray:
        return np.zeros((len(inputs), 29))


def test_a_width_two_known_layouts_fit_is_refused_unless_the_terms_are_named() -> None:
    names = json.dumps(list(ISAACLAB_ORDER))
    bare = BeyondMimicMetadata.from_onnx({"dof_names": names})
    with pytest.raises(ValueError, match="fits 2 known layouts") as refused:
        BeyondMimicAdapter(Wide(154), bare)
    assert "holosoma" in str(refused.value) and "without state estimation" in str(refused.value)
    named = dataclasses.replace(bare, observation_names=HOLOSOMA_TERMS)
    assert BeyondMimicAdapter(Wide(154), named).terms == HOLOSOMA_TERMS
    assert BeyondMimicAdapter(Wide(160), bare).terms == DEFAULT_TERMS
    with pytest.raises(ValueError, match="no known layout is 150"):
        BeyondMimicAdapter(Wide(150), bare)
