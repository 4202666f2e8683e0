"""tools/compliance.py on hand-made traces: a wrist that yields a known distance along the
event's force gives the stiffness it should, whatever the motion both episodes share; runs
it cannot measure are refused with the reason."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import compliance

EVENT = "event:20@{h}:hand=right:up=0:start=2:ramp=0.5:hold=1:release=0.5"
WRIST = 6  # right_wrist_yaw_link in the default set


def steps(yield_m: float, direction: tuple[float, float, float]) -> list[dict[str, object]]:
    """4 s at 50 Hz: the wrist sways along y (the shared motion) and, during the event's
    ramp and hold, yields `yield_m` along `direction`, with 20 N acting along it."""
    out: list[dict[str, object]] = []
    for k in range(200):
        t = k * 0.02
        acting = 2.0 <= t < 3.5
        sway = 0.05 * (k % 7)
        kp = [[0.0, 0.0, 0.0] for _ in range(13)]
        d = yield_m if acting else 0.0
        kp[WRIST] = [0.3 + d * direction[0], sway + d * direction[1], 1.0 + d * direction[2]]
        force = [20.0 * c for c in direction] if acting else [0.0, 0.0, 0.0]
        out.append({"time_s": t, "keypoints_w": kp, "hand_force_w": [[0.0, 0.0, 0.0], force]})
    return out


def write_run(d: Path, yields: dict[int, float], stiffness: float | None = 100.0) -> Path:
    (d / "traces").mkdir(parents=True)
    params = {"stiffness_n_per_m": stiffness} if stiffness is not None else {}
    (d / "run.json").write_text(json.dumps({"keypoints": "default", "policy_parameters": params}))
    (d / "traces" / "stand-stand-no-force.json").write_text(json.dumps(steps(0.0, (1.0, 0.0, 0.0))))
    for h, y in yields.items():
        direction = {0: (1.0, 0.0, 0.0), 90: (0.0, 1.0, 0.0)}[h]
        name = "stand-stand-" + EVENT.format(h=h) + ".json"
        (d / "traces" / name).write_text(json.dumps(steps(y, direction)))
    return d


def test_a_known_yield_gives_force_over_yield(tmp_path: Path) -> None:
    run = write_run(tmp_path / "sweep-100", {0: 0.2, 90: 0.2})
    k, measured = compliance.measure_run(run, window_s=0.5)
    assert k == 100.0
    assert [round(m.yield_m, 9) for m in measured] == [0.2, 0.2]
    assert all(abs(m.effective_n_per_m - 100.0) < 1e-6 for m in measured)
    text = compliance.table([("sweep-100", k, measured)])
    assert "| sweep-100 | 100.0 | 20 | 200.0 / 200.0 | 200.0 | 100 | 1.00 |" in text


def test_the_figure_draws_a_sweep_and_leaves_a_baseline_out(tmp_path: Path) -> None:
    a = write_run(tmp_path / "pair-50", {0: 0.4})
    b = write_run(tmp_path / "pair-baseline", {0: 0.01})
    svg_path = tmp_path / "f.svg"
    assert compliance.main([str(a), str(b), "--svg", str(svg_path)]) == 0
    svg = svg_path.read_text()
    assert svg.count("<circle") == 1 and ">pair<" in svg


def test_runs_that_cannot_be_measured_are_refused(tmp_path: Path) -> None:
    run = write_run(tmp_path / "r", {0: 0.1})
    (run / "traces" / "stand-stand-no-force.json").unlink()
    with pytest.raises(compliance.ComplianceError, match="one traced no-force episode"):
        compliance.measure_run(run, 0.5)
    with pytest.raises(compliance.ComplianceError, match="no canonical event"):
        compliance.parse_event("event:20@0:hand=right")
    assert compliance.parse_event("push-20@0") is None
