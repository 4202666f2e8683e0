"""Cross-check a Rust in-process policy against its Python adapter on a dumped episode.

    python check_against_dump.py --adapter twist2 --dump episode.json --onnx twist2.onnx
    python check_against_dump.py --adapter beyondmimic --dump episode.json --onnx policy.onnx

The Rust policies are `src/policy/twist2.rs` and `src/policy/beyondmimic/`. The dump is JSON
written by the Rust side for consecutive steps of one episode from step 0 (format in
`thorarena.adapters.dump`). Each step's `env` goes through the Python adapter as a one-slot
batch; its observation must be within 1e-5 of the dump's and the ONNX Runtime action within
1e-4. Prints the maxima; exits 1 on a mismatch, 0 otherwise.
"""

from __future__ import annotations

import argparse
import sys

from thorarena.adapters import BeyondMimicAdapter, OnnxPolicy, Twist2Adapter
from thorarena.adapters.base import Adapter
from thorarena.adapters.dump import ACTION_TOLERANCE, OBS_TOLERANCE, compare_dump, load_dump


def make_adapter(
    kind: str, onnx: str, threads: int, observation_names: list[str] | None
) -> Adapter:
    """The Python adapter matching the Rust policy the dump was made with."""
    if kind == "twist2":
        return Twist2Adapter(OnnxPolicy(onnx, intra_op_threads=threads))
    return BeyondMimicAdapter.from_onnx(
        onnx, intra_op_threads=threads, observation_names=observation_names
    )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--adapter", required=True, choices=["twist2", "beyondmimic"])
    parser.add_argument("--dump", required=True, help="JSON dump of one episode (Rust side)")
    parser.add_argument("--onnx", required=True, help="the ONNX the dump was made with")
    parser.add_argument("--threads", type=int, default=1, help="ONNX Runtime intra-op threads")
    parser.add_argument(
        "--observation-names",
        type=lambda v: v.split(","),
        help="beyondmimic: the observation terms in order, comma separated, for a file that "
        "names none (the profile's [beyondmimic] observation_names)",
    )
    args = parser.parse_args()

    dump = load_dump(args.dump)
    adapter = make_adapter(args.adapter, args.onnx, args.threads, args.observation_names)
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
