"""The TWIST2 adapter builds TWIST2's 1432-dim observation block by block (slices, scales,
joint order, quaternion convention), keeps its history per slot (refilled on steps 0 and 1,
shifted later, cleared when one slot's episode restarts), agrees with a plain scalar
re-implementation of the layout, and the dump cross-check tool accepts a matching episode and
rejects a perturbed one. No simulator needed; the real network is used when
`../shared/reference/twist2/twist2_1017_25k.onnx` and onnxruntime are there.

Regenerate the dump fixture (states hand-made below, observations from the scalar
re-implementation, actions from ONNX Runtime): `python tests/test_twist2.py --regenerate`.
"""

from __future__ import annotations

import importlib.util
import json
import math
import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any, cast

import numpy as np
import pytest

import thorarena as ta
from thorarena.adapters import Twist2Adapter
from thorarena.adapters.dump import compare_dump, env_record, load_dump

HERE = Path(__file__).resolve().parent
PACKAGE = HERE.parent
REFERENCE = Path(
    os.environ.get("THORARENA_REFERENCE") or PACKAGE.parents[2] / "shared" / "reference"
)
ONNX = REFERENCE / "twist2" / "twist2_1017_25k.onnx"
FIXTURE = HERE / "fixtures" / "twist2_dump.json"
CHECK_TOOL = PACKAGE / "examples" / "check_against_dump.py"

DEFAULT = np.array(
    [-0.2, 0, 0, 0.4, -0.2, 0] * 2 + [0, 0, 0] + [0, 0.4, 0, 1.2, 0, 0, 0, 0, -0.4, 0, 1.2, 0, 0, 0]
)
SCALE = np.full(29, 0.5)
YAW_90 = [math.cos(math.pi / 4), 0.0, 0.0, math.sin(math.pi / 4)]

MIMIC, PROPRIO, HISTORY, FUTURE = slice(0, 35), slice(35, 127), slice(127, 1397), slice(1397, 1432)


def onnx_or_skip() -> Path:
    if importlib.util.find_spec("onnxruntime") is None:
        pytest.skip("onnxruntime is not installed (pip install 'thorarena[policies]')")
    if not ONNX.exists():
        pytest.skip(f"the reference TWIST2 network is not at {ONNX}")
    return ONNX


def batch(n_envs: int, *, active: tuple[int, ...] | None = None) -> np.ndarray:
    """Standing robot and reference, identity rotations, default pose, all slots active."""
    obs = np.zeros(n_envs, dtype=ta.Layout(n_envs=n_envs, n_joints=29, n_refs=2).env_dtype)
    obs["flags"] = ta.FLAG_ACTIVE
    if active is not None:
        obs["flags"] = [ta.FLAG_ACTIVE if i in active else 0 for i in range(n_envs)]
    obs["root_quat_wxyz"] = [1.0, 0.0, 0.0, 0.0]
    obs["root_pos_w"][:, 2] = 0.79
    obs["q"] = DEFAULT
    obs["reference"]["root_quat_wxyz"] = [1.0, 0.0, 0.0, 0.0]
    obs["reference"]["root_pos_w"][..., 2] = 0.79
    obs["reference"]["joint_pos"] = DEFAULT
    return obs


def adapter(n_envs: int, policy: Any = None) -> Twist2Adapter:
    a = Twist2Adapter(policy)
    a.bind(n_envs=n_envs, action_offset_rad=DEFAULT, action_scale=SCALE)
    return a


def step(a: Twist2Adapter, obs: np.ndarray, k: int) -> np.ndarray:
    obs["step"] = k
    return a.act(obs, np.zeros((len(obs), 29)))


class TakeFirst:
    """A stand-in network: the first 29 inputs, scaled."""

    input_dim = 1432
    output_dim = 29

    def __call__(self, inputs: np.ndarray, *, steps: np.ndarray) -> np.ndarray:
        return inputs[:, :29] * 0.1


# --- blocks -------------------------------------------------------------------------------


