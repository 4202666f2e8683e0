"""tools/force_loss_ablation.py on hand-made runs: the paired difference of the losses, its
stratified interval, and the refusals of runs that cannot be paired."""

from __future__ import annotations

import csv
import json
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import force_loss_ablation as fla

FIELDS = [
    "task",
    "sequence_id",
    "setting",
    "survival",
    "kp_error_mean_mm",
    "kp_error_rms_mm",
    "score",
    "termination",
]


def write_run(d: Path, scores: dict[str, tuple[str, float, float]], dataset: str = "abc") -> Path:
    """A run directory: per sequence (task, force score, no-force score)."""
    d.mkdir()
    (d / "run.json").write_text(
        json.dumps({"dataset_sha256": dataset, "engine": {"name": "mujoco"}, "policy": "p"})
    )
    with (d / "episodes.csv").open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=FIELDS)
        w.writeheader()
        for seq, (task, force, none) in scores.items():
            for setting, score in (("force", force), ("no-force", none)):
                w.writerow(
                    {
                        "task": task,
                        "sequence_id": seq,
                        "setting": setting,
                        "survival": 1.0,
                        "kp_error_mean_mm": 0,
                        "kp_error_rms_mm": 0,
                        "score": score,
                        "termination": "",
                    }
                )
    return d


def test_the_paired_difference_is_each_tasks_mean_then_the_mean_over_tasks(tmp_path: Path) -> None:
    # Task t1 loses 10 in A and 4 in B on both sequences; t2 loses 2 in A and 2 in B.
    a = write_run(
        tmp_path / "a", {"s1": ("t1", 80, 90), "s2": ("t1", 70, 80), "s3": ("t2", 88, 90)}
    )
    b = write_run(
        tmp_path / "b", {"s1": ("t1", 86, 90), "s2": ("t1", 76, 80), "s3": ("t2", 88, 90)}
    )
    _, ea = fla.read_run(a)
    _, eb = fla.read_run(b)
    rows = {r.name: r for r in fla.compare(ea, eb)}
    assert rows["t1"].diff == pytest.approx(-6.0)
    assert rows["t2"].diff == pytest.approx(0.0)
    assert rows["all tasks"].diff == pytest.approx(-3.0)  # tasks weigh equally, not sequences
    # Every resample of identical differences gives them back: a zero-width interval.
    assert rows["t1"].ci == pytest.approx((-6.0, -6.0))
    assert rows["t2"].ci is None  # one sequence: nothing to resample


def test_the_interval_covers_the_mean_and_widens_with_spread(tmp_path: Path) -> None:
    scores_a = {f"s{i}": ("t", 80.0, 90.0) for i in range(20)}
    scores_b = {f"s{i}": ("t", 80.0 + (i % 5), 90.0) for i in range(20)}
    _, ea = fla.read_run(write_run(tmp_path / "a", scores_a))
    _, eb = fla.read_run(write_run(tmp_path / "b", scores_b))
    (row, _) = fla.compare(ea, eb)
    assert row.diff == pytest.approx(-2.0)
    assert row.ci is not None
    lo, hi = row.ci
    assert lo < -2.0 < hi and hi - lo > 0.5


def test_runs_that_cannot_be_paired_are_refused(tmp_path: Path) -> None:
    a = write_run(tmp_path / "a", {"s1": ("t1", 80, 90)})
    b = write_run(tmp_path / "b", {"s2": ("t1", 80, 90)})
    _, ea = fla.read_run(a)
    _, eb = fla.read_run(b)
    with pytest.raises(fla.AblationError, match="different sequences"):
        fla.compare(ea, eb)
    c = write_run(tmp_path / "c", {"s1": ("t1", 80, 90)}, dataset="other")
    assert fla.main([str(a), str(c)]) == 2
    half = tmp_path / "half"
    half.mkdir()
    (half / "run.json").write_text("{}")
    (half / "episodes.csv").write_text(",".join(FIELDS) + "\nt1,s1,force,1,0,0,80,\n")
    with pytest.raises(fla.AblationError, match="lacks the force or the no-force"):
        fla.read_run(half)
