#!/usr/bin/env python3
"""Cross-check ThorArena's rapier backend against MuJoCo on open-loop G1 scenarios.

MuJoCo is the field's reference simulator for the Unitree G1, so a benchmark
built on rapier has to show that its dynamics agree with MuJoCo before its
numbers mean anything. This script takes the trajectory our binary recorded
(``thorarena sim trace --scenario fixed-base|floating``) together with the exact
inputs it used (gains, effort limits, armature, initial state, the target
sequence), replays those inputs open loop in MuJoCo on the reference MJCF with
the same physics model, and reports how far the two trajectories are apart:

* fixed-base: RMS / max joint-angle difference over all joints and all physics
  steps, plus the RMS per joint; the goal is an RMS below 0.005 rad.
* floating: over the first ``FLOATING_WINDOW_S`` seconds, the RMS of the
  pelvis-height difference, of the horizontal pelvis distance and of the
  joint-angle difference, plus both pelvis heights at the end of the run.

The MuJoCo model is made to match ours: timestep = the trace's physics dt,
implicitfast integrator, the trace's gravity; joint armature from the trace;
the PD law in its "hybrid" form (kd is the joint's implicit damping, the
clipped ``kp * (target - q)`` is applied explicitly through ``qfrc_applied``);
no joint friction loss; only the ankle-roll foot spheres touch the floor, with
the trace's sliding friction; a fixed base welds the pelvis at the initial pose.

Prints exactly one JSON object on stdout; all diagnostics go to stderr.
Exit codes: 0 ran (or skipped because the MJCF is absent), 1 ``--enforce`` and
the fixed-base goal is missed, 2 usage or input errors.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

REPO_ROOT = Path(__file__).resolve().parent.parent
DEFAULT_THORARENA = REPO_ROOT / "target" / "release" / "thorarena"
# The published reference artifacts (docs/policies.md, "Reference artifacts"): $THORARENA_REFERENCE,
# else ../shared/reference beside the repository.
REFERENCE_DIR = Path(
    os.environ.get("THORARENA_REFERENCE") or REPO_ROOT.parent / "shared" / "reference"
)
DEFAULT_MJCF = REFERENCE_DIR / "g1" / "g1_sim2sim_29dof.xml"

SCENARIOS = ("fixed-base", "floating")
GOAL_FIXED_BASE_RMS_RAD = 0.005
FLOATING_WINDOW_S = 2.0
FOOT_BODIES = ("left_ankle_roll_link", "right_ankle_roll_link")
FLOOR_GEOM = "floor"
FREEJOINT = "pelvis"
ROOT_BODY = "pelvis"
# Physics step k uses targets[floor(k * physics_dt / control_dt + TARGET_INDEX_EPS)].
TARGET_INDEX_EPS = 1e-9
TIME_TOLERANCE_S = 1e-5


class CrosscheckError(Exception):
    """An input problem that the user has to fix (bad trace, failed binary, ...)."""


@dataclass(frozen=True)
class Trace:
    """One scenario as recorded by our binary: the inputs used and our trajectory."""

    scenario: str
    physics_dt: float
    control_dt: float
    gravity: np.ndarray  # (3,)
    fixed_base: bool
    joint_names: list[str]
    kp: np.ndarray  # (J,)
    kd: np.ndarray  # (J,)
    effort_limit: np.ndarray  # (J,)
    armature: np.ndarray  # (J,)
    friction: float
    root_pos0: np.ndarray  # (3,)
    root_quat0_wxyz: np.ndarray  # (4,)
    q0: np.ndarray  # (J,)
    qd0: np.ndarray  # (J,)
    targets: np.ndarray  # (n_control, J)
    t: np.ndarray  # (n,) time after each physics step
    q: np.ndarray  # (n, J)
    root_pos: np.ndarray  # (n, 3)
    root_quat_wxyz: np.ndarray  # (n, 4)

    @property
    def n_steps(self) -> int:
        return len(self.t)

    def target_index(self, step: int) -> int:
        """Index of the control target held during physics step ``step`` (0-based)."""
        return math.floor(step * self.physics_dt / self.control_dt + TARGET_INDEX_EPS)


@dataclass(frozen=True)
class MujocoRun:
    """MuJoCo's trajectory for a trace, sampled after each physics step."""

    q: np.ndarray  # (n, J)
    root_pos: np.ndarray  # (n, 3)
    root_quat_wxyz: np.ndarray  # (n, 4)
    warnings: dict[str, int]  # MuJoCo warnings raised during the run, by name


