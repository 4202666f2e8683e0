"""The GMT adapter builds GMT's 2154-dim observation (20 future mimic frames of 30, proprio
of 74 on the 23 joints it drives, 20 past proprio frames), keeps its history per slot, and
maps its 23 actions onto the G1's 29 with the wrists at 0. An ONNX model made in the test
(when `onnx` and onnxruntime are installed) checks the dynamic-batch path end to end."""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import thorarena as ta
from thorarena.adapters import GmtAdapter, load_policy
from thorarena.adapters.gmt import JOINTS, WRISTS

DEFAULT = np.array(
    [-0.2, 0, 0, 0.4, -0.2, 0] * 2 + [0, 0, 0] + [0, 0.4, 0, 1.2, 0, 0, 0, 0, -0.4, 0, 1.2, 0, 0, 0]
)
N_REFS = 20
MIMIC, PROPRIO, HISTORY = slice(0, 600), slice(600, 674), slice(674, 2154)


def batch(n_envs: int) -> np.ndarray:
    obs = np.zeros(n_envs, dtype=ta.Layout(n_envs=n_envs, n_joints=29, n_refs=N_REFS).env_dtype)
    obs["flags"] = ta.FLAG_ACTIVE
    obs["root_quat_wxyz"] = [1.0, 0.0, 0.0, 0.0]
    obs["q"] = DEFAULT
    obs["reference"]["root_quat_wxyz"] = [1.0, 0.0, 0.0, 0.0]
    obs["reference"]["joint_pos"] = DEFAULT
    return obs


def adapter(n_envs: int, policy: Any = None) -> GmtAdapter:
    a = GmtAdapter(policy)
    a.bind(n_envs=n_envs, action_offset_rad=DEFAULT, action_scale=np.full(29, 0.5))
    return a


def step(a: GmtAdapter, obs: np.ndarray, k: int) -> np.ndarray:
    obs["step"] = k
    return a.act(obs, np.zeros((len(obs), 29)))


def frame(x: np.ndarray, k: int) -> np.ndarray:
    return x[MIMIC][30 * k : 30 * (k + 1)]


def test_the_observation_is_2154_values_over_20_future_frames() -> None:
    x = step(adapter(2), batch(2), 0)
    assert x.shape == (2, 2154) and x.dtype == np.float32
    offsets = GmtAdapter.reference_offsets_s
    assert len(offsets) == 20
    assert offsets[:3] == (0.02, 0.1, 0.2) and offsets[-1] == 1.9
    assert list(JOINTS) == [*range(19), 22, 23, 24, 25]
    assert sorted([*JOINTS, *WRISTS]) == list(range(29))


def test_each_mimic_frame_is_height_roll_pitch_body_velocity_yaw_rate_and_23_joints() -> None:
    obs = batch(1)
    yaw_90 = [math.cos(math.pi / 4), 0.0, 0.0, math.sin(math.pi / 4)]
    for k in range(N_REFS):
        obs["reference"]["root_pos_w"][0, k, 2] = 0.7 + 0.001 * k
        obs["reference"]["joint_pos"][0, k] = np.arange(29) + 100 * k
    obs["reference"]["root_quat_wxyz"][0, 3] = yaw_90
    obs["reference"]["root_lin_vel_w"][0, 3] = [1.5, 0.0, 0.25]
    obs["reference"]["root_ang_vel_w"][0, 3] = [0.0, 0.0, -0.4]
    half = 0.1  # pitch 0.2 rad
    obs["reference"]["root_quat_wxyz"][0, 7] = [math.cos(half), 0.0, math.sin(half), 0.0]
    x = step(adapter(1), obs, 0)[0]
    f3 = frame(x, 3)
    assert f3[0] == pytest.approx(0.703)
    assert f3[1:3] == pytest.approx([0.0, 0.0], abs=1e-6)
    assert f3[3:6] == pytest.approx([0.0, -1.5, 0.25], abs=1e-6), "world x is body -y at yaw 90°"
    assert f3[6] == pytest.approx(-0.4, abs=1e-6)
    np.testing.assert_array_equal(f3[7:], JOINTS + 300)
    assert frame(x, 7)[1:3] == pytest.approx([0.0, 0.2], abs=1e-6)
    np.testing.assert_array_equal(frame(x, 19)[7:], JOINTS + 1900)