def test_the_observation_is_1432_float32_values_and_asks_for_t_and_t_plus_20_ms() -> None:
    x = step(adapter(2), batch(2), 0)
    assert x.shape == (2, 1432) and x.dtype == np.float32
    assert Twist2Adapter.reference_offsets_s == (0.0, 0.02)


def test_a_90_degree_yaw_root_moving_along_world_x_moves_along_minus_body_y() -> None:
    obs = batch(1)
    for i in (0, 1):
        obs["reference"]["root_quat_wxyz"][0, i] = YAW_90
        obs["reference"]["root_lin_vel_w"][0, i] = [1.5, 0.0, 0.0]
        obs["reference"]["root_ang_vel_w"][0, i] = [0.0, 0.0, 0.7]
    x = step(adapter(1), obs, 0)[0]
    for block in (MIMIC, FUTURE):
        mimic = x[block]
        assert mimic[0] == pytest.approx(0.0, abs=1e-6)
        assert mimic[1] == pytest.approx(-1.5, abs=1e-6)
        assert mimic[5] == pytest.approx(0.7, abs=1e-6), "yaw rate is unchanged by a yaw"
        assert mimic[3:5] == pytest.approx([0.0, 0.0], abs=1e-6), "a pure yaw has no roll, pitch"


def test_mimic_reads_the_t_plus_20_ms_frame_and_future_reads_the_t_frame() -> None:
    obs = batch(1)
    obs["reference"]["root_pos_w"][0, 0, 2] = 0.70
    obs["reference"]["root_pos_w"][0, 1, 2] = 0.75
    obs["reference"]["joint_pos"][0, 0] = np.arange(29) * 0.01
    obs["reference"]["joint_pos"][0, 1] = np.arange(29) * -0.02
    x = step(adapter(1), obs, 0)[0]
    assert x[MIMIC][2] == pytest.approx(0.75) and x[FUTURE][2] == pytest.approx(0.70)
    np.testing.assert_allclose(x[MIMIC][6:], np.arange(29) * -0.02, atol=1e-7)
    np.testing.assert_allclose(x[FUTURE][6:], np.arange(29) * 0.01, atol=1e-7)


def test_roll_and_pitch_follow_the_wxyz_convention() -> None:
    obs = batch(1)
    half = 0.15  # a 0.3 rad rotation
    obs["reference"]["root_quat_wxyz"][0, 1] = [math.cos(half), math.sin(half), 0.0, 0.0]
    obs["reference"]["root_quat_wxyz"][0, 0] = [math.cos(half), 0.0, math.sin(half), 0.0]
    obs["root_quat_wxyz"][0] = [math.cos(0.1), 0.0, math.sin(0.1), 0.0]  # pitch 0.2
    x = step(adapter(1), obs, 0)[0]
    assert x[MIMIC][3:5] == pytest.approx([0.3, 0.0], abs=1e-6)
    assert x[FUTURE][3:5] == pytest.approx([0.0, 0.3], abs=1e-6)
    assert x[PROPRIO][3:5] == pytest.approx([0.0, 0.2], abs=1e-6)


def test_proprio_scales_angular_velocity_offsets_q_and_zeroes_ankle_velocities() -> None:
    obs = batch(1)
    obs["root_ang_vel_b"][0] = [0.4, -0.8, 1.2]
    obs["root_ang_vel_w"][0] = [9.0, 9.0, 9.0]  # not used
    obs["q"][0] = DEFAULT + np.arange(29) * 0.01
    obs["qd"][0] = np.arange(29) + 1.0
    obs["last_action"][0] = np.arange(29) * -0.1
    p = step(adapter(1), obs, 0)[0][PROPRIO]
    assert p[:3] == pytest.approx([0.1, -0.2, 0.3])
    np.testing.assert_allclose(p[5:34], np.arange(29) * 0.01, atol=1e-7)
    qd = (np.arange(29) + 1.0) * 0.05
    qd[[4, 5, 10, 11]] = 0.0
    np.testing.assert_allclose(p[34:63], qd, atol=1e-6)
    np.testing.assert_allclose(p[63:92], np.arange(29) * -0.1, atol=1e-6)