def _array(doc: dict[str, Any], key: str, shape: tuple[int, ...]) -> np.ndarray:
    """Read ``doc[key]`` as a float array of the given shape (-1 = any length)."""
    if key not in doc:
        raise CrosscheckError(f"trace is missing key {key!r}")
    try:
        arr = np.asarray(doc[key], dtype=float)
    except (TypeError, ValueError) as exc:
        raise CrosscheckError(f"trace key {key!r} is not a numeric array: {exc}") from exc
    if arr.ndim != len(shape) or any(
        want not in (-1, got) for want, got in zip(shape, arr.shape, strict=True)
    ):
        raise CrosscheckError(
            f"trace key {key!r} has shape {arr.shape}, expected {shape} (-1 = any)")
    if not np.all(np.isfinite(arr)):
        raise CrosscheckError(f"trace key {key!r} contains non-finite values")
    return arr


def parse_trace(doc: dict[str, Any]) -> Trace:
    """Validate a trace JSON object (the contract of ``thorarena sim trace``) into a Trace."""
    for key in ("scenario", "physics_dt_s", "control_dt_s", "fixed_base", "joint_names",
                "pd_form", "friction", "initial"):
        if key not in doc:
            raise CrosscheckError(f"trace is missing key {key!r}")
    scenario = doc["scenario"]
    if scenario not in SCENARIOS:
        raise CrosscheckError(f"unknown scenario {scenario!r}; expected one of {SCENARIOS}")
    fixed_base = doc["fixed_base"]
    if fixed_base is not (scenario == "fixed-base"):
        raise CrosscheckError(f"scenario {scenario!r} has inconsistent fixed_base={fixed_base!r}")
    if doc["pd_form"] != "hybrid":
        raise CrosscheckError(
            f"pd_form {doc['pd_form']!r} is not supported; the MuJoCo replay implements 'hybrid' "
            "(kd as implicit joint damping, kp term applied explicitly)")
    physics_dt = float(doc["physics_dt_s"])
    control_dt = float(doc["control_dt_s"])
    if not (physics_dt > 0 and control_dt > 0):
        raise CrosscheckError(
            f"physics_dt_s={physics_dt} and control_dt_s={control_dt} must be > 0")

    names = doc["joint_names"]
    if not (isinstance(names, list) and names and all(isinstance(n, str) for n in names)):
        raise CrosscheckError("joint_names must be a non-empty list of strings")
    if len(set(names)) != len(names):
        raise CrosscheckError("joint_names contains duplicates")
    n_joints = len(names)
    initial = doc["initial"]
    if not isinstance(initial, dict):
        raise CrosscheckError("trace key 'initial' must be an object")

    t = _array(doc, "t", (-1,))
    n = len(t)
    if n == 0:
        raise CrosscheckError("trace has no physics steps ('t' is empty)")
    trace = Trace(
        scenario=scenario,
        physics_dt=physics_dt,
        control_dt=control_dt,
        gravity=_array(doc, "gravity", (3,)),
        fixed_base=fixed_base,
        joint_names=list(names),
        kp=_array(doc, "kp", (n_joints,)),
        kd=_array(doc, "kd", (n_joints,)),
        effort_limit=_array(doc, "effort_limit", (n_joints,)),
        armature=_array(doc, "armature", (n_joints,)),
        friction=float(doc["friction"]),
        root_pos0=_array(initial, "root_pos", (3,)),
        root_quat0_wxyz=_array(initial, "root_quat_wxyz", (4,)),
        q0=_array(initial, "q", (n_joints,)),
        qd0=_array(initial, "qd", (n_joints,)),
        targets=_array(doc, "targets", (-1, n_joints)),
        t=t,
        q=_array(doc, "q", (n, n_joints)),
        root_pos=_array(doc, "root_pos", (n, 3)),
        root_quat_wxyz=_array(doc, "root_quat_wxyz", (n, 4)),
    )
    expected_t = physics_dt * np.arange(1, n + 1)
    worst = float(np.max(np.abs(t - expected_t)))
    if worst > TIME_TOLERANCE_S:
        raise CrosscheckError(f"trace 't' deviates from (k+1)*physics_dt_s by up to {worst:.3g} s")
    needed = trace.target_index(n - 1) + 1
    if len(trace.targets) < needed:
        raise CrosscheckError(
            f"trace has {len(trace.targets)} targets but {n} physics steps need {needed}")
    if np.any(trace.effort_limit < 0):
        raise CrosscheckError("effort_limit must be >= 0")
    return trace


