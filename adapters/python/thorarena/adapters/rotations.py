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


def _quadratic_form_of_body_from_world() -> np.ndarray:
    """M (16, 9) with R^T.flat = outer(q, q).flat @ M: every entry of a rotation matrix is
    a quadratic form in the quaternion (the homogeneous form, equal to the usual one for
    unit quaternions)."""
    w, x, y, z = range(4)
    # R (world from body) as {(a, b): coefficient of q_a q_b} per entry.
    r = [
        [{(w, w): 1, (x, x): 1, (y, y): -1, (z, z): -1}, {(x, y): 2, (w, z): -2},
         {(x, z): 2, (w, y): 2}],
        [{(x, y): 2, (w, z): 2}, {(w, w): 1, (x, x): -1, (y, y): 1, (z, z): -1},
         {(y, z): 2, (w, x): -2}],
        [{(x, z): 2, (w, y): -2}, {(y, z): 2, (w, x): 2},
         {(w, w): 1, (x, x): -1, (y, y): -1, (z, z): 1}],
    ]  # fmt: skip
    m = np.zeros((16, 9))
    for i in range(3):
        for j in range(3):
            for (a, b), c in r[j][i].items():  # R^T[i][j] = R[j][i]
                m[4 * a + b, 3 * i + j] = c
    return m


_BODY_FROM_WORLD = _quadratic_form_of_body_from_world()


def body_from_world(quat_wxyz: np.ndarray) -> np.ndarray:
    """R^T of unit quaternions (…, 4): (…, 3, 3), so v_b = R^T v_w. Two numpy calls
    whatever the batch: what per-step observation builders want at small batches."""
    q = np.ascontiguousarray(quat_wxyz)
    qq = (q[..., :, None] * q[..., None, :]).reshape(*q.shape[:-1], 16)
    rt: np.ndarray = (qq @ _BODY_FROM_WORLD).reshape(*q.shape[:-1], 3, 3)
    return rt


def roll_pitch_of(body_from_world: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Roll and pitch (as `roll_pitch`) from R^T (…, 3, 3): roll = atan2(R21, R22),
    pitch = asin(clip(-R20, -1, 1))."""
    rt = body_from_world
    roll = np.arctan2(rt[..., 1, 2], rt[..., 2, 2])
    pitch = np.arcsin(np.minimum(np.maximum(-rt[..., 0, 2], -1.0), 1.0))
    return roll, pitch


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
