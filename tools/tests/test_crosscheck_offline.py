"""Offline tests of tools/mujoco_crosscheck.py, without the thorarena binary.

The synthetic traces are produced by MuJoCo itself through the script's own
replay, so "ours" equals MuJoCo exactly: the crosscheck must report zero error,
and a known perturbation of one joint must show up with the expected RMS / max.
Tests that need the reference MJCF skip (with the reason) when it is absent.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import mujoco_crosscheck as mc
from mujoco_step_bench import default_angle, gains

PHYSICS_DT_S = 0.005
CONTROL_DT_S = 0.02
ROOT_POS = [0.0, 0.0, 0.793]
# Armature for the joints the MJCF leaves without one, copied from their sibling joints.
MISSING_ARMATURE = {
    "waist_pitch_joint": 0.0103,
    **{f"{side}_wrist_{axis}_joint": 0.003597
       for side in ("left", "right") for axis in ("roll", "pitch", "yaw")},
}

requires_mjcf = pytest.mark.skipif(
    not mc.DEFAULT_MJCF.is_file(), reason=f"reference MJCF not found at {mc.DEFAULT_MJCF}")


def synthetic_inputs(mjcf: Path, scenario: str, duration_s: float) -> dict[str, Any]:
    """Trace JSON with realistic inputs (sinusoidal targets around the standing pose).

    The trajectory keys ("t", "q", "root_pos", "root_quat_wxyz") are zero placeholders
    of the right shape; fill them with :func:`fill_with_mujoco`.
    """
    model = mc.mujoco.MjModel.from_xml_path(str(mjcf))
    hinge = [j for j in range(model.njnt) if model.jnt_type[j] == mc.mujoco.mjtJoint.mjJNT_HINGE]
    names = [model.joint(j).name for j in hinge]
    kp, kd = zip(*(gains(n) for n in names), strict=True)
    armature = [MISSING_ARMATURE.get(n, float(model.dof_armature[model.jnt_dofadr[j]]))
                for n, j in zip(names, hinge, strict=True)]
    effort = [float(model.jnt_actfrcrange[j][1]) for j in hinge]
    q0 = np.array([default_angle(n) for n in names])

    n_steps = round(duration_s / PHYSICS_DT_S)
    n_control = math.ceil(n_steps * PHYSICS_DT_S / CONTROL_DT_S)
    tc = CONTROL_DT_S * np.arange(n_control)[:, None]
    freq = 0.5 + 0.05 * np.arange(len(names))[None, :]
    targets = q0 + 0.15 * np.sin(2 * np.pi * freq * tc)
    return {
        "scenario": scenario, "physics_dt_s": PHYSICS_DT_S, "control_dt_s": CONTROL_DT_S,
        "duration_s": duration_s, "gravity": [0.0, 0.0, -9.81],
        "fixed_base": scenario == "fixed-base", "joint_names": names,
        "kp": list(kp), "kd": list(kd), "effort_limit": effort, "armature": armature,
        "pd_form": "hybrid", "friction": 1.0,
        "initial": {"root_pos": ROOT_POS, "root_quat_wxyz": [1.0, 0.0, 0.0, 0.0],
                    "q": q0.tolist(), "qd": [0.0] * len(names)},
        "targets": targets.tolist(),
        "t": (PHYSICS_DT_S * np.arange(1, n_steps + 1)).tolist(),
        "q": np.zeros((n_steps, len(names))).tolist(),
        "root_pos": np.zeros((n_steps, 3)).tolist(),
        "root_quat_wxyz": np.zeros((n_steps, 4)).tolist(),
    }


def fill_with_mujoco(mjcf: Path, doc: dict[str, Any]) -> dict[str, Any]:
    """Return ``doc`` with its trajectory replaced by the script's own MuJoCo replay."""
    trace = mc.parse_trace(doc)
    run = mc.replay(mc.build_model(mjcf, trace), trace)
    return {**doc, "q": run.q.tolist(), "root_pos": run.root_pos.tolist(),
            "root_quat_wxyz": run.root_quat_wxyz.tolist()}


