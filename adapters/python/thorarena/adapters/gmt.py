"""GMT (Chen et al. 2025, "General Motion Tracking for Humanoid Whole-Body Control"): the
2154-dim observation of the released 23-DoF G1 policy.

Source: github.com/zixuan417/humanoid-general-motion-tracking (Apache-2.0), `sim2sim.py`
(`HumanoidEnv._get_mimic_obs` and `run`) and `utils/motion_lib.py`. The upstream repository
is not in the index searchable here, so its commit could not be verified; the layout was read
from two forks that carry the file unchanged in these parts (same copyright header, same
code): s1lent4gnt/humanoid-general-motion-tracking at be78f0c93bef (`sim2sim.py`) and
171d12ff5942 (`utils/motion_lib.py`), and xshipolar/humanoid-general-motion-tracking at
c1a3257cb881 (`sim2sim.py`, identical observation code).

GMT drives 23 joints: the canonical G1 order without the six wrist joints (legs 12, waist 3,
per arm shoulder pitch/roll/yaw and elbow). Per environment:

    mimic(frame)  (30) = root_pos_w.z, roll, pitch, v (3), w_z, joint_pos (23)
                         where v = R^T root_lin_vel_w, w = R^T root_ang_vel_w, R the frame's
                         root rotation; roll/pitch as in `rotations.roll_pitch`
    mimic        (600) = mimic of the 20 frames at t + 0.02 · [1, 5, 10, 15, …, 95] s,
                         frame after frame (`tar_obs_steps` x control dt 0.02 s)
    proprio       (74) = root_ang_vel_b * 0.25, roll, pitch (robot), q - default,
                         qd * 0.05 (ankles 4, 5, 10, 11 zeroed), last_action (all 23 joints)
    obs         (2154) = mimic ++ proprio ++ history (20 x 74, oldest first), float32

History starts as zeros and is updated after the observation is built (shift by one,
append `proprio`), as `sim2sim.py`'s deque does; there is no refill on the first steps and no
clipping. The network output (23) is the raw action; the wrist joints get action 0, so the
profile holds them at its default pose. The `gmt` profile maps target = default + 0.5 ·
action; `sim2sim.py` also clips the action to ±10 before scaling (the profile should do the
same; the adapter writes the raw output because the wire's `last_action` must stay the raw
one).

Known differences from `sim2sim.py` that are not the adapter's: the reference's root
velocities there are forward differences smoothed by a 19-frame box filter
(`utils/motion_lib.py`), here they are whatever the simulator's reference carries; the
robot's roll, pitch and angular velocity there come from MuJoCo's IMU sensors, here from
the root (pelvis) state.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from .base import Adapter
from .rotations import roll_pitch, rotate_inverse

JOINTS = np.array([*range(19), 22, 23, 24, 25], dtype=np.intp)
"""Canonical indices of GMT's 23 joints (its action and observation order)."""
WRISTS = np.array([19, 20, 21, 26, 27, 28], dtype=np.intp)
"""Canonical indices of the wrist joints GMT does not drive."""
N_DOF = len(JOINTS)
TARGET_STEPS = (1, 5, 10, 15, 20, 25, 30, 35, 40, 45, 50, 55, 60, 65, 70, 75, 80, 85, 90, 95)
"""`tar_obs_steps`: the future reference frames, in 50 Hz control steps ahead."""
CONTROL_DT_S = 0.02
N_MIMIC_FRAME = 7 + N_DOF
"""30."""
N_MIMIC = N_MIMIC_FRAME * len(TARGET_STEPS)
"""600."""
N_PROPRIO = 3 + 2 + 3 * N_DOF
"""74."""
N_HISTORY = 20
N_OBS = N_MIMIC + N_PROPRIO * (N_HISTORY + 1)
"""2154."""
ANG_VEL_SCALE = 0.25
DOF_VEL_SCALE = 0.05
ANKLE_DOFS = (4, 5, 10, 11)
"""Ankle pitch/roll in GMT's order (the legs come first, as in the canonical order)."""


def mimic_observation(frames: np.ndarray) -> np.ndarray:
    """mimic of reference frames `(n, n_frames)` (records of `Layout.ref_dtype`), shape
    (n, 30 · n_frames), frame after frame."""
    quat = frames["root_quat_wxyz"]
    velocities = np.stack([frames["root_lin_vel_w"], frames["root_ang_vel_w"]], axis=-2)
    body = rotate_inverse(quat[..., None, :], velocities)  # (..., 2, 3): v, w
    roll, pitch = roll_pitch(quat)
    per_frame = np.concatenate(
        [
            frames["root_pos_w"][..., 2:3],
            roll[..., None],
            pitch[..., None],
            body[..., 0, :],
            body[..., 1, 2:3],
            frames["joint_pos"][..., JOINTS],
        ],
        axis=-1,
    )
    return per_frame.reshape(len(frames), -1)


def proprio_observation(records: np.ndarray, default_pos: np.ndarray) -> np.ndarray:
    """proprio (74) of environment records, shape (n, 74)."""
    roll, pitch = roll_pitch(records["root_quat_wxyz"])
    qd = records["qd"][:, JOINTS] * DOF_VEL_SCALE
    qd[:, list(ANKLE_DOFS)] = 0.0
    return np.concatenate(
        [
            records["root_ang_vel_b"] * ANG_VEL_SCALE,
            roll[:, None],
            pitch[:, None],
            records["q"][:, JOINTS] - default_pos[JOINTS],
            qd,
            records["last_action"][:, JOINTS],
        ],
        axis=1,
    )


class GmtAdapter(Adapter):
    """GMT's observation (2154) and network (23 raw actions, wrists held at action 0)."""

    name: ClassVar[str] = "gmt"
    profile = "gmt"
    reference_offsets_s: ClassVar[tuple[float, ...]] = tuple(
        round(k * CONTROL_DT_S, 9) for k in TARGET_STEPS
    )
    obs_dim = N_OBS

    def slot_state(self) -> dict[str, tuple[int, ...]]:
        return {"history": (N_HISTORY, N_PROPRIO)}

    def observe(self, records: np.ndarray, slots: np.ndarray) -> np.ndarray:
        proprio = proprio_observation(records, self.action_offset_rad)
        history = self.state["history"]
        obs = np.concatenate(
            [
                mimic_observation(records["reference"]),
                proprio,
                history[slots].reshape(len(slots), -1),
            ],
            axis=1,
        )
        history[slots, :-1] = history[slots, 1:]
        history[slots, -1] = proprio
        return obs.astype(np.float32)

    def actions_from_outputs(self, outputs: np.ndarray, records: np.ndarray) -> np.ndarray:
        outputs = np.asarray(outputs, dtype=np.float64)
        if outputs.shape[1:] != (N_DOF,):
            raise ValueError(f"GMT outputs {N_DOF} actions, the network gave {outputs.shape[1:]}")
        actions = np.zeros((len(outputs), len(self.joint_names)))
        actions[:, JOINTS] = outputs
        return actions