def test_the_observation_is_clipped_to_100() -> None:
    obs = batch(1)
    obs["qd"][0, 0] = 1e5
    obs["qd"][0, 1] = -1e5
    p = step(adapter(1), obs, 0)[0][PROPRIO]
    assert (p[34], p[35]) == (100.0, -100.0)


# --- history and resets ---------------------------------------------------------------------


def singles(a: Twist2Adapter, obs: np.ndarray, n_steps: int) -> list[np.ndarray]:
    """Runs steps 0..n_steps-1, each with different joint angles; returns each step's obs."""
    out = []
    for k in range(n_steps):
        obs["q"] = DEFAULT + 0.01 * (k + 1)
        out.append(step(a, obs, k))
    return out


def history_rows(x: np.ndarray) -> np.ndarray:
    return x[HISTORY].reshape(10, 127)


def test_history_is_zeros_on_step_0_and_the_first_single_ten_times_on_step_1() -> None:
    xs = singles(adapter(1), batch(1), 2)
    assert not history_rows(xs[0][0]).any()
    np.testing.assert_array_equal(history_rows(xs[1][0]), np.tile(xs[0][0][:127], (10, 1)))


def test_step_1_refills_the_history_and_later_steps_shift_it_oldest_first() -> None:
    xs = [x[0] for x in singles(adapter(1), batch(1), 5)]
    s = [x[:127] for x in xs]
    np.testing.assert_array_equal(history_rows(xs[2]), np.tile(s[1], (10, 1)))
    np.testing.assert_array_equal(history_rows(xs[3]), np.vstack([np.tile(s[1], (9, 1)), s[2]]))
    np.testing.assert_array_equal(
        history_rows(xs[4]), np.vstack([np.tile(s[1], (8, 1)), s[2], s[3]])
    )


def test_a_new_episode_in_one_slot_clears_only_that_slots_history() -> None:
    a, obs = adapter(2), batch(2)
    before = singles(a, obs, 4)[-1]
    obs["step"] = [4, 0]
    x = a.act(obs, np.zeros((2, 29)))
    assert not history_rows(x[1]).any(), "slot 1 restarted: zeros, as before any step"
    expected = np.vstack([history_rows(before[0])[1:], before[0][:127]])
    np.testing.assert_array_equal(history_rows(x[0]), expected)


def test_inactive_slots_get_no_action_and_keep_no_state() -> None:
    a, obs = adapter(3, TakeFirst()), batch(3, active=(0, 2))
    actions = np.zeros((3, 29))
    obs["step"] = 0
    x = a.act(obs, actions)
    assert x.shape == (2, 1432)
    assert not actions[1].any() and actions[0].any() and actions[2].any()
    assert not a.state["history"][1].any()
    np.testing.assert_allclose(actions[0], x[0, :29] * 0.1, rtol=1e-6)


def test_the_history_is_float32_and_holds_the_clipped_singles() -> None:
    obs = batch(1)
    obs["qd"][0, 0] = 1e5
    a = adapter(1)
    x = step(a, obs, 0)
    assert a.state["history"].dtype == np.float32
    np.testing.assert_array_equal(a.state["history"][0], np.tile(x[0][:127], (10, 1)))
    assert a.state["history"][0, 0, 35 + 34] == 100.0


def test_a_network_timer_gets_one_entry_per_network_call() -> None:
    a, obs = adapter(2, TakeFirst()), batch(2)
    a.network_s = []
    for k in range(3):
        step(a, obs, k)
    obs["flags"] = 0
    step(a, obs, 3)  # no active slot: no network call
    assert len(a.network_s) == 3 and all(t > 0 for t in a.network_s)


