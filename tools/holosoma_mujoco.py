#!/usr/bin/env python3
"""Reference run of holosoma's published G1 whole-body tracking policy in MuJoCo.

Establishes what "the policy tracks its own motion" means in its authors' simulator, so
ThorArena's numbers for the same policy have something to be compared with. The policy
(``fastsac_g1_29dof_dancing.onnx``) embeds its motion: given ``time_step`` it returns the
reference joint positions/velocities and the pose of ``torso_link`` at that step besides the
action. This script rebuilds holosoma's inference loop (sim-to-sim, MuJoCo) around it:

* Scene: holosoma's MJCF (``g1_29dof.xml``; it has no floor and no <option>), loaded through
  MjSpec with the mesh directory fixed when the XML's own does not resolve, plus the ground
  plane holosoma's scene manager adds (named ``floor``, which the MJCF's foot <pair>s
  reference): friction 0.7/0.005/0.001, solref 0.001 1, solimp 0.99 0.99 0.01 0.5 2,
  contype 2 / conaffinity 1 (holosoma ``simulator/mujoco/scene_manager.py``,
  ``_create_ground_plane``). Physics dt 0.002 s, MuJoCo's default integrator and solver.
* Observation (154), its terms concatenated in **alphabetical order** -- holosoma sorts the
  terms of a group both in training (``managers/observation/manager.py``, ``compute_group``:
  ``sorted(obs_tensors.keys())``) and at inference (``holosoma_inference/policies/base.py``,
  ``obs_terms_sorted``); the network's own observation normaliser confirms it (its mean is
  ~[1, 0, 0, 1, 0, 0] on the last six inputs, the rotation-matrix columns):
  ``actions`` (29, last raw output clipped to +-100), ``base_ang_vel`` (3, pelvis angular
  velocity in the pelvis frame, i.e. the IMU gyro), ``dof_pos`` (29, q - default),
  ``dof_vel`` (29), ``motion_command`` (58, reference joint_pos ++ joint_vel),
  ``motion_ref_ori_b`` (6, first two columns, row-major, of the rotation
  R(robot torso)^T R(reference torso), each with its start yaw removed --
  ``inference/policies/wbt.py:262-277``).
* Action: clip +-100 (``wbt.py:308``), times ``policy_action_scale`` 1.0
  (``config_values/task.py``, ``wbt``), PD target = default_dof_angles + scaled action
  (``holosoma_inference/policies/base.py``, ``policy_action``). PD torque
  kp (q* - q) - kd qd with kp/kd from the ONNX metadata, computed every physics step and
  clipped to the joint effort limits (holosoma ``bridge/base/basic_sdk2py_bridge.py``,
  ``_compute_pd_torques``; the limits equal the MJCF's ``actuatorfrcrange``), applied as
  generalised forces. 50 Hz policy (``task.py``: ``rl_rate=50``).
* Episode (ThorArena's protocol): the robot starts at the reference's first frame (joints and
  joint velocities from the network's step-0 outputs, pelvis pose solved from the reference
  torso pose through the kinematics, zero root velocity). At control step k the observation is
  built from the current state and the reference at step k (``--command-lag 0``), or at
  step k-1 as ``wbt.py`` does (it feeds the motion outputs of the previous call,
  ``wbt.py:266,305``; ``--command-lag 1``); after the 10 physics substeps the state is
  compared with reference frame k+1.
* Metrics, as ThorArena's ``src/eval/episode.rs``: fall when |torso height - reference torso
  height| > 0.25 m or the angle between R_robot^T(-z) and R_ref^T(-z) > 0.8 rad; survival =
  recorded steps / reference steps; per-step keypoint error = mean distance over 13 body
  origins with the reference re-anchored to the robot's pelvis by the full pose
  (``src/eval/metrics/keypoints.rs``, ``reanchor``: world_from_robot_root * ref_root^-1). A
  yaw + horizontal-translation re-anchoring is reported alongside.

Measured with the defaults (MuJoCo 4.0.0): the motion has 6774 frames (135.46 s at 50 Hz;
its first frames are the default-pose lead-in holosoma prepends, 4 cm above the floor);
survival 1.0, keypoint error mean 46.6 mm, RMS 49.4 mm, about 6 s of wall time on one core.
The listed term order falls in 0.26 s, a PD target without the default pose in 3.3 s, a
world-frame base_ang_vel in 19 s; ``--command-lag 1`` survives or falls at 29-30 s depending
on dt and on ``--hold-s`` (the dance's hardest segment), as does clamping hip_roll to the
actuators' 88 N m ctrlrange.

Prints a human-readable summary, or one JSON object with ``--json``; diagnostics go to
stderr. Exit codes: 0 ran (or skipped because the reference artifacts are absent), 2 usage
or input errors. Uses one CPU core (OMP_NUM_THREADS=1, onnxruntime with one thread).
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse
import json
import math
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import mujoco
import numpy as np
import numpy.typing as npt
from g1_keypoints import DEFAULT_KEYPOINT_BODIES
from holosoma_policy import (
    Array,
    Policy,
    Reference,
    UsageError,
    load_policy,
    probe_last_frame,
    reference_table,
)

REPO_ROOT = Path(__file__).resolve().parent.parent
# The published reference artifacts (docs/policies.md, "Reference artifacts"): $THORARENA_REFERENCE,
# else ../shared/reference beside the repository.
REFERENCE_DIR = Path(
    os.environ.get("THORARENA_REFERENCE") or REPO_ROOT.parent / "shared" / "reference"
)
DEFAULT_ONNX = REFERENCE_DIR / "holosoma" / "fastsac_g1_29dof_dancing.onnx"
DEFAULT_MJCF = REFERENCE_DIR / "holosoma" / "g1_29dof.xml"
DEFAULT_MESHDIR = REFERENCE_DIR / "g1" / "meshes"

CONTROL_DT_S = 0.02  # rl_rate 50 (holosoma inference config_values/task.py, wbt)
PHYSICS_DT_S = 0.002
ACTION_CLIP = 100.0  # wbt.py:308
ACTION_SCALE = 1.0  # config_values/task.py, wbt: policy_action_scale
# g1_29dof default_dof_angles (config_values/robot.py), in the robot's dof_names order.
DEFAULT_DOF_ANGLES = {
    "left_hip_pitch_joint": -0.312,
    "left_knee_joint": 0.669,
    "left_ankle_pitch_joint": -0.363,
    "right_hip_pitch_joint": -0.312,
    "right_knee_joint": 0.669,
    "right_ankle_pitch_joint": -0.363,
    "left_shoulder_pitch_joint": 0.2,
    "left_shoulder_roll_joint": 0.2,
    "left_elbow_joint": 0.6,
    "right_shoulder_pitch_joint": 0.2,
    "right_shoulder_roll_joint": -0.2,
    "right_elbow_joint": 0.6,
}
OBS_DIMS = {
    "actions": 29,
    "base_ang_vel": 3,
    "dof_pos": 29,
    "dof_vel": 29,
    "motion_command": 58,
    "motion_ref_ori_b": 6,
}
# holosoma concatenates a group's terms sorted by name; "listed" is the order the config
# lists them in (config_values/observation.py, wbt), kept to show what it does to the policy.
OBS_ORDERS = {
    "sorted": tuple(sorted(OBS_DIMS)),
    "listed": (
        "motion_command",
        "motion_ref_ori_b",
        "base_ang_vel",
        "dof_pos",
        "dof_vel",
        "actions",
    ),
}
ROOT_BODY = "pelvis"
TORSO_BODY = "torso_link"  # robot.py: motion={"body_name_ref": ["torso_link"]}
KEYPOINT_BODIES = DEFAULT_KEYPOINT_BODIES
FOOT_BODIES = ("left_ankle_roll_link", "right_ankle_roll_link")
FLOOR_GEOM = "floor"
MAX_TORSO_HEIGHT_ERROR_M = 0.25  # src/eval/episode.rs, TerminationRule::default
MAX_TORSO_TILT_ERROR_RAD = 0.8


# ---------------------------------------------------------------------------------------
# Rotations (quaternions are w, x, y, z unless named otherwise)
# ---------------------------------------------------------------------------------------


def quat_to_mat(q: Array) -> Array:
    w, x, y, z = (float(v) for v in q / np.linalg.norm(q))
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def mat_to_quat(m: Array) -> Array:
    out = np.zeros(4)
    mujoco.mju_mat2Quat(out, np.ascontiguousarray(m, dtype=np.float64).reshape(9))
    return out


def yaw_of(m: Array) -> float:
    """Heading of a rotation matrix (z of the z-y-x Euler angles)."""
    return math.atan2(float(m[1, 0]), float(m[0, 0]))


def rot_z(yaw: float) -> Array:
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def angle_between(a: Array, b: Array) -> float:
    cos = float(np.dot(a, b) / (np.linalg.norm(a) * np.linalg.norm(b)))
    return math.acos(max(-1.0, min(1.0, cos)))


# ---------------------------------------------------------------------------------------
# The MuJoCo model
# ---------------------------------------------------------------------------------------


def build_model(mjcf: Path, meshdir: Path, dt: float) -> tuple[Any, str]:
    spec = mujoco.MjSpec.from_file(str(mjcf))
    own = (mjcf.parent / spec.meshdir) if spec.meshdir else mjcf.parent
    used = own
    if not own.is_dir():
        if not meshdir.is_dir():
            raise UsageError(f"meshes not found in {own} nor in {meshdir}")
        spec.meshdir = str(meshdir)
        used = meshdir
    spec.option.timestep = dt
    spec.option.gravity = [0.0, 0.0, -9.81]
    # holosoma simulator/mujoco/scene_manager.py, _create_ground_plane and add_terrain.
    floor = spec.worldbody.add_geom(
        name=FLOOR_GEOM,
        type=mujoco.mjtGeom.mjGEOM_PLANE,
        size=[0.0, 0.0, 0.05],
        friction=[0.7, 0.005, 0.001],
        solimp=[0.99, 0.99, 0.01, 0.5, 2.0],
        solref=[0.001, 1.0],
    )
    floor.contype = 2
    floor.conaffinity = 1
    return spec.compile(), str(used)


@dataclass
class Robot:
    model: Any
    qadr: npt.NDArray[np.intp]  # qpos address per policy dof
    vadr: npt.NDArray[np.intp]  # qvel address per policy dof
    effort: Array  # torque limit per policy dof
    root_qadr: int
    root_vadr: int
    pelvis: int
    torso: int
    keypoints: npt.NDArray[np.intp]
    feet: npt.NDArray[np.intp]


def robot_of(model: Any, dof_names: list[str], ctrlrange_clamp: bool) -> Robot:
    def body(name: str) -> int:
        i = int(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name))
        if i < 0:
            raise UsageError(f"MJCF has no body {name!r}")
        return i

    qadr, vadr, effort = [], [], []
    for name in dof_names:
        j = int(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name))
        if j < 0:
            raise UsageError(f"MJCF has no joint {name!r}")
        qadr.append(int(model.jnt_qposadr[j]))
        vadr.append(int(model.jnt_dofadr[j]))
        limit = math.inf
        if model.jnt_actfrclimited[j]:
            limit = float(max(abs(model.jnt_actfrcrange[j][0]), abs(model.jnt_actfrcrange[j][1])))
        if ctrlrange_clamp:
            a = int(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, name))
            if a >= 0 and model.actuator_ctrllimited[a]:
                limit = min(limit, float(np.max(np.abs(model.actuator_ctrlrange[a]))))
        effort.append(limit)
    free = [j for j in range(model.njnt) if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE]
    if len(free) != 1:
        raise UsageError("MJCF must have exactly one free joint")
    return Robot(
        model=model,
        qadr=np.array(qadr, dtype=np.intp),
        vadr=np.array(vadr, dtype=np.intp),
        effort=np.array(effort),
        root_qadr=int(model.jnt_qposadr[free[0]]),
        root_vadr=int(model.jnt_dofadr[free[0]]),
        pelvis=body(ROOT_BODY),
        torso=body(TORSO_BODY),
        keypoints=np.array([body(b) for b in KEYPOINT_BODIES], dtype=np.intp),
        feet=np.array([body(b) for b in FOOT_BODIES], dtype=np.intp),
    )


class Kinematics:
    """Forward kinematics of a reference pose with the pelvis at the origin."""

    def __init__(self, robot: Robot) -> None:
        self.robot = robot
        self.data = mujoco.MjData(robot.model)

    def pelvis_frame(self, joint_pos: Array) -> tuple[Array, Array, Array]:
        """(torso rotation, torso position, keypoint positions), all in the pelvis frame."""
        r = self.robot
        q = self.data.qpos
        q[:] = r.model.qpos0
        q[r.root_qadr : r.root_qadr + 7] = [0, 0, 0, 1, 0, 0, 0]
        q[r.qadr] = joint_pos
        mujoco.mj_kinematics(r.model, self.data)
        return (
            self.data.xmat[r.torso].reshape(3, 3).copy(),
            self.data.xpos[r.torso].copy(),
            self.data.xpos[r.keypoints].copy(),
        )

    def reference_pelvis(
        self, joint_pos: Array, torso_pos: Array, torso_quat: Array
    ) -> tuple[Array, Array, Array]:
        """World pelvis (rotation, position) of a reference frame, and keypoints (pelvis frame).

        pelvis = torso_ref * (pelvis -> torso)^-1.
        """
        r_pt, p_pt, kp_local = self.pelvis_frame(joint_pos)
        r_wt = quat_to_mat(torso_quat)
        r_wp = r_wt @ r_pt.T
        p_wp = torso_pos - r_wp @ p_pt
        return r_wp, p_wp, kp_local


# ---------------------------------------------------------------------------------------
# The episode
# ---------------------------------------------------------------------------------------


@dataclass
class Conventions:
    obs_order: str
    ang_vel_frame: str  # "body" (pelvis frame, the IMU gyro) or "world"
    action_offset: str  # "default" (target = default + a) or "none" (target = a)
    command_lag: int  # 0: reference at step k; 1: previous call's outputs (wbt.py)
    yaw_offset: bool  # remove each start yaw (wbt.py) or not
    ctrlrange_clamp: bool

    def as_json(self) -> dict[str, Any]:
        return {
            "obs_order": list(OBS_ORDERS[self.obs_order]),
            "obs_order_name": self.obs_order,
            "base_ang_vel_frame": self.ang_vel_frame,
            "pd_target": (
                "default_dof_angles + 1.0 * clip(a, -100, 100)"
                if self.action_offset == "default"
                else "1.0 * clip(a, -100, 100)"
            ),
            "command_lag": self.command_lag,
            "yaw_offset_removed": self.yaw_offset,
            "torque_clamp": (
                "min(joint actuatorfrcrange, actuator ctrlrange)"
                if self.ctrlrange_clamp
                else "joint actuatorfrcrange (holosoma dof_effort_limit_list)"
            ),
        }


class Controller:
    """holosoma's inference loop (wbt.py) around one MuJoCo model: observation, action, PD."""

    def __init__(
        self, policy: Policy, ref: Reference, robot: Robot, conv: Conventions, physics_dt: float
    ) -> None:
        self.policy, self.ref, self.robot, self.conv = policy, ref, robot, conv
        self.model = robot.model
        self.data = mujoco.MjData(self.model)
        self.substeps = round(CONTROL_DT_S / physics_dt)
        self.default = np.array([DEFAULT_DOF_ANGLES.get(n, 0.0) for n in policy.dof_names])
        self.offset = self.default if conv.action_offset == "default" else 0.0 * self.default
        self.order = OBS_ORDERS[conv.obs_order]
        self.last_action = np.zeros(29)
        # wbt.py:192-208: before the first call the command is the step-0 outputs.
        self.prev_cmd = np.concatenate([ref.joint_pos[0], ref.joint_vel[0]])
        self.prev_quat = ref.torso_quat[0].copy()
        self.unyaw_robot = np.eye(3)
        self.unyaw_motion = np.eye(3)
        self.max_abs_action = 0.0
        self.saturated = 0
        self.policy_s = 0.0
        self.physics_s = 0.0

    def torso_rot(self) -> Array:
        return np.asarray(self.data.xmat[self.robot.torso]).reshape(3, 3)

    def capture_yaw_offsets(self) -> None:
        """Start yaws, captured when the policy starts (wbt.py:333-337, 421-437)."""
        if self.conv.yaw_offset:
            self.unyaw_robot = rot_z(-yaw_of(self.torso_rot()))
            self.unyaw_motion = rot_z(-yaw_of(quat_to_mat(self.ref.torso_quat[0])))

    def observation(self, k: int) -> tuple[npt.NDArray[np.float32], Array]:
        r, d = self.robot, self.data
        if self.conv.command_lag == 0:
            cmd = np.concatenate([self.ref.joint_pos[k], self.ref.joint_vel[k]])
            ref_quat = self.ref.torso_quat[k]
        else:
            cmd, ref_quat = self.prev_cmd, self.prev_quat
        r_robot = self.unyaw_robot @ self.torso_rot()
        r_ref = self.unyaw_motion @ quat_to_mat(ref_quat)
        ori = (r_robot.T @ r_ref)[:, :2].reshape(-1)  # wbt.py:276-277
        # The free joint's angular velocity is in the pelvis frame (the IMU gyro's).
        w_body = np.asarray(d.qvel[r.root_vadr + 3 : r.root_vadr + 6]).copy()
        pelvis_rot = np.asarray(d.xmat[r.pelvis]).reshape(3, 3)
        ang_vel = w_body if self.conv.ang_vel_frame == "body" else pelvis_rot @ w_body
        terms = {
            "actions": self.last_action,
            "base_ang_vel": ang_vel,
            "dof_pos": np.asarray(d.qpos[r.qadr]) - self.default,
            "dof_vel": np.asarray(d.qvel[r.vadr]),
            "motion_command": cmd,
            "motion_ref_ori_b": ori,
        }
        return np.concatenate([terms[t] for t in self.order]).astype(np.float32), ori

    def control_step(self, k: int) -> Array:
        """One 50 Hz step at motion step k; returns the observed motion_ref_ori_b."""
        obs, ori = self.observation(k)
        t0 = time.perf_counter()
        out = self.policy.run(obs, k)
        self.policy_s += time.perf_counter() - t0
        self.prev_cmd = np.concatenate([out["joint_pos"], out["joint_vel"]])
        xyzw = out["ref_quat_xyzw"]
        self.prev_quat = np.array([xyzw[3], xyzw[0], xyzw[1], xyzw[2]])
        action = np.clip(out["actions"], -ACTION_CLIP, ACTION_CLIP)
        self.last_action = action.copy()
        self.max_abs_action = max(self.max_abs_action, float(np.max(np.abs(action))))
        target = self.offset + ACTION_SCALE * action
        r, d = self.robot, self.data
        t0 = time.perf_counter()
        for _ in range(self.substeps):
            tau = self.policy.kp * (target - d.qpos[r.qadr]) - self.policy.kd * d.qvel[r.vadr]
            clipped = np.clip(tau, -r.effort, r.effort)
            self.saturated += int(np.count_nonzero(clipped != tau))
            d.qfrc_applied[r.vadr] = clipped
            mujoco.mj_step(self.model, d)
        # mj_step leaves the kinematics of the state before its last integration.
        mujoco.mj_kinematics(self.model, d)
        self.physics_s += time.perf_counter() - t0
        return ori

    def finite(self) -> bool:
        return bool(np.all(np.isfinite(self.data.qpos)) and np.all(np.isfinite(self.data.qvel)))

    def torso_errors(self, j: int) -> tuple[float, float]:
        """(signed torso height error, tilt) against reference frame j (src/eval/episode.rs)."""
        down = np.array([0.0, 0.0, -1.0])
        tilt = angle_between(
            self.torso_rot().T @ down, quat_to_mat(self.ref.torso_quat[j]).T @ down
        )
        dz = float(self.data.xpos[self.robot.torso][2]) - float(self.ref.torso_pos[j][2])
        return dz, tilt


