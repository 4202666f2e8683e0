"""Run a BeyondMimic-style ONNX export (whole_body_tracking or mjlab tracking task, metadata
attached) as the policy of a ThorArena run serving session NAME:

    cargo run --release -- eval --policy ipc:NAME --dataset DIR   # one shell
    python run_beyondmimic.py --session NAME --onnx policy.onnx                        # another

The process declares the `beyondmimic` profile at connect, so the run needs no `--profile`.

Joint order, default pose and action scale come from the file's metadata. The gains it was
trained with are printed: the simulator's profile sets the real ones, so check them against
`data/profiles/beyondmimic.toml`. Needs onnxruntime (`pip install './adapters/python[policies]'`).
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from thorarena import ThorArenaError
from thorarena.adapters import BeyondMimicAdapter


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--session", required=True, help="session to join")
    parser.add_argument("--onnx", required=True, help="policy.onnx with BeyondMimic metadata")
    parser.add_argument("--threads", type=int, default=1, help="ONNX Runtime intra-op threads")
    parser.add_argument(
        "--observation-names",
        type=lambda v: v.split(","),
        help="the observation terms in order, comma separated, for a file that names none "
        "(e.g. holosoma's: actions,base_ang_vel,dof_pos,dof_vel,motion_command,motion_ref_ori_b)",
    )
    parser.add_argument(
        "--name", default=BeyondMimicAdapter.name, help="policy name in the results"
    )
    parser.add_argument(
        "--timeout", type=float, default=10.0, help="seconds to wait for the simulator"
    )
    args = parser.parse_args()

    adapter = BeyondMimicAdapter.from_onnx(
        args.onnx, intra_op_threads=args.threads, observation_names=args.observation_names
    )
    meta = adapter.metadata
    print(f"observation: {', '.join(adapter.terms)} ({adapter.obs_dim})", flush=True)
    print(f"anchor body: {meta.anchor_body_name}", flush=True)
    for what, values in (("kp", meta.joint_stiffness), ("kd", meta.joint_damping)):
        if values is not None:
            canonical = np.round(adapter.canonical(values), 3).tolist()
            print(f"trained {what} (canonical order): {canonical}")
    session = adapter.connect(args.session, name=args.name, timeout_s=args.timeout)
    print(
        f"connected: {session.n_envs} environments, control dt {session.control_dt_s} s",
        flush=True,
    )
    adapter.bind(
        n_envs=session.n_envs,
        action_offset_rad=session.action_offset_rad,
        action_scale=session.action_scale,
    )
    print(
        f"session action mapping vs metadata: {adapter.mapping_mismatch():.4f} rad at most "
        "(the adapter converts, so targets are the policy's either way)",
        flush=True,
    )
    steps = adapter.run(session)
    print(f"run over after {steps} steps", flush=True)
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except ThorArenaError as e:  # no session, refused, timed out: the message says why
        sys.exit(f"error: {e}")
