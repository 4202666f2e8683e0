#!/usr/bin/env python3
"""What a change of one factor does to the FATS a policy loses to the forces, paired per sequence.

A run of `thorarena eval` scores every sequence with force and without; the loss to the
forces of one sequence is its no-force score minus its force score. Two runs of the same
policy on the same dataset and engine that differ in one factor (its profile's gains, say)
give two losses per sequence, and their difference is paired: the sequence, its motion and
its forces are the same on both sides, so sequence-to-sequence variety cancels. This prints,
per task and over tasks (each task weighted equally, as FATS weights them):

- each run's FATS with force and without, and its survival under force;
- the mean paired difference of the losses (B - A) with a bootstrap 95 % interval that
  resamples sequences within each task (a stratified bootstrap: every resample keeps each
  task's number of sequences, as the score's own intervals do).

Usage:
    python3 tools/force_loss_ablation.py A_RUN B_RUN [--label-a NAME] [--label-b NAME]

A_RUN and B_RUN are run directories (each with `episodes.csv` and `run.json`). The two must
hold the same sequences on the same dataset (checked: `dataset_sha256`) and engine; a
sequence missing either setting in either run is refused, not skipped.
"""

from __future__ import annotations

import argparse
import csv
import json
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

RESAMPLES = 10_000
SEED = 0


class AblationError(Exception):
    """Two runs that cannot be paired, or a run that cannot be read."""


@dataclass(frozen=True)
class Episode:
    """One sequence's scores in one run."""

    task: str
    force: float
    no_force: float
    survival_force: float

    @property
    def loss(self) -> float:
        """FATS points lost to the forces on this sequence."""
        return self.no_force - self.force


def read_run(run: Path) -> tuple[dict[str, object], dict[str, Episode]]:
    """The run's header and its episodes by sequence id (both settings required)."""
    try:
        header = json.loads((run / "run.json").read_text())
        rows = list(csv.DictReader((run / "episodes.csv").open()))
    except (OSError, ValueError) as e:
        raise AblationError(f"{run}: {e}") from e
    by_seq: dict[str, dict[str, dict[str, str]]] = {}
    for r in rows:
        by_seq.setdefault(r["sequence_id"], {})[r["setting"]] = r
    episodes = {}
    for seq, settings in by_seq.items():
        if "force" not in settings or "no-force" not in settings:
            raise AblationError(f"{run}: {seq} lacks the force or the no-force episode")
        f, n = settings["force"], settings["no-force"]
        episodes[seq] = Episode(
            f["task"], float(f["score"]), float(n["score"]), float(f["survival"])
        )
    return header, episodes


def task_means(values: dict[str, list[float]]) -> float:
    """The mean over tasks of each task's mean."""
    return float(np.mean([np.mean(v) for v in values.values()]))


def stratified_ci(
    values: dict[str, list[float]], resamples: int = RESAMPLES, seed: int = SEED
) -> tuple[float, float]:
    """Bootstrap 95 % interval of `task_means`, resampling within each task."""
    rng = np.random.default_rng(seed)
    groups = [np.asarray(v, dtype=float) for v in values.values()]
    means = np.zeros(resamples)
    for g in groups:
        idx = rng.integers(0, len(g), size=(resamples, len(g)))
        means += g[idx].mean(axis=1)
    means /= len(groups)
    lo, hi = np.percentile(means, [2.5, 97.5])
    return float(lo), float(hi)


@dataclass(frozen=True)
class Row:
    """One line of the table: a task, or all tasks."""

    name: str
    a_force: float
    a_no_force: float
    a_survival: float
    b_force: float
    b_no_force: float
    b_survival: float
    diff: float
    ci: tuple[float, float] | None


def compare(a: dict[str, Episode], b: dict[str, Episode]) -> list[Row]:
    """Per task and over tasks: both runs' scores and the paired difference of the losses."""
    if set(a) != set(b):
        only = sorted(set(a) ^ set(b))
        raise AblationError(f"the runs hold different sequences (e.g. {only[:3]})")
    by_task: dict[str, list[str]] = {}
    for seq, ep in sorted(a.items()):
        if b[seq].task != ep.task:
            raise AblationError(f"{seq} is {ep.task} in one run and {b[seq].task} in the other")
        by_task.setdefault(ep.task, []).append(seq)

    def row(name: str, tasks: dict[str, list[str]]) -> Row:
        def over(f: Callable[[str], float]) -> float:
            return task_means({t: [f(s) for s in seqs] for t, seqs in tasks.items()})

        diffs = {t: [b[s].loss - a[s].loss for s in seqs] for t, seqs in tasks.items()}
        many = any(len(v) > 1 for v in diffs.values())
        return Row(
            name,
            over(lambda s: a[s].force),
            over(lambda s: a[s].no_force),
            over(lambda s: a[s].survival_force),
            over(lambda s: b[s].force),
            over(lambda s: b[s].no_force),
            over(lambda s: b[s].survival_force),
            task_means(diffs),
            stratified_ci(diffs) if many else None,
        )

    rows = [row(t, {t: seqs}) for t, seqs in by_task.items()]
    rows.append(row("all tasks", by_task))
    return rows


def table(rows: list[Row], label_a: str, label_b: str) -> str:
    """The rows as Markdown."""
    out = [
        f"| task | {label_a}: force / no-force / survival "
        f"| {label_b}: force / no-force / survival "
        f"| lost to forces, {label_a} | lost to forces, {label_b} "
        f"| {label_b} - {label_a} (95 % CI) |",
        "|---|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        ci = f" ({r.ci[0]:+.1f} to {r.ci[1]:+.1f})" if r.ci else ""
        out.append(
            f"| {r.name} | {r.a_force:.1f} / {r.a_no_force:.1f} / {r.a_survival:.3f} "
            f"| {r.b_force:.1f} / {r.b_no_force:.1f} / {r.b_survival:.3f} "
            f"| {r.a_no_force - r.a_force:.1f} | {r.b_no_force - r.b_force:.1f} "
            f"| {r.diff:+.1f}{ci} |"
        )
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    p.add_argument("a", type=Path, help="the reference run (its own profile, say)")
    p.add_argument("b", type=Path, help="the run with one factor changed")
    p.add_argument("--label-a", default="A")
    p.add_argument("--label-b", default="B")
    args = p.parse_args(argv)
    try:
        ha, a = read_run(args.a)
        hb, b = read_run(args.b)
        for key in ("dataset_sha256", "engine", "policy"):
            if ha.get(key) != hb.get(key):
                raise AblationError(f"the runs differ in {key}: {ha.get(key)} / {hb.get(key)}")
        print(table(compare(a, b), args.label_a, args.label_b))
    except AblationError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