def test_a_batch_the_simulator_counted_all_active_acts_as_one_whose_flags_say_so() -> None:
    built = np.arange(3 * 1432, dtype=np.float32).reshape(3, 1432) / 1000.0
    results = []
    for all_active in (False, True):
        a, obs = adapter(3, TakeFirst()), batch(3)
        actions = np.zeros((3, 29))
        for k in range(3):
            obs["step"] = k
            inputs = a.act(obs, actions, None if k < 2 else built, all_active=all_active)
        results.append((inputs, actions.copy(), a.state["history"].copy()))
    (inputs_f, actions_f, history_f), (inputs_t, actions_t, history_t) = results
    assert np.array_equal(inputs_f, inputs_t) and np.array_equal(actions_f, actions_t)
    assert np.array_equal(history_f, history_t) and history_t.any()


def test_an_input_built_by_the_simulator_goes_to_the_network_as_it_is() -> None:
    a = adapter(3, TakeFirst())
    obs = batch(3, active=(0, 2))
    built = np.arange(3 * 1432, dtype=np.float32).reshape(3, 1432) / 1000.0
    actions = np.zeros((3, 29))
    inputs = a.act(obs, actions, built)
    assert np.array_equal(inputs, built[[0, 2]])
    assert np.allclose(actions[[0, 2]], built[[0, 2], :29] * 0.1)
    assert not actions[1].any()
    # The adapter's own builder was not run: its history is untouched.
    assert not a.state["history"].any()


def test_the_run_loop_answers_every_step_of_a_session() -> None:
    class FakeSession:
        n_envs = 2
        action_offset_rad = DEFAULT
        action_scale = SCALE
        steps_answered = 0
        layout = ta.Layout(n_envs=2, n_joints=29, n_refs=2)
        policy_inputs = None  # the adapter builds the observation itself
        n_active = 2  # as the simulator counts the batches below

        class info:  # noqa: N801
            reference_offsets_s = (0.0, 0.02)

        def steps(self, *, zero_actions: bool = True) -> Iterator[tuple[np.ndarray, np.ndarray]]:
            # The adapter asks for unzeroed memory: what an earlier step left is garbage
            # here, and the row of a slot that went inactive must come back zero.
            assert not zero_actions
            for k in range(3):
                obs = batch(2, active=(0,) if k == 2 else (0, 1))
                obs["step"] = k
                self.n_active = 1 if k == 2 else 2
                actions = np.full((2, 29), np.nan)
                yield obs, actions
                assert np.isfinite(actions).all()
                assert actions[0].any()
                assert actions[1].any() if k < 2 else not actions[1].any()
                self.steps_answered += 1

    a = Twist2Adapter(TakeFirst())
    assert a.run(cast(ta.Session, FakeSession())) == 3


# --- against a scalar re-implementation and the dump tool ---------------------------------


def _rotation(q: list[float]) -> list[list[float]]:
    w, x, y, z = q
    return [
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ]


def _in_body(q: list[float], v: list[float]) -> list[float]:
    r = _rotation(q)
    return [sum(r[row][col] * v[row] for row in range(3)) for col in range(3)]


def _roll_pitch(q: list[float]) -> list[float]:
    w, x, y, z = q
    return [
        math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y)),
        math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x)))),
    ]


def _mimic(frame: dict[str, Any]) -> list[float]:
    q = frame["root_quat_wxyz"]
    v = _in_body(q, frame["root_lin_vel_w"])
    w = _in_body(q, frame["root_ang_vel_w"])
    return [v[0], v[1], frame["root_pos_w"][2], *_roll_pitch(q), w[2], *frame["joint_pos"]]


def scalar_observations(envs: list[dict[str, Any]], default: list[float]) -> list[list[float]]:
    """TWIST2's observation written out element by element from the layout's description."""
    history = [[0.0] * 127 for _ in range(10)]
    out = []
    for env in envs:
        qd = [0.0 if j in (4, 5, 10, 11) else v * 0.05 for j, v in enumerate(env["qd"])]
        proprio = [
            *(v * 0.25 for v in env["root_ang_vel_b"]),
            *_roll_pitch(env["root_quat_wxyz"]),
            *(q - d for q, d in zip(env["q"], default, strict=True)),
            *qd,
            *env["last_action"],
        ]
        single = _mimic(env["reference"][1]) + proprio
        obs = single + [v for row in history for v in row] + _mimic(env["reference"][0])
        out.append([min(100.0, max(-100.0, v)) for v in obs])
        history = [list(single)] * 10 if env["step"] <= 1 else [*history[1:], list(single)]
    return out