def test_proprio_covers_the_23_joints_with_scales_and_zeroed_ankle_velocities() -> None:
    obs = batch(1)
    obs["root_ang_vel_b"][0] = [0.4, -0.8, 1.2]
    obs["root_quat_wxyz"][0] = [math.cos(0.15), math.sin(0.15), 0.0, 0.0]  # roll 0.3
    obs["q"][0] = DEFAULT + np.arange(29) * 0.01
    obs["qd"][0] = np.arange(29) + 1.0
    obs["last_action"][0] = np.arange(29) * -0.1
    p = step(adapter(1), obs, 0)[0][PROPRIO]
    assert p[:3] == pytest.approx([0.1, -0.2, 0.3])
    assert p[3:5] == pytest.approx([0.3, 0.0], abs=1e-6)
    np.testing.assert_allclose(p[5:28], JOINTS * 0.01, atol=1e-6)
    qd = (JOINTS + 1.0) * 0.05
    qd[[4, 5, 10, 11]] = 0.0
    np.testing.assert_allclose(p[28:51], qd, atol=1e-6)
    np.testing.assert_allclose(p[51:74], JOINTS * -0.1, atol=1e-6)


def test_the_observation_is_not_clipped() -> None:
    obs = batch(1)
    obs["qd"][0, 0] = 4000.0
    assert step(adapter(1), obs, 0)[0][PROPRIO][28] == pytest.approx(200.0)


def test_history_starts_as_zeros_and_shifts_in_each_proprio_after_use() -> None:
    a, obs = adapter(1), batch(1)
    xs = []
    for k in range(3):
        obs["q"] = DEFAULT + 0.01 * (k + 1)
        xs.append(step(a, obs, k)[0])
    rows = [x[HISTORY].reshape(20, 74) for x in xs]
    assert not rows[0].any()
    assert not rows[1][:19].any()
    np.testing.assert_array_equal(rows[1][19], xs[0][PROPRIO])
    np.testing.assert_array_equal(rows[2][18:], np.vstack([xs[0][PROPRIO], xs[1][PROPRIO]]))


def test_a_new_episode_in_one_slot_clears_only_that_slots_history() -> None:
    a, obs = adapter(2), batch(2)
    obs["q"] = DEFAULT + 0.1
    for k in range(3):
        step(a, obs, k)
    obs["step"] = [3, 0]
    x = a.act(obs, np.zeros((2, 29)))
    assert x[0][HISTORY].any()
    assert not x[1][HISTORY].any()


class Counting:
    """A stand-in network answering 1, 2, …, 23."""

    input_dim = 2154
    output_dim = 23

    def __call__(self, inputs: np.ndarray, *, steps: np.ndarray) -> np.ndarray:
        return np.tile(np.arange(1.0, 24.0), (len(inputs), 1))


def test_the_23_actions_land_on_their_joints_and_the_wrists_get_0() -> None:
    actions = np.zeros((2, 29))
    obs = batch(2)
    adapter(2, Counting()).act(obs, actions)
    np.testing.assert_array_equal(actions[:, JOINTS], np.tile(np.arange(1.0, 24.0), (2, 1)))
    assert not actions[:, WRISTS].any()


def test_a_torchscript_file_without_torch_says_what_to_install(tmp_path: Path) -> None:
    if importlib.util.find_spec("torch") is not None:
        pytest.skip("torch is installed: nothing to report")
    with pytest.raises(ImportError, match="torch"):
        load_policy(tmp_path / "pretrained.pt")


def test_an_onnx_gmt_network_runs_batched_over_the_active_slots(tmp_path: Path) -> None:
    if importlib.util.find_spec("onnx") is None or importlib.util.find_spec("onnxruntime") is None:
        pytest.skip("needs the onnx and onnxruntime packages to make and run a model")
    import onnx
    from onnx import TensorProto, helper, numpy_helper

    weights = np.zeros((2154, 23), dtype=np.float32)
    weights[600 + 5 + np.arange(23), np.arange(23)] = 1.0  # action = q - default of its joint
    graph = helper.make_graph(
        [helper.make_node("MatMul", ["obs", "w"], ["actions"])],
        "gmt_stand_in",
        [helper.make_tensor_value_info("obs", TensorProto.FLOAT, ["batch", 2154])],
        [helper.make_tensor_value_info("actions", TensorProto.FLOAT, ["batch", 23])],
        [numpy_helper.from_array(weights, "w")],
    )
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 13)])
    model.ir_version = 8
    path = tmp_path / "gmt.onnx"
    onnx.save(model, str(path))

    policy = load_policy(path)
    assert (policy.input_dim, policy.output_dim) == (2154, 23)
    obs = batch(3)
    obs["flags"][1] = 0
    obs["q"] = DEFAULT + np.arange(29) * 0.01 + np.arange(3)[:, None]
    actions = np.zeros((3, 29))
    adapter(3, policy).act(obs, actions)
    for slot in (0, 2):
        np.testing.assert_allclose(actions[slot, JOINTS], JOINTS * 0.01 + slot, atol=1e-5)
    assert not actions[1].any() and not actions[:, WRISTS].any()
