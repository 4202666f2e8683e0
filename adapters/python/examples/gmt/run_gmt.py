"""Run a GMT checkpoint (23 joints; TorchScript `.pt` or ONNX, input [batch, 2154], output
[batch, 23]) as the policy of a ThorArena run serving session NAME:

    cargo run --release -- eval --policy ipc:NAME --dataset DIR   # one shell
    python run_gmt.py --session NAME --policy pretrained.pt                    # another

The process declares the `gmt` profile at connect, so the run needs no `--profile`.

It joins with GMT's 20 reference offsets (0.02 … 1.9 s) under the name "gmt" and answers
each step with the network's raw output on the 23 joints it drives (wrists: action 0).
ONNX needs onnxruntime (`pip install './adapters/python[policies]'`), TorchScript needs torch.
"""

from __future__ import annotations

import argparse
import sys

from thorarena import ThorArenaError
from thorarena.adapters import GmtAdapter, load_policy


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--session", required=True, help="session to join")
    parser.add_argument("--policy", required=True, help="GMT policy: .onnx, or TorchScript (.pt)")
    parser.add_argument("--threads", type=int, default=1, help="inference intra-op threads")
    parser.add_argument("--name", default=GmtAdapter.name, help="policy name in the results")
    parser.add_argument(
        "--timeout", type=float, default=10.0, help="seconds to wait for the simulator"
    )
    args = parser.parse_args()

    adapter = GmtAdapter(load_policy(args.policy, intra_op_threads=args.threads))
    session = adapter.connect(args.session, name=args.name, timeout_s=args.timeout)
    print(
        f"connected: {session.n_envs} environments, control dt {session.control_dt_s} s",
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
