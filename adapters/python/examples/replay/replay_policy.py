"""The cross-language example scenario "replay": answer each step with the action that makes
the PD target equal the first reference frame's joint positions.

    action = (reference[0].joint_pos - action_offset_rad) / action_scale   (active slots)
    action = 0                                                             (inactive slots)

Run it against a ThorArena run serving session NAME:

    python replay_policy.py --session NAME
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

import thorarena as ta
from thorarena import ThorArenaError


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--session", required=True, help="session to join")
    parser.add_argument(
        "--name", default="replay-python", help="policy name recorded in the results"
    )
    parser.add_argument(
        "--timeout", type=float, default=10.0, help="seconds to wait for the simulator"
    )
    parser.add_argument(
        "--transport",
        choices=("python", "native", "auto"),
        default="python",
        help="iceoryx2's Python binding (default), or the C ABI (libthorarena_ipc.so, "
        "THORARENA_IPC_LIB), or that when found",
    )
    parser.add_argument(
        "--profile",
        default="default",
        help="the bundled profile declared at connect as the one this policy runs under "
        "(default: %(default)s, the built-in baselines'); 'none' declares none, so the run "
        "must name one with --profile",
    )
    args = parser.parse_args()

    session = ta.connect(
        args.session,
        name=args.name,
        joint_names=ta.G1_JOINT_NAMES,
        timeout_s=args.timeout,
        transport=args.transport,
        profile=None if args.profile == "none" else args.profile,
    )
    print(
        f"connected: {session.n_envs} environments, {session.n_joints} joints, "
        f"over {type(session).__name__}",
        flush=True,
    )
    for obs, actions in session.steps():
        active = (obs["flags"] & ta.FLAG_ACTIVE) != 0
        target = obs["reference"][:, 0]["joint_pos"]
        replay = (target - session.action_offset_rad) / session.action_scale
        actions[:] = np.where(active[:, None], replay, 0.0)
    print(f"run over after {session.steps_answered} steps", flush=True)
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except ThorArenaError as e:  # no session, refused, timed out: the message says why
        sys.exit(f"error: {e}")
