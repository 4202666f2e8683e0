"""The latency-benchmark echo: answer each step with each slot's joint positions (action = q).

Options for failure tests: `--die-after-steps N` kills this process (SIGKILL, no cleanup)
after answering N steps, on receiving step N + 1; `--delay-ms X --delay-at-step K` sleeps
X ms before answering step K (1-based), for late-reply tests. Prints "connected" on stdout
once connected, so a driver can synchronise.

    python echo_policy.py --session NAME [--die-after-steps N] [--delay-ms X --delay-at-step K]
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
import time

import thorarena as ta
from thorarena import ThorArenaError


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--session", required=True, help="session to join")
    parser.add_argument("--name", default="echo-python", help="policy name recorded in the results")
    parser.add_argument(
        "--timeout", type=float, default=10.0, help="seconds to wait for the simulator"
    )
    parser.add_argument("--spin-us", type=float, default=50.0, help="busy-poll before blocking, µs")
    parser.add_argument(
        "--die-after-steps", type=int, default=None, metavar="N", help="SIGKILL self after N steps"
    )
    parser.add_argument(
        "--delay-ms", type=float, default=0.0, metavar="X", help="sleep X ms on step K"
    )
    parser.add_argument(
        "--delay-at-step", type=int, default=None, metavar="K", help="the step to delay (1-based)"
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
        spin_us=args.spin_us,
        profile=None if args.profile == "none" else args.profile,
    )
    print("connected", flush=True)
    for step, (obs, actions) in enumerate(session.steps(), start=1):
        if args.die_after_steps is not None and step == args.die_after_steps + 1:
            # Step N's actions went out when the loop resumed; die holding step N + 1.
            os.kill(os.getpid(), signal.SIGKILL)
        if step == args.delay_at_step and args.delay_ms > 0:
            time.sleep(args.delay_ms / 1000.0)
        actions[:] = obs["q"]
    print(f"run over after {session.steps_answered} steps", flush=True)
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except ThorArenaError as e:  # no session, refused, timed out: the message says why
        sys.exit(f"error: {e}")