def _set_linear_damping(joint: mujoco.MjsJoint, kd: float) -> None:
    """Make ``kd`` the joint's only damping term.

    MuJoCo 4.0 stores polynomial damping coefficients ``[linear, higher orders...]``;
    MuJoCo 3.3 stores the linear coefficient as a scalar.
    """
    if np.ndim(joint.damping) == 0:
        joint.damping = kd
    else:
        coefficients = np.zeros_like(joint.damping)
        coefficients[0] = kd
        joint.damping = coefficients


def build_model(mjcf: Path, trace: Trace) -> mujoco.MjModel:
    """Compile the reference MJCF with the physics settings of ``trace`` (see module doc)."""
    spec = mujoco.MjSpec.from_file(str(mjcf))
    spec.option.timestep = trace.physics_dt
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.gravity = trace.gravity

    for name, kd, armature in zip(trace.joint_names, trace.kd, trace.armature, strict=True):
        joint = spec.joint(name)
        if joint is None:
            raise CrosscheckError(f"joint {name!r} from the trace does not exist in {mjcf}")
        _set_linear_damping(joint, float(kd))
        joint.armature = float(armature)
        joint.frictionloss = 0.0

    floor_found = False
    feet_found = 0
    for geom in spec.geoms:
        if geom.name == FLOOR_GEOM:
            # Floor collides with geoms whose conaffinity has bit 0 (the feet only).
            geom.contype, geom.conaffinity = 1, 0
            geom.friction[0] = trace.friction
            floor_found = True
        elif geom.type == mujoco.mjtGeom.mjGEOM_SPHERE and geom.parent.name in FOOT_BODIES:
            # contype 0 keeps foot spheres from touching each other (no self-contact).
            geom.contype, geom.conaffinity = 0, 1
            geom.friction[0] = trace.friction
            feet_found += 1
        else:
            geom.contype, geom.conaffinity = 0, 0
    if not floor_found:
        raise CrosscheckError(f"no geom named {FLOOR_GEOM!r} in {mjcf}")
    if feet_found == 0:
        raise CrosscheckError(f"no sphere geoms on {FOOT_BODIES} in {mjcf}")

    if trace.fixed_base:
        freejoint = spec.joint(FREEJOINT)
        if freejoint is None:
            raise CrosscheckError(f"no freejoint {FREEJOINT!r} in {mjcf} to remove for fixed base")
        spec.delete(freejoint)
        # Keyframes were written for the floating model's qpos size.
        for key in list(spec.keys):
            spec.delete(key)
        root = spec.body(ROOT_BODY)
        if root is None:
            raise CrosscheckError(f"no body {ROOT_BODY!r} in {mjcf} to weld for fixed base")
        root.pos = trace.root_pos0
        root.quat = trace.root_quat0_wxyz
    return spec.compile()


def _joint_addresses(model: mujoco.MjModel, names: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """qpos and dof addresses of the named hinge joints, in the order of ``names``."""
    qpos_adr, dof_adr = [], []
    for name in names:
        jid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)
        if jid < 0:
            raise CrosscheckError(f"joint {name!r} not found in the compiled model")
        qpos_adr.append(model.jnt_qposadr[jid])
        dof_adr.append(model.jnt_dofadr[jid])
    return np.array(qpos_adr), np.array(dof_adr)