def fell(dz: float, tilt: float) -> str | None:
    if abs(dz) > MAX_TORSO_HEIGHT_ERROR_M:
        return "torso_height"
    if tilt > MAX_TORSO_TILT_ERROR_RAD:
        return "torso_tilt"
    return None


def run_episode(
    policy: Policy,
    ref: Reference,
    robot: Robot,
    conv: Conventions,
    steps: int,
    physics_dt: float,
    hold_s: float,
) -> dict[str, Any]:
    ctl = Controller(policy, ref, robot, conv, physics_dt)
    model, data = ctl.model, ctl.data
    kin = Kinematics(robot)

    # Initial state: the reference's first frame, zero root velocity.
    r_wp0, p_wp0, _ = kin.reference_pelvis(ref.joint_pos[0], ref.torso_pos[0], ref.torso_quat[0])
    data.qpos[:] = model.qpos0
    data.qpos[robot.root_qadr : robot.root_qadr + 3] = p_wp0
    data.qpos[robot.root_qadr + 3 : robot.root_qadr + 7] = mat_to_quat(r_wp0)
    data.qpos[robot.qadr] = ref.joint_pos[0]
    data.qvel[:] = 0.0
    data.qvel[robot.vadr] = ref.joint_vel[0]
    mujoco.mj_forward(model, data)
    torso_check = float(np.linalg.norm(data.xpos[robot.torso] - ref.torso_pos[0]))
    # Lowest point of the foot colliders above the floor (MuJoCo's contact margin is 0, so
    # measure with mj_geomDistance against the floor).
    floor_id = int(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, FLOOR_GEOM))
    gaps = [
        float(mujoco.mj_geomDistance(model, data, g, floor_id, 1.0, None))
        for g in range(model.ngeom)
        if int(model.geom_bodyid[g]) in set(robot.feet.tolist()) and model.geom_contype[g]
    ]
    ctl.capture_yaw_offsets()

    fall: dict[str, Any] | None = None
    # holosoma's sim-to-sim flow runs the policy with the motion pinned at step 0 before the
    # clip starts (wbt.py:297-301); --hold-s replays that (not scored).
    for h in range(round(hold_s / CONTROL_DT_S)):
        ctl.control_step(0)
        reason = fell(*ctl.torso_errors(0)) if ctl.finite() else "physics_diverged"
        if reason:
            fall = {"phase": "hold", "step": h, "reason": reason}
            break

    kp_err: list[float] = []
    kp_err_yaw: list[float] = []
    kp_err_obs: list[float] = []
    kp_err_body = np.zeros(len(KEYPOINT_BODIES))
    root_drift: list[float] = []
    torso_dz: list[float] = []
    torso_tilt: list[float] = []
    first_ori: list[float] | None = None
    ctl.saturated = 0
    started = time.perf_counter()
    for k in range(steps if fall is None else 0):
        ori = ctl.control_step(k)
        if first_ori is None:
            first_ori = [round(float(v), 6) for v in ori]
        if not ctl.finite():
            fall = {"phase": "motion", "step": k, "reason": "physics_diverged"}
            break

        # Compare with reference frame k+1 (src/eval/episode.rs: record after the step).
        j = min(k + 1, ref.frames - 1)
        r_wp, p_wp, kp_local = kin.reference_pelvis(
            ref.joint_pos[j], ref.torso_pos[j], ref.torso_quat[j]
        )
        robot_kp = np.asarray(data.xpos[robot.keypoints])
        rob_r = np.asarray(data.xmat[robot.pelvis]).reshape(3, 3)
        rob_p = np.asarray(data.xpos[robot.pelvis])
        # src/eval/metrics/keypoints.rs reanchor: world_from_robot_root * ref_root^-1 * x_ref.
        dist = np.linalg.norm(rob_p + kp_local @ rob_r.T - robot_kp, axis=1)
        kp_err.append(float(np.mean(dist)))
        kp_err_body += dist
        # Yaw + horizontal translation only.
        ref_w = p_wp + kp_local @ r_wp.T
        h_rot = rot_z(yaw_of(rob_r) - yaw_of(r_wp))
        shifted = (ref_w - np.array([p_wp[0], p_wp[1], 0.0])) @ h_rot.T
        shifted += np.array([rob_p[0], rob_p[1], 0.0])
        kp_err_yaw.append(float(np.mean(np.linalg.norm(shifted - robot_kp, axis=1))))
        # Against frame k (the one in the observation), full re-anchoring.
        _, _, kp_local_k = kin.pelvis_frame(ref.joint_pos[k])
        kp_err_obs.append(
            float(np.mean(np.linalg.norm(rob_p + kp_local_k @ rob_r.T - robot_kp, axis=1)))
        )
        root_drift.append(float(np.linalg.norm((rob_p - p_wp)[:2])))

        dz, tilt = ctl.torso_errors(j)
        torso_dz.append(dz)
        torso_tilt.append(tilt)
        reason = fell(dz, tilt)
        if reason:
            fall = {
                "phase": "motion",
                "step": k,
                "time_s": round((k + 1) * CONTROL_DT_S, 3),
                "reason": reason,
                "torso_height_error_m": round(dz, 4),
                "torso_tilt_rad": round(tilt, 4),
            }
            break
    wall = time.perf_counter() - started

    n = len(kp_err)
    mm = 1000.0

    def mean_mm(xs: list[float]) -> float | None:
        return round(float(np.mean(xs)) * mm, 2) if xs else None

    def rms_mm(xs: list[float]) -> float | None:
        return round(float(np.sqrt(np.mean(np.square(xs)))) * mm, 2) if xs else None

    return {
        "steps": n,
        "steps_ref": steps,
        "survival": round(n / steps, 4) if steps else 0.0,
        "fall": fall,
        "keypoint_error_mean_mm": mean_mm(kp_err),
        "keypoint_error_rms_mm": rms_mm(kp_err),
        "keypoint_error_max_mm": round(max(kp_err) * mm, 2) if kp_err else None,
        "keypoint_error_per_body_mean_mm": {
            b: round(float(e) / max(n, 1) * mm, 1)
            for b, e in zip(KEYPOINT_BODIES, kp_err_body, strict=True)
        },
        "keypoint_error_yaw_xy_reanchor_mean_mm": mean_mm(kp_err_yaw),
        "keypoint_error_yaw_xy_reanchor_rms_mm": rms_mm(kp_err_yaw),
        "keypoint_error_vs_observed_frame_mean_mm": mean_mm(kp_err_obs),
        # src/eval/episode.rs root_drift_m: horizontal pelvis distance to the reference pelvis.
        "root_drift_mean_m": round(float(np.mean(root_drift)), 4) if root_drift else 0.0,
        "root_drift_end_m": round(root_drift[-1], 4) if root_drift else 0.0,
        "max_torso_height_error_m": round(float(np.max(np.abs(torso_dz))), 4) if n else 0.0,
        "max_torso_tilt_rad": round(float(np.max(torso_tilt)), 4) if n else 0.0,
        "initial_state": {
            "pelvis": "torso_ref * (pelvis->torso by kinematics at joint_pos[0])^-1",
            "root_velocity": "zero",
            "joint_velocity": "reference joint_vel[0]",
            "pelvis_pos": [round(float(v), 5) for v in p_wp0],
            "pelvis_quat_wxyz": [round(float(v), 6) for v in mat_to_quat(r_wp0)],
            "torso_vs_reference_m": round(torso_check, 9),
            "foot_collider_floor_gap_m": round(min(gaps), 4) if gaps else None,
            "hold_s": hold_s,
            "motion_ref_ori_b_step0": first_ori,
        },
        "max_abs_action": round(ctl.max_abs_action, 3),
        "torque_saturation_fraction": round(ctl.saturated / max(n * ctl.substeps * 29, 1), 6),
        "series": {
            "keypoint_error_m": kp_err,
            "torso_height_error_m": torso_dz,
            "torso_tilt_rad": torso_tilt,
            "root_drift_m": root_drift,
        },
        "wall_time_s": round(wall, 2),
        "policy_time_s": round(ctl.policy_s, 2),
        "physics_time_s": round(ctl.physics_s, 2),
    }


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    p = argparse.ArgumentParser(
        description=(
            "Run holosoma's G1 whole-body tracking policy (ONNX with embedded motion) in "
            "MuJoCo on holosoma's MJCF and report survival and keypoint error as ThorArena "
            "measures them."
        )
    )
    p.add_argument("--onnx", type=Path, default=DEFAULT_ONNX, help="policy (%(default)s)")
    p.add_argument("--mjcf", type=Path, default=DEFAULT_MJCF, help="MJCF (%(default)s)")
    p.add_argument(
        "--meshdir",
        type=Path,
        default=DEFAULT_MESHDIR,
        help="meshes, used when the MJCF's own meshdir does not exist (%(default)s)",
    )
    p.add_argument(
        "--steps", type=int, default=None, help="control steps (default: the whole motion)"
    )
    p.add_argument(
        "--command-lag",
        type=int,
        choices=(0, 1),
        default=0,
        help="0: the observation carries the reference at step k; 1: the previous call's "
        "motion outputs, as holosoma's wbt.py feeds them (default %(default)s)",
    )
    p.add_argument(
        "--obs-order",
        choices=tuple(OBS_ORDERS),
        default="sorted",
        help="term order: holosoma's alphabetical one, or as the config lists them "
        "(default %(default)s)",
    )
    p.add_argument(
        "--ang-vel-frame",
        choices=("body", "world"),
        default="body",
        help="frame of base_ang_vel (default %(default)s: pelvis frame, the IMU gyro)",
    )
    p.add_argument(
        "--action-offset",
        choices=("default", "none"),
        default="default",
        help="PD target = default_dof_angles + a, or a alone (default %(default)s)",
    )
    p.add_argument(
        "--no-yaw-offset",
        action="store_true",
        help="do not remove the start yaws from the orientations (wbt.py removes them)",
    )
    p.add_argument(
        "--ctrlrange-clamp",
        action="store_true",
        help="also clamp torques to the actuators' ctrlrange (hip_roll 88 instead of 139 N m)",
    )
    p.add_argument(
        "--physics-dt",
        type=float,
        default=PHYSICS_DT_S,
        help="physics time step, s (default %(default)s; must divide 0.02)",
    )
    p.add_argument(
        "--hold-s",
        type=float,
        default=0.0,
        help="run the policy this long with the motion pinned at step 0 before the clip "
        "starts, as holosoma's sim-to-sim flow does (not scored; default %(default)s)",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument(
        "--trace",
        type=Path,
        default=None,
        help="write the per-step series (keypoint error, torso height error and tilt, root "
        "drift) to this JSON file",
    )
    return p.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    for path in (args.onnx, args.mjcf):
        if not path.is_file():
            msg = f"skipped: {path} not found (reference artifacts absent)"
            print(msg, file=sys.stderr)
            if args.json:
                print(json.dumps({"skipped": msg}))
            return 0
    substeps = CONTROL_DT_S / args.physics_dt
    if args.physics_dt <= 0 or abs(substeps - round(substeps)) > 1e-9:
        print("--physics-dt must divide 0.02 s", file=sys.stderr)
        return 2
    try:
        total_start = time.perf_counter()
        policy = load_policy(args.onnx)
        probed = probe_last_frame(policy)
        last = policy.graph_last_index if policy.graph_last_index is not None else probed
        if probed != last:
            print(
                f"note: outputs stop changing at step {probed}, graph clamps at {last}",
                file=sys.stderr,
            )
        ref = reference_table(policy, last + 1)
        model, meshdir = build_model(args.mjcf, args.meshdir, args.physics_dt)
        conv = Conventions(
            obs_order=args.obs_order,
            ang_vel_frame=args.ang_vel_frame,
            action_offset=args.action_offset,
            command_lag=args.command_lag,
            yaw_offset=not args.no_yaw_offset,
            ctrlrange_clamp=args.ctrlrange_clamp,
        )
        robot = robot_of(model, policy.dof_names, args.ctrlrange_clamp)
        steps_ref = ref.frames - 1  # src/eval/episode.rs reference_steps: duration / dt
        steps = steps_ref if args.steps is None else max(0, min(args.steps, steps_ref))
        result = run_episode(policy, ref, robot, conv, steps, args.physics_dt, args.hold_s)
    except UsageError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    series = result.pop("series")
    if args.trace is not None:
        args.trace.write_text(json.dumps({"control_dt_s": CONTROL_DT_S, **series}))
    report: dict[str, Any] = {
        "policy": str(args.onnx),
        "mjcf": str(args.mjcf),
        "meshdir": meshdir,
        "motion_frames": ref.frames,
        "motion_frames_probed": probed + 1,
        "motion_duration_s": round((ref.frames - 1) * CONTROL_DT_S, 3),
        "control_dt_s": CONTROL_DT_S,
        "physics_dt_s": args.physics_dt,
        "conventions": conv.as_json(),
        **result,
        "total_wall_time_s": round(time.perf_counter() - total_start, 2),
    }
    if args.json:
        print(json.dumps(report))
    else:
        fall = report["fall"]
        print(
            f"motion: {report['motion_frames']} frames, {report['motion_duration_s']} s at "
            f"50 Hz\nsurvival {report['survival']:.4f} ({report['steps']}/{steps} steps)"
            + (f", fell at step {fall['step']} ({fall['reason']})" if fall else "")
            + f"\nkeypoint error mean {report['keypoint_error_mean_mm']} mm, "
            f"RMS {report['keypoint_error_rms_mm']} mm "
            f"(yaw+xy re-anchoring: mean {report['keypoint_error_yaw_xy_reanchor_mean_mm']} mm)"
            f"\nwall time {report['wall_time_s']} s (episode), "
            f"{report['total_wall_time_s']} s total"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
