"""holosoma's whole-body tracking network as `tools/holosoma_mujoco.py` runs it: the ONNX
session with its metadata (`dof_names`, `kp`, `kd`), the last frame of the motion embedded
in it (from the graph's clamp on `time_step`, and probed from outside), and that motion as
a table. Our code; facts from holosoma's `inference/policies/wbt.py` (see the tool).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

Array = npt.NDArray[np.float64]


class UsageError(Exception):
    """Bad arguments or unreadable inputs (exit code 2)."""


@dataclass
class Policy:
    session: Any
    dof_names: list[str]
    kp: Array
    kd: Array
    graph_last_index: int | None  # the clamp on time_step found in the graph, if any

    def run(self, obs: npt.NDArray[np.float32], time_step: int) -> dict[str, Array]:
        feed = {
            "obs": obs.reshape(1, -1).astype(np.float32),
            "time_step": np.array([[float(time_step)]], dtype=np.float32),
        }
        names = ["actions", "joint_pos", "joint_vel", "ref_pos_xyz", "ref_quat_xyzw"]
        outs = self.session.run(names, feed)
        return {
            n: np.asarray(o, dtype=np.float64).reshape(-1) for n, o in zip(names, outs, strict=True)
        }


def load_policy(path: Path) -> Policy:
    import onnx
    import onnxruntime as ort
    from onnx import numpy_helper

    model = onnx.load(str(path))
    meta = {p.key: json.loads(p.value) for p in model.metadata_props}
    for key in ("dof_names", "kp", "kd"):
        if key not in meta:
            raise UsageError(f"{path}: metadata {key!r} missing")
    # The graph clamps time_step with a Clip whose max is a Constant: the last frame index.
    consts = {
        n.output[0]: numpy_helper.to_array(n.attribute[0].t)
        for n in model.graph.node
        if n.op_type == "Constant" and n.attribute and n.attribute[0].type == 4
    }
    last: int | None = None
    for node in model.graph.node:
        if node.op_type == "Clip" and len(node.input) >= 3 and node.input[2] in consts:
            value = consts[node.input[2]]
            if value.size == 1 and np.issubdtype(value.dtype, np.integer):
                last = int(value.reshape(()))
    options = ort.SessionOptions()
    options.intra_op_num_threads = 1
    options.inter_op_num_threads = 1
    session = ort.InferenceSession(
        str(path), sess_options=options, providers=["CPUExecutionProvider"]
    )
    return Policy(
        session=session,
        dof_names=list(meta["dof_names"]),
        kp=np.asarray(meta["kp"], dtype=np.float64),
        kd=np.asarray(meta["kd"], dtype=np.float64),
        graph_last_index=last,
    )


def _motion_outputs(policy: Policy, t: int) -> Array:
    out = policy.run(np.zeros(154, dtype=np.float32), t)
    return np.concatenate(
        [out["joint_pos"], out["joint_vel"], out["ref_pos_xyz"], out["ref_quat_xyzw"]]
    )


def probe_last_frame(policy: Policy) -> int:
    """Last frame index, found from outside: the outputs stop changing at the clamp.

    Doubles time_step until two far-apart queries agree, then bisects for the first step
    whose outputs equal the clamped ones (a motion whose last frames are exactly equal would
    be reported short, hence the cross-check with the graph's clamp).
    """
    hi = 1
    while not np.array_equal(_motion_outputs(policy, hi), _motion_outputs(policy, 4 * hi)):
        hi *= 2
        if hi > 1 << 24:
            raise UsageError("the motion outputs never stop changing with time_step")
    final = _motion_outputs(policy, 4 * hi)
    lo = 0
    while lo < hi:
        mid = (lo + hi) // 2
        if np.array_equal(_motion_outputs(policy, mid), final):
            hi = mid
        else:
            lo = mid + 1
    return lo


@dataclass
class Reference:
    joint_pos: Array  # [T, 29], policy dof order
    joint_vel: Array  # [T, 29]
    torso_pos: Array  # [T, 3]
    torso_quat: Array  # [T, 4] wxyz

    @property
    def frames(self) -> int:
        return int(self.joint_pos.shape[0])


def reference_table(policy: Policy, frames: int) -> Reference:
    rows = np.stack([_motion_outputs(policy, t) for t in range(frames)])
    xyzw = rows[:, 61:65]
    return Reference(
        joint_pos=rows[:, 0:29],
        joint_vel=rows[:, 29:58],
        torso_pos=rows[:, 58:61],
        torso_quat=np.concatenate([xyzw[:, 3:4], xyzw[:, 0:3]], axis=1),
    )