def replay(model: mujoco.MjModel, trace: Trace) -> MujocoRun:
    """Run the trace's inputs open loop in MuJoCo for as many physics steps as the trace has."""
    qpos_adr, dof_adr = _joint_addresses(model, trace.joint_names)
    data = mujoco.MjData(model)
    if not trace.fixed_base:
        data.qpos[0:3] = trace.root_pos0
        data.qpos[3:7] = trace.root_quat0_wxyz / np.linalg.norm(trace.root_quat0_wxyz)
    data.qpos[qpos_adr] = trace.q0
    data.qvel[dof_adr] = trace.qd0
    mujoco.mj_forward(model, data)

    n = trace.n_steps
    q = np.empty((n, len(trace.joint_names)))
    root_pos = np.tile(trace.root_pos0, (n, 1))
    root_quat = np.tile(trace.root_quat0_wxyz, (n, 1))
    for k in range(n):
        target = trace.targets[trace.target_index(k)]
        tau = np.clip(
            trace.kp * (target - data.qpos[qpos_adr]), -trace.effort_limit, trace.effort_limit
        )
        data.qfrc_applied[dof_adr] = tau
        mujoco.mj_step(model, data)
        q[k] = data.qpos[qpos_adr]
        if not trace.fixed_base:
            # qpos rather than xpos: after mj_step, xpos still holds the pre-step pose.
            root_pos[k] = data.qpos[0:3]
            root_quat[k] = data.qpos[3:7]
    warnings = {
        mujoco.mjtWarning(i).name: int(data.warning[i].number)
        for i in range(int(mujoco.mjtWarning.mjNWARNING))
        if data.warning[i].number > 0
    }
    return MujocoRun(q=q, root_pos=root_pos, root_quat_wxyz=root_quat, warnings=warnings)


def _rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(x))))


def compare_fixed_base(trace: Trace, run: MujocoRun) -> dict[str, Any]:
    """Joint-angle agreement over all joints and all physics steps."""
    diff = trace.q - run.q
    rms = _rms(diff)
    return {
        "fixed_base_rms_rad": rms,
        "fixed_base_max_rad": float(np.max(np.abs(diff))),
        "fixed_base_per_joint_rms_rad": {
            name: _rms(diff[:, j]) for j, name in enumerate(trace.joint_names)
        },
        "goal_fixed_base_rms_rad": GOAL_FIXED_BASE_RMS_RAD,
        "fixed_base_goal_met": rms <= GOAL_FIXED_BASE_RMS_RAD,
    }


def compare_floating(trace: Trace, run: MujocoRun) -> dict[str, Any]:
    """Pelvis and joint agreement over the first FLOATING_WINDOW_S seconds, plus end heights."""
    window = trace.t <= FLOATING_WINDOW_S + TIME_TOLERANCE_S
    dz = trace.root_pos[window, 2] - run.root_pos[window, 2]
    dxy = np.linalg.norm(trace.root_pos[window, :2] - run.root_pos[window, :2], axis=1)
    return {
        "floating_window_s": FLOATING_WINDOW_S,
        "floating_pelvis_z_rms_m": _rms(dz),
        "floating_pelvis_xy_rms_m": _rms(dxy),
        "floating_joint_rms_rad": _rms(trace.q[window] - run.q[window]),
        "floating_mujoco_pelvis_z_end_m": float(run.root_pos[-1, 2]),
        "floating_ours_pelvis_z_end_m": float(trace.root_pos[-1, 2]),
    }


