"""Cross-checking another implementation of an adapter against this one, step by step.

A dump is JSON written by the other side (the Rust policies do, for one episode):

    {"action_offset_rad": [29], "action_scale": [29],
     "steps": [{"env": {<every wire field by name; "reference": a list of frame dicts>},
                "obs": [the other side's observation], "action": [its raw actions]}, ...]}

with consecutive steps of one episode from step 0. `compare_dump` feeds each `env` to a
Python adapter as a one-slot batch with the session's dtype, in order, and reports the
largest differences of observation and action.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..protocol import ENV_ARRAYS, ENV_HEADER_DTYPE, FLAG_ACTIVE, REF_ARRAYS, Layout
from .base import Adapter

OBS_TOLERANCE = 1e-5
"""Largest observation difference accepted (the observations are float32)."""
ACTION_TOLERANCE = 1e-4
"""Largest action difference accepted (ONNX Runtime versions and thread counts differ)."""


def load_dump(path: str | os.PathLike[str]) -> dict[str, Any]:
    """A dump file, with its top-level keys checked."""
    with open(path, encoding="utf-8") as f:
        dump: dict[str, Any] = json.load(f)
    missing = [k for k in ("action_offset_rad", "action_scale", "steps") if k not in dump]
    if missing:
        raise ValueError(f"{path}: not a dump, it lacks {missing}")
    return dump


def env_record(env: Mapping[str, Any], layout: Layout) -> np.ndarray:
    """One environment block as a one-record array of `layout.env_dtype`, from its fields
    by name (`reserved` may be absent; any other missing field is an error)."""
    record = np.zeros(1, dtype=layout.env_dtype)
    assert ENV_HEADER_DTYPE.names is not None
    for name in ENV_HEADER_DTYPE.names:
        if name in env:
            record[name] = env[name]
        elif name != "reserved":
            raise ValueError(f"env lacks {name!r}")
    for name, _, _ in ENV_ARRAYS:
        if name not in env:
            raise ValueError(f"env lacks {name!r}")
        record[name][0] = env[name]
    frames: Sequence[Mapping[str, Any]] = env.get("reference", ())
    if len(frames) != layout.n_refs:
        raise ValueError(f"env has {len(frames)} reference frames, the layout {layout.n_refs}")
    for i, frame in enumerate(frames):
        for name, _, _ in REF_ARRAYS:
            if name not in frame:
                raise ValueError(f"reference[{i}] lacks {name!r}")
            record["reference"][0, i][name] = frame[name]
    return record


@dataclass(kw_only=True)
class StepDiff:
    """How far one step of the dump is from the Python adapter."""

    step: int
    """The env's `step`."""
    obs_max_abs: float
    """max |obs_dump - obs_python|."""
    obs_argmax: int
    """Index of that largest observation difference."""
    action_max_abs: float | None
    """max |action_dump - action_python|; None without a network."""


@dataclass(kw_only=True)
class DumpComparison:
    """Every step's differences and the maxima over the episode."""

    steps: list[StepDiff] = field(default_factory=list)

    @property
    def obs_max_abs(self) -> float:
        """Largest observation difference over all steps."""
        return max((s.obs_max_abs for s in self.steps), default=0.0)

    @property
    def action_max_abs(self) -> float | None:
        """Largest action difference over all steps (None without a network)."""
        diffs = [s.action_max_abs for s in self.steps if s.action_max_abs is not None]
        return max(diffs) if diffs else None

    def ok(
        self, obs_tolerance: float = OBS_TOLERANCE, action_tolerance: float = ACTION_TOLERANCE
    ) -> bool:
        """True when every difference is within its tolerance."""
        action = self.action_max_abs
        return self.obs_max_abs <= obs_tolerance and (action is None or action <= action_tolerance)


def compare_dump(dump: Mapping[str, Any], adapter: Adapter) -> DumpComparison:
    """Feeds the dump's steps to `adapter` (bound here to one slot and the dump's action
    mapping) and compares its observations, and its actions when it has a network."""
    steps = dump["steps"]
    if not steps:
        raise ValueError("the dump has no steps")
    n_refs = len(steps[0]["env"].get("reference", ()))
    layout = Layout(n_envs=1, n_joints=len(adapter.joint_names), n_refs=n_refs)
    adapter.bind(
        n_envs=1,
        action_offset_rad=np.asarray(dump["action_offset_rad"], dtype=np.float64),
        action_scale=np.asarray(dump["action_scale"], dtype=np.float64),
    )
    comparison = DumpComparison()
    for i, entry in enumerate(steps):
        record = env_record(entry["env"], layout)
        step = int(record["step"][0])
        if step != i:
            raise ValueError(
                f"entry {i} has step {step}: the dump must start at 0 and be consecutive"
            )
        # The dump is one live episode: its slot is active whatever flags were recorded.
        record["flags"] |= FLAG_ACTIVE
        actions = np.zeros((1, layout.n_joints))
        obs = adapter.act(record, actions)[0]
        theirs = np.asarray(entry["obs"], dtype=np.float64)
        if theirs.shape != obs.shape:
            raise ValueError(
                f"step {step}: the dump's obs has {theirs.size} values, Python's {obs.size}"
            )
        obs_diff = np.abs(theirs - obs.astype(np.float64))
        action_diff = None
        if adapter.policy is not None:
            their_action = np.asarray(entry["action"], dtype=np.float64)
            action_diff = float(np.max(np.abs(their_action - actions[0])))
        comparison.steps.append(
            StepDiff(
                step=step,
                obs_max_abs=float(obs_diff.max()),
                obs_argmax=int(obs_diff.argmax()),
                action_max_abs=action_diff,
            )
        )
    return comparison