def _quat_rpy(roll: float, pitch: float, yaw: float) -> list[float]:
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return [
        cr * cp * cy + sr * sp * sy,
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
    ]


def hand_made_episode(n_steps: int = 5) -> list[dict[str, Any]]:
    """A walking-like episode: the root turned ~90°, tilted a little, joints near the default."""
    d = DEFAULT.tolist()
    envs = []
    for k in range(n_steps):
        frames = [
            {
                "time_s": 0.02 * (k + i),
                "root_pos_w": [0.01 * (k + i), -0.05, 0.78 + 0.002 * i],
                "root_quat_wxyz": _quat_rpy(0.02, 0.03 - 0.01 * i, 1.5708 + 0.05 * (k + i)),
                "root_lin_vel_w": [0.5, 0.05 * i, -0.01],
                "root_ang_vel_w": [0.02, -0.01, 0.2 + 0.1 * i],
                "joint_pos": [d[j] + 0.05 * math.sin(j + 0.3 * (k + i)) for j in range(29)],
                "joint_vel": [0.1 * math.cos(j + k) for j in range(29)],
            }
            for i in (0, 1)
        ]
        envs.append(
            {
                "episode_id": 7,
                "step": k,
                "flags": ta.FLAG_ACTIVE | (ta.FLAG_RESET if k == 0 else 0),
                "time_s": 0.02 * k,
                "root_pos_w": [0.009 * k, -0.04, 0.79 - 0.001 * k],
                "root_quat_wxyz": _quat_rpy(0.05, -0.08, 1.5708 + 0.04 * k),
                "root_lin_vel_w": [0.45, 0.02, -0.03],
                "root_ang_vel_w": [0.1, -0.2, 0.3],
                "root_lin_vel_b": [0.02, -0.45, -0.03],
                "root_ang_vel_b": [0.3 - 0.05 * k, -0.1, 0.5],
                "projected_gravity_b": [0.08, 0.05, -0.99],
                "q": [d[j] + 0.01 * math.sin(j + k) for j in range(29)],
                "qd": [0.5 * math.cos(0.7 * j + k) for j in range(29)],
                "last_action": [0.0 if k == 0 else 0.2 * math.sin(1.3 * j + k) for j in range(29)],
                "reference": frames,
            }
        )
    return envs


def regenerate_fixture() -> None:
    import onnxruntime

    envs = hand_made_episode(4)
    observations = scalar_observations(envs, DEFAULT.tolist())
    session = onnxruntime.InferenceSession(str(ONNX), providers=["CPUExecutionProvider"])
    actions = session.run(None, {"input": np.asarray(observations, dtype=np.float32)})[0]
    dump = {
        "_about": "hand-made states (tests/test_twist2.py hand_made_episode); obs from the "
        "scalar re-implementation there; action from ONNX Runtime on twist2_1017_25k.onnx",
        "action_offset_rad": DEFAULT.tolist(),
        "action_scale": SCALE.tolist(),
        "steps": [
            {"env": env, "obs": obs, "action": action.tolist()}
            for env, obs, action in zip(envs, observations, actions, strict=True)
        ],
    }
    FIXTURE.write_text(json.dumps(dump) + "\n", encoding="utf-8")