def crosscheck(mjcf: Path, traces: list[Trace]) -> dict[str, Any]:
    """Replay every trace in MuJoCo and merge the comparison metrics into one report."""
    report: dict[str, Any] = {"mujoco_version": mujoco.__version__, "mjcf": str(mjcf)}
    mujoco_warnings: dict[str, dict[str, int]] = {}
    for trace in traces:
        print(f"[crosscheck] replaying {trace.scenario}: {trace.n_steps} steps at "
              f"dt={trace.physics_dt} s", file=sys.stderr)
        run = replay(build_model(mjcf, trace), trace)
        if run.warnings:
            print(f"[crosscheck] WARNING: MuJoCo raised {run.warnings} in {trace.scenario}; "
                  "its trajectory is not trustworthy", file=sys.stderr)
            mujoco_warnings[trace.scenario] = run.warnings
        if trace.fixed_base:
            report.update(compare_fixed_base(trace, run))
        else:
            report.update(compare_floating(trace, run))
    if mujoco_warnings:
        report["mujoco_warnings"] = mujoco_warnings
    return report


def _load_json(text: str, source: str) -> dict[str, Any]:
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise CrosscheckError(f"{source} is not valid JSON: {exc}") from exc
    if not isinstance(doc, dict):
        raise CrosscheckError(f"{source} must hold one JSON object")
    return doc


def trace_from_binary(thorarena: Path, scenario: str) -> Trace:
    """Run ``thorarena sim trace --scenario <scenario>`` and parse its stdout."""
    if not thorarena.is_file():
        raise CrosscheckError(
            f"thorarena binary not found at {thorarena}; build with cargo build --release "
            "(or pass --thorarena PATH / --trace-json FILE)")
    cmd = [str(thorarena), "sim", "trace", "--scenario", scenario]
    print(f"[crosscheck] running {' '.join(cmd)}", file=sys.stderr)
    proc = subprocess.run(cmd, stdout=subprocess.PIPE, text=True, check=False)
    if proc.returncode != 0:
        raise CrosscheckError(f"{' '.join(cmd)} exited with code {proc.returncode}")
    return parse_trace(_load_json(proc.stdout, f"stdout of {' '.join(cmd)}"))


def trace_from_file(path: Path) -> Trace:
    try:
        text = path.read_text()
    except OSError as exc:
        raise CrosscheckError(f"cannot read trace file {path}: {exc}") from exc
    return parse_trace(_load_json(text, str(path)))


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--thorarena", type=Path, default=DEFAULT_THORARENA,
                        help="thorarena binary (default: %(default)s)")
    parser.add_argument("--mjcf", type=Path, default=DEFAULT_MJCF,
                        help="reference G1 MJCF (default: %(default)s)")
    parser.add_argument("--trace-json", type=Path, action="append", default=[], metavar="FILE",
                        help="read a trace from FILE instead of running the binary (repeatable)")
    parser.add_argument("--enforce", action="store_true",
                        help=f"exit 1 if fixed_base_rms_rad > {GOAL_FIXED_BASE_RMS_RAD} "
                             "(or was not measured)")
    return parser.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    if not args.mjcf.is_file():
        reason = f"reference MJCF not found at {args.mjcf}"
        print(f"[crosscheck] skipped: {reason}", file=sys.stderr)
        print(json.dumps({"skipped": reason}))
        return 0
    try:
        if args.trace_json:
            traces = [trace_from_file(path) for path in args.trace_json]
        else:
            traces = [trace_from_binary(args.thorarena, scenario) for scenario in SCENARIOS]
        scenarios = [trace.scenario for trace in traces]
        if len(set(scenarios)) != len(scenarios):
            raise CrosscheckError(f"each scenario may be given once, got {scenarios}")
        report = crosscheck(args.mjcf.resolve(), traces)
    except CrosscheckError as exc:
        print(f"[crosscheck] error: {exc}", file=sys.stderr)
        return 2
    print(json.dumps(report))
    if args.enforce:
        if "fixed_base_rms_rad" not in report:
            print("[crosscheck] --enforce: the fixed-base scenario was not run", file=sys.stderr)
            return 1
        if not report["fixed_base_goal_met"]:
            print(f"[crosscheck] --enforce: fixed_base_rms_rad {report['fixed_base_rms_rad']:.4g} "
                  f"exceeds the goal {GOAL_FIXED_BASE_RMS_RAD}", file=sys.stderr)
            return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
