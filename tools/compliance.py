#!/usr/bin/env python3
"""How far a wrist yields per newton under a force event, against the stiffness commanded.

SoftMimic (arXiv:2510.17792) commands a stiffness k for its end effectors and measures
compliance as the displacement per newton, to be compared with 1/k. This does the same on
`thorarena eval` runs with traces (`--trace TASK/SEQUENCE`) holding, for one sequence,
`no-force` and force events (`event:<N>@<deg>:hand=...`):

- the wrist's yield at each control step is its world position in the event episode minus
  its position in the no-force episode at the same time (the same clip, the same policy:
  the motion cancels), projected on the event's direction;
- the yield is averaged over the last `--window` seconds of the hold (the force steady);
- the effective stiffness is the force over that yield, N/m, per direction and as the
  force over the mean yield of the directions.

Usage:
    python3 tools/compliance.py RUN [RUN ...] [--window 0.5] [--svg FIGURE.svg]

Each RUN is a run directory with `run.json` and `traces/`; the figure draws the runs named
`<series>-<k>` (a stiffness sweep) as one line per series. A run's commanded stiffness is
its `policy_parameters.stiffness_n_per_m` (none for a network without a stiffness command).
The wrist is the `right_wrist_yaw_link` or `left_wrist_yaw_link` keypoint of the run's
keypoint set, its position in the trace's `keypoints_w`.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from dataclasses import dataclass
from pathlib import Path

from g1_keypoints import DEFAULT_KEYPOINT_BODIES

WRIST = {"right": "right_wrist_yaw_link", "left": "left_wrist_yaw_link"}

KEYPOINT_SETS = {"default": list(DEFAULT_KEYPOINT_BODIES)}


class ComplianceError(Exception):
    """A run that cannot be read or measured."""


@dataclass(frozen=True)
class Event:
    """A force event's setting, parsed from its canonical name."""

    name: str
    force_n: float
    heading_deg: float
    hand: str
    hold_from_s: float
    hold_until_s: float


def parse_event(name: str) -> Event | None:
    """The event named `name` (canonical: every field written out), or None."""
    if not name.startswith("event:"):
        return None
    parts = name[len("event:") :].split(":")
    force, _, heading = parts[0].partition("@")
    fields = dict(p.split("=", 1) for p in parts[1:])
    try:
        start = float(fields["start"])
        ramp = float(fields["ramp"])
        hold = float(fields["hold"])
        return Event(
            name=name,
            force_n=float(force),
            heading_deg=float(heading or 0.0),
            hand=fields["hand"],
            hold_from_s=start + ramp,
            hold_until_s=start + ramp + hold,
        )
    except (KeyError, ValueError) as e:
        raise ComplianceError(f"`{name}` is no canonical event name ({e})") from e


@dataclass(frozen=True)
class Measured:
    """One event's yield."""

    event: Event
    yield_m: float

    @property
    def effective_n_per_m(self) -> float:
        """Force over yield, N/m (infinite for no yield)."""
        return self.event.force_n / self.yield_m if self.yield_m > 0 else math.inf


def read_json(path: Path) -> object:
    try:
        return json.loads(path.read_text())
    except (OSError, json.JSONDecodeError) as e:
        raise ComplianceError(f"{path}: {e}") from e


def wrist_yield_m(
    event_steps: list[dict[str, object]],
    free_steps: list[dict[str, object]],
    wrist: int,
    side: int,
    event: Event,
    window_s: float,
) -> float:
    """The wrist's mean yield along the event's force over the hold's last `window_s`, m."""
    free = {round(float(str(s["time_s"])), 6): s for s in free_steps}
    from_s = max(event.hold_from_s, event.hold_until_s - window_s)
    along: list[float] = []
    for s in event_steps:
        t = float(str(s["time_s"]))
        if not (from_s <= t < event.hold_until_s):
            continue
        f = s["hand_force_w"][side]  # type: ignore[index]
        norm = math.sqrt(sum(float(x) ** 2 for x in f))
        other = free.get(round(t, 6))
        if norm == 0 or other is None:
            continue
        here = s["keypoints_w"][wrist]  # type: ignore[index]
        there = other["keypoints_w"][wrist]  # type: ignore[index]
        along.append(
            sum(
                (float(a) - float(b)) * float(x) / norm
                for a, b, x in zip(here, there, f, strict=True)
            )
        )
    if not along:
        raise ComplianceError(
            f"{event.name}: no traced step of its hold ({from_s} to {event.hold_until_s} s)"
            " with the force acting and a no-force step beside it"
        )
    return sum(along) / len(along)


def measure_run(run: Path, window_s: float) -> tuple[float | None, list[Measured]]:
    """A run's commanded stiffness and each of its traced events' yields."""
    header = read_json(run / "run.json")
    if not isinstance(header, dict):
        raise ComplianceError(f"{run}/run.json is no run header")
    params = header.get("policy_parameters") or {}
    stiffness = params.get("stiffness_n_per_m") if isinstance(params, dict) else None
    keypoints = KEYPOINT_SETS.get(str(header.get("keypoints", "default")))
    if keypoints is None:
        raise ComplianceError(
            f"{run}: keypoint set `{header.get('keypoints')}` is not one this tool knows"
        )
    traces = sorted((run / "traces").glob("*.json"))
    free = [t for t in traces if t.name.endswith("-no-force.json")]
    if len(free) != 1:
        raise ComplianceError(
            f"{run}/traces: one traced no-force episode is needed, found {len(free)}"
        )
    prefix = free[0].name[: -len("no-force.json")]
    free_steps = read_json(free[0])
    out: list[Measured] = []
    for trace in traces:
        event = parse_event(trace.name[len(prefix) : -len(".json")])
        if event is None:
            continue
        if event.hand not in WRIST:
            raise ComplianceError(f"{event.name}: one hand is measured, not `{event.hand}`")
        steps = read_json(trace)
        if not isinstance(steps, list) or not isinstance(free_steps, list):
            raise ComplianceError(f"{trace}: a trace is a list of steps")
        side = 1 if event.hand == "right" else 0
        wrist = keypoints.index(WRIST[event.hand])
        out.append(Measured(event, wrist_yield_m(steps, free_steps, wrist, side, event, window_s)))
    if not out:
        raise ComplianceError(f"{run}/traces: no traced force event")
    return (float(stiffness) if stiffness is not None else None), out


