"""Cross-check the Rust TWIST2 policy (`src/policy/twist2.rs`) against the Python adapter.

    python check_against_dump.py --dump episode.json --onnx twist2.onnx

The dump is JSON written by the Rust side for consecutive steps of one episode from step 0
(format in `thorarena.adapters.dump`). Each step's `env` goes through the Python adapter
as a one-slot batch; its observation must be within 1e-5 of the dump's and the ONNX Runtime
action within 1e-4. Prints the maxima; exits 1 on a mismatch, 0 otherwise.
"""

from __future__ import annotations

import argparse
import sys

from thorarena.adapters import OnnxPolicy, Twist2Adapter
from thorarena.adapters.dump import ACTION_TOLERANCE, OBS_TOLERANCE, compare_dump, load_dump


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--dump", required=True, help="JSON dump of one episode (Rust side)")
    parser.add_argument("--onnx", required=True, help="the TWIST2 ONNX the dump was made with")
    parser.add_argument("--threads", type=int, default=1, help="ONNX Runtime intra-op threads")
    args = parser.parse_args()

    dump = load_dump(args.dump)
    adapter = Twist2Adapter(OnnxPolicy(args.onnx, intra_op_threads=args.threads))
    result = compare_dump(dump, adapter)
    worst_obs = max(result.steps, key=lambda s: s.obs_max_abs)
    print(
        f"{len(result.steps)} steps; observation max |diff| {result.obs_max_abs:.3g} "
        f"(step {worst_obs.step}, index {worst_obs.obs_argmax}; tolerance {OBS_TOLERANCE:g})"
    )
    action = result.action_max_abs
    assert action is not None
    worst_action = max(result.steps, key=lambda s: s.action_max_abs or 0.0)
    print(
        f"action max |diff| {action:.3g} (step {worst_action.step}; tolerance {ACTION_TOLERANCE:g})"
    )
    if not result.ok():
        print("MISMATCH", file=sys.stderr)
        return 1
    print("ok")
    return 0


if __name__ == "__main__":
    sys.exit(main())
