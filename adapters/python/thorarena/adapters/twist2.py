"""TWIST2 (Ze et al. 2025): the released whole-body tracking policy's 1432-dim observation.

Source: github.com/amazon-far/TWIST2 (MIT), files
`deploy_real/server_low_level_g1_sim.py` (proprioception, history, action mapping, ONNX
input `input` [batch, 1432] → output `output` [batch, 29]), `deploy_real/server_motion_lib.py`
(mimic observation), `legged_gym/legged_gym/envs/g1/g1_mimic_future.py` and its configs
`g1_mimic_distill_config.py` / `g1_mimic_future_config.py` (training). The upstream commit
could not be verified here: the upstream repository is not in the searchable index. The terms
and their order were read in forks carrying the same files: meetsitaram/TWIST2 at
10267c3a2f46 (`server_low_level_g1_sim.py`: proprio, ankle zeroing, history of 10 x 127)
and beac122c8d32 (`g1_mimic_future.py`: the student's mimic terms and proprio). The training
timing (future frame at t, history refilled on the first two steps after a reset) was not
re-read there; it comes from our harness that walked the policy in MuJoCo
(SOURCES.md, "TWIST2 in MuJoCo"), which this module
matches number for number.

Per environment, with R a frame's root rotation (quaternions (w, x, y, z)):

    mimic(frame)  (35) = v_x, v_y, root_pos_w.z, roll, pitch, w_z, joint_pos (29)
                         where v = R^T root_lin_vel_w, w = R^T root_ang_vel_w
    proprio       (92) = root_ang_vel_b * 0.25, roll, pitch (robot), q - action_offset_rad,
                         qd * 0.05 (ankles 4, 5, 10, 11 zeroed), last_action
    single       (127) = mimic(reference[1]) ++ proprio
    obs         (1432) = single ++ history (10 x 127, oldest first) ++ mimic(reference[0]),
                         clipped to ±100, float32

`reference[0]` is the reference at t (the "future" frame as training builds it),
`reference[1]` at t + 0.02 s (the mimic frame, one
50 Hz step ahead). History is updated after the observation is built: on an episode's steps 0
and 1 all 10 rows become `single` (training refills it after a reset), later it shifts by
one and appends `single`; before step 0 it is zeros. The action written is the raw network
output; the `twist2` profile clips it to ±10 and maps target = default + 0.5 · action.

`src/policy/twist2.rs` builds the same observation in Rust; `examples/
check_against_dump.py --adapter twist2` compares the two (observation ≤ 1e-5, action ≤ 1e-4).
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from .base import Adapter
from .rotations import body_from_world, roll_pitch_of

N_JOINTS = 29
N_MIMIC = 6 + N_JOINTS
"""35: v_x, v_y, height, roll, pitch, yaw rate, joint positions."""
N_PROPRIO = 3 + 2 + 3 * N_JOINTS
"""92."""
N_SINGLE = N_MIMIC + N_PROPRIO
"""127."""
N_HISTORY = 10
N_OBS = N_SINGLE * (N_HISTORY + 1) + N_MIMIC
"""1432."""
ANG_VEL_SCALE = 0.25
DOF_VEL_SCALE = 0.05
ANKLE_JOINTS = (4, 5, 10, 11)
"""Ankle pitch/roll of both legs: their velocities are zeroed in the observation."""
OBS_CLIP = 100.0
MIMIC_LOOKAHEAD_S = 0.02
"""The mimic frame is one 50 Hz step ahead of the future frame."""


FUTURE_START = N_SINGLE * (N_HISTORY + 1)
"""Column of mimic(reference[0]), after single and the history."""


def write_proprio(
    out: np.ndarray,
    records: np.ndarray,
    roll: np.ndarray,
    pitch: np.ndarray,
    default_pos: np.ndarray,
) -> None:
    """proprio (92) of environment records into `out` (shape (n, 92)), given the robot's
    roll and pitch. Each term is computed in float64, then stored (rounded once)."""
    j = 5
    out[:, 0:3] = records["root_ang_vel_b"] * ANG_VEL_SCALE
    out[:, 3] = roll
    out[:, 4] = pitch
    out[:, j : j + N_JOINTS] = records["q"] - default_pos
    j += N_JOINTS
    out[:, j : j + N_JOINTS] = records["qd"] * DOF_VEL_SCALE
    out[:, [j + a for a in ANKLE_JOINTS]] = 0.0
    j += N_JOINTS
    out[:, j : j + N_JOINTS] = records["last_action"]


def clip_in_place(x: np.ndarray, bound: float) -> None:
    """x = clip(x, -bound, bound), as two ufunc calls (`np.clip`'s dispatch costs more than
    the clipping at small batches)."""
    np.maximum(x, -bound, out=x)
    np.minimum(x, bound, out=x)


class Twist2Adapter(Adapter):
    """TWIST2's observation (1432) and network (29 raw actions in canonical order).

    The observation is written block by block into one float32 array (no concatenation of
    the whole row), and the history is kept in float32, already clipped: storing a value
    rounded to float32 and clipped to ±100 gives the float32 the observation would hold,
    so the result is the float64-then-round-once observation, bit for bit, at a third of
    the memory traffic (measured with `thorarena bench ipc --clients twist2`).
    """

    name: ClassVar[str] = "twist2"
    profile = "twist2"
    simulator_input: ClassVar[str | None] = "twist2"
    reference_offsets_s: ClassVar[tuple[float, ...]] = (0.0, MIMIC_LOOKAHEAD_S)
    obs_dim = N_OBS

    state_dtypes: ClassVar[dict[str, type]] = {"history": np.float32}

    def slot_state(self) -> dict[str, tuple[int, ...]]:
        return {"history": (N_HISTORY, N_SINGLE)}

    def observe(self, records: np.ndarray, slots: np.ndarray) -> np.ndarray:
        n = len(slots)
        frames = records["reference"]  # (n, 2): frames at t and t + 0.02 s
        # One rotation matrix per reference frame and for the robot, in one product.
        quats = np.concatenate([frames["root_quat_wxyz"], records["root_quat_wxyz"][:, None]], 1)
        rt = body_from_world(quats)  # (n, 3, 3, 3)
        roll, pitch = roll_pitch_of(rt)  # (n, 3)
        velocities = np.stack([frames["root_lin_vel_w"], frames["root_ang_vel_w"]], axis=-1)
        body = rt[:, :2] @ velocities  # (n, 2, 3, 2): columns v, w in the body frame
        mimic = np.concatenate(
            [
                body[..., :2, 0],
                frames["root_pos_w"][..., 2:3],
                roll[:, :2, None],
                pitch[:, :2, None],
                body[..., 2:3, 1],
                frames["joint_pos"],
            ],
            axis=-1,
        )  # (n, 2, 35)
        obs = np.empty((n, N_OBS), dtype=np.float32)
        single = obs[:, :N_SINGLE]
        single[:, :N_MIMIC] = mimic[:, 1]
        write_proprio(single[:, N_MIMIC:], records, roll[:, 2], pitch[:, 2], self.action_offset_rad)
        clip_in_place(single, OBS_CLIP)
        future = obs[:, FUTURE_START:]
        future[:] = mimic[:, 0]
        clip_in_place(future, OBS_CLIP)
        # The history rows (stored clipped) into the observation, then updated from it.
        history = self.state["history"]
        every = n == self.n_envs  # all slots active: plain slices, no gathers
        rows = history if every else history[slots]
        obs[:, N_SINGLE:FUTURE_START] = rows.reshape(n, -1)
        refill = records["step"] <= 1
        if every and not refill.any():
            history[:, :-1] = obs[:, 2 * N_SINGLE : FUTURE_START].reshape(
                n, N_HISTORY - 1, N_SINGLE
            )
            history[:, -1] = single
        else:
            history[slots[refill]] = single[refill, None, :]
            keep = ~refill
            shift = slots[keep]
            history[shift, :-1] = obs[keep, 2 * N_SINGLE : FUTURE_START].reshape(
                len(shift), N_HISTORY - 1, N_SINGLE
            )
            history[shift, -1] = single[keep]
        return obs