def run_main(tmp_path: Path, doc: dict[str, Any], capsys: pytest.CaptureFixture[str],
             *extra: str) -> tuple[int, dict[str, Any]]:
    path = tmp_path / f"{doc['scenario']}.json"
    path.write_text(json.dumps(doc))
    code = mc.main(["--mjcf", str(mc.DEFAULT_MJCF), "--trace-json", str(path), *extra])
    return code, json.loads(capsys.readouterr().out)


@pytest.fixture(scope="module")
def fixed_base_doc() -> dict[str, Any]:
    return fill_with_mujoco(mc.DEFAULT_MJCF, synthetic_inputs(mc.DEFAULT_MJCF, "fixed-base", 1.0))


@requires_mjcf
def test_identical_fixed_base_trace_has_zero_error(
        tmp_path: Path, fixed_base_doc: dict[str, Any], capsys: pytest.CaptureFixture[str]) -> None:
    q = np.array(fixed_base_doc["q"])
    assert np.all(np.isfinite(q)) and np.ptp(q, axis=0).max() > 0.05, (
        "replay should move the joints"
    )
    code, report = run_main(tmp_path, fixed_base_doc, capsys)
    assert code == 0
    assert report["mujoco_version"] == mc.mujoco.__version__
    assert report["fixed_base_rms_rad"] < 1e-12
    assert report["fixed_base_max_rad"] < 1e-12
    assert report["fixed_base_goal_met"] is True
    assert report["goal_fixed_base_rms_rad"] == 0.005
    assert set(report["fixed_base_per_joint_rms_rad"]) == set(fixed_base_doc["joint_names"])
    assert "mujoco_warnings" not in report
    assert not any(key.startswith("floating_") for key in report)


@requires_mjcf
@pytest.mark.parametrize("offset, enforce_code", [(0.01, 0), (0.03, 1)])
def test_perturbed_joint_shows_in_rms_and_max(
        tmp_path: Path, fixed_base_doc: dict[str, Any], capsys: pytest.CaptureFixture[str],
        offset: float, enforce_code: int) -> None:
    names = fixed_base_doc["joint_names"]
    j = names.index("left_knee_joint")
    q = np.array(fixed_base_doc["q"])
    q[:, j] += offset
    code, report = run_main(tmp_path, {**fixed_base_doc, "q": q.tolist()}, capsys, "--enforce")
    expected_rms = offset / math.sqrt(len(names))
    assert report["fixed_base_rms_rad"] == pytest.approx(expected_rms, rel=1e-6)
    assert report["fixed_base_max_rad"] == pytest.approx(offset, abs=1e-9)
    per_joint = report["fixed_base_per_joint_rms_rad"]
    assert per_joint["left_knee_joint"] == pytest.approx(offset, abs=1e-9)
    assert max(v for name, v in per_joint.items() if name != "left_knee_joint") < 1e-12
    assert report["fixed_base_goal_met"] is (enforce_code == 0)
    assert code == enforce_code


@requires_mjcf
def test_identical_floating_trace_has_zero_error(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    doc = fill_with_mujoco(mc.DEFAULT_MJCF, synthetic_inputs(mc.DEFAULT_MJCF, "floating", 0.5))
    root_pos = np.array(doc["root_pos"])
    assert abs(root_pos[-1, 2] - root_pos[0, 2]) > 1e-4, "the floating pelvis should move"
    code, report = run_main(tmp_path, doc, capsys)
    assert code == 0
    for key in ("floating_pelvis_z_rms_m", "floating_pelvis_xy_rms_m", "floating_joint_rms_rad"):
        assert report[key] < 1e-12, key
    assert report["floating_mujoco_pelvis_z_end_m"] == pytest.approx(
        report["floating_ours_pelvis_z_end_m"], abs=1e-12)
    assert not any(key.startswith("fixed_base") for key in report)


def test_missing_mjcf_is_skipped(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code = mc.main(["--mjcf", str(tmp_path / "absent.xml"), "--trace-json", "unused.json"])
    assert code == 0
    assert "skipped" in json.loads(capsys.readouterr().out)


@requires_mjcf
def test_missing_binary_is_a_clear_error(capsys: pytest.CaptureFixture[str]) -> None:
    code = mc.main(["--mjcf", str(mc.DEFAULT_MJCF), "--thorarena", "/nonexistent/thorarena"])
    assert code == 2
    assert "cargo build --release" in capsys.readouterr().err