def table(rows: list[tuple[str, float | None, list[Measured]]]) -> str:
    """The Markdown table: per run, the yield per direction and the effective stiffness."""
    lines = [
        "| run | commanded k (N/m) | force (N) | yield per direction (mm) | mean yield (mm)"
        " | effective k (N/m) | effective / commanded |",
        "|---|---:|---:|---|---:|---:|---:|",
    ]
    for label, k, measured in rows:
        force = measured[0].event.force_n
        yields = [m.yield_m for m in sorted(measured, key=lambda m: m.event.heading_deg)]
        mean = sum(yields) / len(yields)
        k_eff = force / mean if mean > 0 else math.inf
        per = " / ".join(f"{1e3 * y:.1f}" for y in yields)
        ratio = f"{k_eff / k:.2f}" if k else "-"
        lines.append(
            f"| {label} | {k if k is not None else '-'} | {force:g} | {per} | {1e3 * mean:.1f}"
            f" | {k_eff:.0f} | {ratio} |"
        )
    return "\n".join(lines) + "\n"


def svg(points: list[tuple[str, float, float]], title: str) -> str:
    """A log-log figure of effective against commanded stiffness, with the identity line."""
    w, h, m = 420, 320, 50
    lo, hi = 10.0, 3000.0

    def x(v: float) -> float:
        return m + (w - 2 * m) * (math.log10(v) - math.log10(lo)) / (
            math.log10(hi) - math.log10(lo)
        )

    def y(v: float) -> float:
        return (
            h
            - m
            - (h - 2 * m) * (math.log10(v) - math.log10(lo)) / (math.log10(hi) - math.log10(lo))
        )

    out = [
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}"'
        ' font-family="sans-serif" font-size="11">',
        f'<text x="{w / 2}" y="16" text-anchor="middle">{title}</text>',
        f'<line x1="{x(lo)}" y1="{y(lo)}" x2="{x(hi)}" y2="{y(hi)}"'
        ' stroke="#999" stroke-dasharray="4 3"/>',
        f'<line x1="{m}" y1="{h - m}" x2="{w - m}" y2="{h - m}" stroke="black"/>',
        f'<line x1="{m}" y1="{m}" x2="{m}" y2="{h - m}" stroke="black"/>',
        f'<text x="{w / 2}" y="{h - 12}" text-anchor="middle">commanded stiffness (N/m)</text>',
        f'<text x="14" y="{h / 2}" text-anchor="middle" transform="rotate(-90 14 {h / 2})">'
        "effective stiffness (N/m)</text>",
    ]
    for tick in (10, 30, 100, 300, 1000, 3000):
        out.append(f'<text x="{x(tick)}" y="{h - m + 14}" text-anchor="middle">{tick}</text>')
        out.append(f'<text x="{m - 4}" y="{y(tick) + 4}" text-anchor="end">{tick}</text>')
    colours = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd"]
    series = sorted({s for s, _, _ in points})
    for i, name in enumerate(series):
        c = colours[i % len(colours)]
        pts = sorted((k, e) for s, k, e in points if s == name)
        path = " ".join(f"{x(k):.1f},{y(min(max(e, lo), hi)):.1f}" for k, e in pts)
        out.append(f'<polyline points="{path}" fill="none" stroke="{c}"/>')
        for k, e in pts:
            out.append(
                f'<circle cx="{x(k):.1f}" cy="{y(min(max(e, lo), hi)):.1f}" r="3" fill="{c}"/>'
            )
        out.append(f'<text x="{m + 8}" y="{m + 14 * (i + 1)}" fill="{c}">{name}</text>')
    out.append("</svg>")
    return "\n".join(out) + "\n"


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("runs", nargs="+", type=Path)
    ap.add_argument(
        "--window", type=float, default=0.5, help="seconds at the hold's end averaged (default 0.5)"
    )
    ap.add_argument("--svg", type=Path, help="write the effective-against-commanded figure here")
    ap.add_argument("--title", default="Effective against commanded stiffness")
    args = ap.parse_args(argv)
    if not (args.window > 0):
        print("compliance: --window must be positive", file=sys.stderr)
        return 2
    rows: list[tuple[str, float | None, list[Measured]]] = []
    try:
        for run in args.runs:
            k, measured = measure_run(run, args.window)
            rows.append((run.name, k, measured))
    except ComplianceError as e:
        print(f"compliance: {e}", file=sys.stderr)
        return 1
    print(table(rows), end="")
    if args.svg:
        points: list[tuple[str, float, float]] = []
        for label, k, measured in rows:
            if k is None:
                continue
            series, _, last = label.rpartition("-")
            mean = sum(m.yield_m for m in measured) / len(measured)
            # A run named `<series>-<k>` is one point of a stiffness sweep; others (a stiff
            # baseline) are in the table only.
            if mean > 0 and last.replace(".", "", 1).isdigit():
                points.append((series, k, measured[0].event.force_n / mean))
        args.svg.write_text(svg(points, args.title))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
