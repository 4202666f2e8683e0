"""Rotations for observation builders, vectorized over leading axes.

Quaternions are (w, x, y, z), as on the wire, and assumed unit. `world_from_body` is the
rotation matrix R of a body's quaternion: v_w = R v_b, so v_b = R^T v_w.
"""

from __future__ import annotations

import numpy as np


def rotate_inverse(quat_wxyz: np.ndarray, v: np.ndarray) -> np.ndarray:
    """R^T v: a world-frame vector in the body frame of `quat_wxyz` (shapes (..., 4), (..., 3),
    broadcast against each other)."""
    w, x, y, z = quat_wxyz[..., 0], quat_wxyz[..., 1], quat_wxyz[..., 2], quat_wxyz[..., 3]
    vx, vy, vz = v[..., 0], v[..., 1], v[..., 2]
    # v (2w² - 1) - 2w (u x v) + 2u (u . v), u = (x, y, z), written out: numpy's cross and
    # the generic helpers cost more than the arithmetic on a few vectors.
    a = 2.0 * w * w - 1.0
    b = 2.0 * (x * vx + y * vy + z * vz)
    w2 = 2.0 * w
    return np.stack(
        (
            vx * a - w2 * (y * vz - z * vy) + x * b,
            vy * a - w2 * (z * vx - x * vz) + y * b,
            vz * a - w2 * (x * vy - y * vx) + z * b,
        ),
        axis=-1,
    )


def roll_pitch(quat_wxyz: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Roll and pitch of the intrinsic z-y-x (yaw, pitch, roll) Euler angles, rad:
    roll = atan2(2(wx + yz), 1 - 2(x² + y²)), pitch = asin(clip(2(wy - zx), -1, 1))."""
    w, x, y, z = quat_wxyz[..., 0], quat_wxyz[..., 1], quat_wxyz[..., 2], quat_wxyz[..., 3]
    roll = np.arctan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y))
    pitch = np.arcsin(np.clip(2.0 * (w * y - z * x), -1.0, 1.0))
    return roll, pitch


def world_from_body(quat_wxyz: np.ndarray) -> np.ndarray:
    """The rotation matrix of `quat_wxyz`, shape (..., 3, 3)."""
    w, x, y, z = quat_wxyz[..., 0], quat_wxyz[..., 1], quat_wxyz[..., 2], quat_wxyz[..., 3]
    rows = [
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ]
    return np.stack([np.stack(row, axis=-1) for row in rows], axis=-2)


def rotation_about(axis: str, angle: np.ndarray) -> np.ndarray:
    """Rotation matrices about the body axis `"x"`, `"y"` or `"z"` by `angle` (shape (...,))."""
    c, s = np.cos(angle), np.sin(angle)
    one, zero = np.ones_like(angle), np.zeros_like(angle)
    if axis == "x":
        rows = [[one, zero, zero], [zero, c, -s], [zero, s, c]]
    elif axis == "y":
        rows = [[c, zero, s], [zero, one, zero], [-s, zero, c]]
    elif axis == "z":
        rows = [[c, -s, zero], [s, c, zero], [zero, zero, one]]
    else:
        raise ValueError(f"axis must be x, y or z, not {axis!r}")
    return np.stack([np.stack(row, axis=-1) for row in rows], axis=-2)
