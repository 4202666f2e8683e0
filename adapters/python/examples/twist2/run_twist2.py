"""Run a TWIST2 checkpoint (ONNX, input `input` [batch, 1432], output `output` [batch, 29])
as the policy of a ThorArena run serving session NAME:

    cargo run --release -- eval --policy ipc:NAME --dataset DIR   # one shell
    python run_twist2.py --session NAME --onnx twist2.onnx                         # another

The process declares the `twist2` profile at connect, so the run needs no `--profile`.

It joins with the adapter's reference offsets (0 and 0.02 s) under the name "twist2" and
answers each step with the network's raw output for every active slot. By default the
simulator builds TWIST2's 1432-float observation into the batch (the same Rust code the
in-process policy uses) and the network runs on it in place; `--observation python` builds
it here in numpy instead. Needs onnxruntime (`pip install './adapters/python[policies]'`).
"""

from __future__ import annotations

import argparse
import json
import sys

import numpy as np

from thorarena import ThorArenaError
from thorarena.adapters import OnnxPolicy, Twist2Adapter


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--session", required=True, help="session to join")
    parser.add_argument("--onnx", required=True, help="TWIST2 policy exported to ONNX")
    parser.add_argument("--threads", type=int, default=1, help="ONNX Runtime intra-op threads")
    parser.add_argument("--name", default=Twist2Adapter.name, help="policy name in the results")
    parser.add_argument(
        "--timeout", type=float, default=10.0, help="seconds to wait for the simulator"
    )
    parser.add_argument(
        "--observation",
        choices=("simulator", "python"),
        default="simulator",
        help="who builds TWIST2's observation: the simulator, into the batch (default), or "
        "this adapter in numpy",
    )
    parser.add_argument(
        "--spin-us",
        type=float,
        default=50.0,
        help="busy-poll this long for each observation before blocking, µs (longer: lower "
        "latency, a core kept busy)",
    )
    parser.add_argument(
        "--transport",
        choices=("python", "native", "auto"),
        default="auto",
        help="the session over iceoryx2's Python binding, or over the C ABI "
        "(libthorarena_ipc.so: cargo build --release -p thorarena-ipc; THORARENA_IPC_LIB "
        "names it; about 15 µs less per step), or (auto, the default) the C ABI when found",
    )
    parser.add_argument(
        "--time-network",
        action="store_true",
        help="time every network call; at the end print one JSON line "
        '{"network_us": {"count", "p50", "p90", "p99", "each": [every call]}} on stdout',
    )
    args = parser.parse_args()

    adapter = Twist2Adapter(OnnxPolicy(args.onnx, intra_op_threads=args.threads))
    if args.time_network:
        adapter.network_s = []
    session = adapter.connect(
        args.session,
        name=args.name,
        timeout_s=args.timeout,
        spin_us=args.spin_us,
        input=Twist2Adapter.simulator_input if args.observation == "simulator" else None,
        transport=args.transport,
    )
    built = "the simulator" if session.layout.n_inputs else "this adapter"
    print(
        f"connected: {session.n_envs} environments, control dt {session.control_dt_s} s, "
        f"observation built by {built}, session over {type(session).__name__}",
        flush=True,
    )
    steps = adapter.run(session)
    print(f"run over after {steps} steps", flush=True)
    if adapter.network_s is not None:
        us = np.asarray(adapter.network_s) * 1e6
        p50, p90, p99 = (float(np.percentile(us, q)) for q in (50, 90, 99))
        each = [round(float(x), 2) for x in us]
        timing = {"count": len(us), "p50": p50, "p90": p90, "p99": p99, "each": each}
        print(json.dumps({"network_us": timing}), flush=True)
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except ThorArenaError as e:  # no session, refused, timed out: the message says why
        sys.exit(f"error: {e}")