def test_the_adapter_matches_the_scalar_re_implementation_over_an_episode() -> None:
    envs = hand_made_episode(14)
    envs[12]["step"] = 0  # a new episode in the same slot: history starts over
    envs[13]["step"] = 1
    layout = ta.Layout(n_envs=1, n_joints=29, n_refs=2)
    a = adapter(1)
    expected = scalar_observations(envs[:12], DEFAULT.tolist())
    expected += scalar_observations(envs[12:], DEFAULT.tolist())
    for env, want in zip(envs, expected, strict=True):
        got = a.act(env_record(env, layout), np.zeros((1, 29)))[0]
        np.testing.assert_allclose(got, want, rtol=0, atol=2e-6)


def test_the_fixture_holds_the_scalar_observations_of_its_states() -> None:
    dump = load_dump(FIXTURE)
    envs = [s["env"] for s in dump["steps"]]
    expected = scalar_observations(envs, dump["action_offset_rad"])
    for s, want in zip(dump["steps"], expected, strict=True):
        np.testing.assert_allclose(s["obs"], want, rtol=0, atol=1e-12)


def test_the_dump_comparison_accepts_the_fixture_and_finds_a_perturbed_value() -> None:
    dump = load_dump(FIXTURE)
    result = compare_dump(dump, Twist2Adapter(None))
    assert result.ok() and result.obs_max_abs < 1e-6 and result.action_max_abs is None
    dump["steps"][3]["obs"][500] += 1e-4
    bad = compare_dump(dump, Twist2Adapter(None))
    assert not bad.ok()
    assert bad.steps[3].obs_argmax == 500
    assert bad.obs_max_abs == pytest.approx(1e-4, rel=0.01)


def test_the_dump_must_start_at_step_0_and_be_consecutive() -> None:
    dump = load_dump(FIXTURE)
    del dump["steps"][1]
    with pytest.raises(ValueError, match="consecutive"):
        compare_dump(dump, Twist2Adapter(None))


def run_check_tool(dump_path: Path, onnx: Path) -> subprocess.CompletedProcess[str]:
    env = dict(
        os.environ, PYTHONPATH=os.pathsep.join([str(PACKAGE), os.environ.get("PYTHONPATH", "")])
    )
    return subprocess.run(
        [
            sys.executable,
            str(CHECK_TOOL),
            "--adapter",
            "twist2",
            "--dump",
            str(dump_path),
            "--onnx",
            str(onnx),
        ],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
    )


def test_the_check_tool_passes_the_fixture_with_the_real_network() -> None:
    onnx = onnx_or_skip()
    done = run_check_tool(FIXTURE, onnx)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "ok" in done.stdout and "observation max |diff|" in done.stdout


def test_the_check_tool_fails_on_a_wrong_action_and_on_a_wrong_observation(
    tmp_path: Path,
) -> None:
    onnx = onnx_or_skip()
    for field, index in (("action", 3), ("obs", 1400)):
        dump = load_dump(FIXTURE)
        dump["steps"][2][field][index] += 1e-3
        path = tmp_path / f"bad-{field}.json"
        path.write_text(json.dumps(dump), encoding="utf-8")
        done = run_check_tool(path, onnx)
        assert done.returncode == 1, done.stdout + done.stderr
        assert "MISMATCH" in done.stderr


def test_batched_inference_gives_each_slot_its_own_action() -> None:
    from thorarena.adapters import OnnxPolicy

    policy = OnnxPolicy(onnx_or_skip())
    envs = hand_made_episode(3)
    layout = ta.Layout(n_envs=3, n_joints=29, n_refs=2)
    obs = np.concatenate([env_record(env, layout) for env in envs])
    obs["step"] = 0
    a = Twist2Adapter(policy)
    a.bind(n_envs=3, action_offset_rad=DEFAULT, action_scale=SCALE)
    actions = np.zeros((3, 29))
    x = a.act(obs, actions)
    for i in range(3):
        alone = policy(x[i : i + 1], steps=np.zeros(1))[0]
        np.testing.assert_allclose(actions[i], alone, rtol=0, atol=1e-5)
    assert np.abs(actions[0] - actions[1]).max() > 1e-3


if __name__ == "__main__" and "--regenerate" in sys.argv:
    regenerate_fixture()
    print(f"wrote {FIXTURE}")
