#!/usr/bin/env python3
"""Measure MuJoCo's cost of one physics step for the floating G1 standing under PD.

This is the reference point for ThorArena's own step-time benchmark: the same
robot (the reference MJCF, unmodified, at its own timestep of 0.001 s) standing
on the floor in the default pose, held by legged-gym style PD gains. The PD
torques are computed in Python each step and applied through ``qfrc_applied``,
but only ``mj_step`` is timed, so the figure is MuJoCo's cost alone.

Prints one JSON object on stdout: the median microseconds per step over the
repeats, the timestep, the contact count at the end, simulated seconds per wall
second and the MuJoCo version, plus the final pelvis height: the default
legged-gym gains cannot hold the pose open loop (ankle kp 40 is below the
toppling stiffness), so the robot tips over after about 1.5 s. ``thorarena bench
physics`` therefore passes its own stiffer standing gains with ``--gains-json``,
so both engines time the same upright robot. If the MJCF is missing it prints
``{"skipped": reason}`` and exits 0.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

REPO_ROOT = Path(__file__).resolve().parent.parent
# $THORARENA_REFERENCE, else ../shared/reference beside the repository (README).
REFERENCE_DIR = Path(
    os.environ.get("THORARENA_REFERENCE") or REPO_ROOT.parent / "shared" / "reference"
)
DEFAULT_MJCF = REFERENCE_DIR / "g1" / "g1_sim2sim_29dof.xml"
WARMUP_STEPS = 200
# Below this pelvis height the robot counts as fallen (it stands at about 0.77 m).
STANDING_MIN_PELVIS_Z_M = 0.5

# (kp, kd) keyed by the joint name without its left_/right_ prefix (legged-gym style).
LEG_GAINS = {
    "hip_pitch_joint": (100.0, 2.0), "hip_roll_joint": (100.0, 2.0), "hip_yaw_joint": (100.0, 2.0),
    "knee_joint": (150.0, 4.0), "ankle_pitch_joint": (40.0, 2.0), "ankle_roll_joint": (40.0, 2.0),
}
WAIST_GAINS = (150.0, 4.0)
ARM_GAINS = (40.0, 5.0)
# Standing pose keyed like LEG_GAINS; the right shoulder roll is mirrored; other joints 0.
DEFAULT_POSE = {"hip_pitch_joint": -0.2, "knee_joint": 0.4, "ankle_pitch_joint": -0.2,
                "shoulder_roll_joint": 0.4, "elbow_joint": 1.2}


def default_angle(joint: str) -> float:
    side, _, base = joint.partition("_")
    angle = DEFAULT_POSE.get(base, 0.0)
    return -angle if side == "right" and base == "shoulder_roll_joint" else angle


def gains(joint: str) -> tuple[float, float]:
    if joint.startswith("waist_"):
        return WAIST_GAINS
    return LEG_GAINS.get(joint.partition("_")[2], ARM_GAINS)


class StandingPd:
    """The G1 in its standing pose, with a PD controller holding that pose."""

    def __init__(self, model: mujoco.MjModel, gains_override: dict[str, Any] | None = None) -> None:
        hinges = [j for j in range(model.njnt) if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE]
        if len(hinges) != model.njnt - 1 or model.jnt_type[0] != mujoco.mjtJoint.mjJNT_FREE:
            raise ValueError("expected a floating base (freejoint first) and hinge joints only")
        names = [model.joint(j).name for j in hinges]
        self.model = model
        self.data = mujoco.MjData(model)
        self.qpos_adr = model.jnt_qposadr[hinges]
        self.dof_adr = model.jnt_dofadr[hinges]
        self.q_default = np.array([default_angle(n) for n in names])
        self.kp, self.kd = (np.array(g) for g in zip(*(gains(n) for n in names), strict=True))
        if gains_override is not None:
            # strict=False: a short kp/kd list leaves joints out, reported as missing below.
            kp_kd = zip(gains_override["kp"], gains_override["kd"], strict=False)
            by_name = dict(zip(gains_override["joint_names"], kp_kd, strict=False))
            missing = [n for n in names if n not in by_name]
            if missing:
                raise ValueError(f"--gains-json lacks joints: {', '.join(missing)}")
            self.kp = np.array([by_name[n][0] for n in names])
            self.kd = np.array([by_name[n][1] for n in names])
        self.effort_limit = model.jnt_actfrcrange[hinges, 1]
        # Root pose (pelvis height) from the file's qpos0; joints at the default pose.
        self.data.qpos[:] = model.qpos0
        self.data.qpos[self.qpos_adr] = self.q_default
        mujoco.mj_forward(model, self.data)

    def apply_pd(self) -> None:
        """Set qfrc_applied to the clipped PD torques for the current state."""
        q = self.data.qpos[self.qpos_adr]
        qd = self.data.qvel[self.dof_adr]
        tau = self.kp * (self.q_default - q) - self.kd * qd
        self.data.qfrc_applied[self.dof_adr] = np.clip(tau, -self.effort_limit, self.effort_limit)

    def run(self, steps: int) -> float:
        """Advance ``steps`` physics steps; return the wall time spent inside mj_step only."""
        spent = 0.0
        for _ in range(steps):
            self.apply_pd()
            start = time.perf_counter()
            mujoco.mj_step(self.model, self.data)
            spent += time.perf_counter() - start
        return spent


def bench(
    mjcf: Path, steps: int, repeats: int, gains_override: dict[str, Any] | None = None
) -> dict[str, Any]:
    model = mujoco.MjModel.from_xml_path(str(mjcf))
    sim = StandingPd(model, gains_override)
    sim.run(WARMUP_STEPS)
    us_per_step = [sim.run(steps) / steps * 1e6 for _ in range(repeats)]
    median_us = statistics.median(us_per_step)
    dt = float(model.opt.timestep)
    return {
        "mujoco_version": mujoco.__version__,
        "mjcf": str(mjcf),
        "dt_s": dt,
        "steps": steps,
        "repeats": repeats,
        "median_us_per_step": median_us,
        "us_per_step_per_repeat": us_per_step,
        "ncon": int(sim.data.ncon),
        "pelvis_z_end_m": float(sim.data.qpos[2]),
        "standing_at_end": bool(sim.data.qpos[2] > STANDING_MIN_PELVIS_Z_M),
        "sim_seconds_per_wall_second": dt / (median_us * 1e-6),
    }


def positive_int(text: str) -> int:
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be >= 1, got {value}")
    return value


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--mjcf", type=Path, default=DEFAULT_MJCF,
                        help="reference G1 MJCF (default: %(default)s)")
    parser.add_argument("--steps", type=positive_int, default=2000,
                        help="timed steps per repeat (default: %(default)s)")
    parser.add_argument("--repeats", type=positive_int, default=5,
                        help="number of timed repeats; the median is reported "
                             "(default: %(default)s)")
    parser.add_argument("--gains-json", type=str, default=None,
                        help='gains to use instead of the legged-gym ones, as JSON '
                             '{"joint_names": [...], "kp": [...], "kd": [...]} '
                             '(thorarena bench physics passes its standing gains so that both '
                             'engines hold the same robot upright)')
    args = parser.parse_args(argv)
    if not args.mjcf.is_file():
        reason = f"reference MJCF not found at {args.mjcf}"
        print(f"[step_bench] skipped: {reason}", file=sys.stderr)
        print(json.dumps({"skipped": reason}))
        return 0
    gains_override = json.loads(args.gains_json) if args.gains_json else None
    print(json.dumps(bench(args.mjcf.resolve(), args.steps, args.repeats, gains_override)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
