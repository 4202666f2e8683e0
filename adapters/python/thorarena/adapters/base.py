"""What every policy adapter shares: per-slot state, batching over active slots, the loop.

An adapter turns the wire's observation batch into a network's input, runs the network on
the active slots in one batch, and writes its output as raw actions. A subclass says which
reference frames it needs (`reference_offsets_s`), which per-slot state it keeps
(`slot_state`, zeros on an episode's first step), how to build the network input from the
active records (`observe`) and, if the network's output is not already the 29 raw actions
in canonical order, how to map it (`actions_from_outputs`).

    adapter = Twist2Adapter(OnnxPolicy("policy.onnx"))
    adapter.run(adapter.connect("demo"))
"""

from __future__ import annotations

import time
from abc import ABC, abstractmethod
from typing import Any, ClassVar

import numpy as np

from ..client import Session, connect
from ..protocol import FLAG_ACTIVE, FLAG_RESET, G1_JOINT_NAMES, Profile
from .runtime import Policy


class Adapter(ABC):
    """A policy whose observation is built in Python from ThorArena's wire observation."""

    name: ClassVar[str] = "adapter"
    """Policy name recorded in the results (`Hello.name`)."""
    joint_names: ClassVar[tuple[str, ...]] = G1_JOINT_NAMES
    """Joint order of the wire, checked by the simulator at connect time."""
    reference_offsets_s: ClassVar[tuple[float, ...]] = (0.0,)
    """Reference frames to ask for, seconds ahead of each step."""
    obs_dim: int = 0
    """Width of the network input."""
    state_dtypes: ClassVar[dict[str, type]] = {}
    """The dtype of a per-slot state array, where it is not float64."""
    simulator_input: ClassVar[str | None] = None
    """A network input the simulator builds for this adapter (`connect(input=...)`), the
    same vector `observe` builds: `connect` asks for it unless told `input=None`, and
    `run` then feeds the network from the session's policy-input block."""

    profile: ClassVar[str | Profile | None] = None
    """The dynamics profile the network was trained under, declared at connect
    (`connect(profile=...)`): a bundled profile's name or its numbers."""

    def __init__(self, policy: Policy | None) -> None:
        self.policy = policy
        """The network; None builds observations only (`act` then writes no actions)."""
        self.n_envs = 0
        self._every_slot = np.arange(0)
        self.action_offset_rad = np.zeros(len(self.joint_names))
        """The session's action mapping: target = offset + scale * action."""
        self.action_scale = np.ones(len(self.joint_names))
        self.state: dict[str, np.ndarray] = {}
        """Per-slot state, arrays of shape (n_envs, ...), zeroed when an episode starts."""
        self.network_s: list[float] | None = None
        """Set to a list to time the network: each call's wall time is appended, in s
        (`thorarena bench ipc --clients twist2` compares it with the round trip)."""

    # --- what a subclass provides -------------------------------------------------------

    def slot_state(self) -> dict[str, tuple[int, ...]]:
        """Name and per-slot shape of each state array (zeros at reset; float64 unless
        `state_dtypes` says otherwise)."""
        return {}

    @abstractmethod
    def observe(self, records: np.ndarray, slots: np.ndarray) -> np.ndarray:
        """The network input, float32 `(len(slots), obs_dim)`, for the active `records` (in
        slot order, `slots` their slot indices); updates the per-slot state."""

    def actions_from_outputs(self, outputs: np.ndarray, records: np.ndarray) -> np.ndarray:
        """Raw actions in canonical joint order, `(len(records), n_joints)`, any float dtype
        (`act` casts them into the float64 batch), from the network's outputs. By default
        the outputs are the actions."""
        return np.asarray(outputs)

    # --- the shared machinery -----------------------------------------------------------

    def bind(
        self,
        *,
        n_envs: int,
        action_offset_rad: np.ndarray | Any,
        action_scale: np.ndarray | Any,
    ) -> None:
        """Sizes the per-slot state for `n_envs` slots (all zero) and takes the session's
        action mapping. `run` calls it; call it yourself to drive `act` without a session."""
        n = len(self.joint_names)
        offset = np.asarray(action_offset_rad, dtype=np.float64)
        scale = np.asarray(action_scale, dtype=np.float64)
        if offset.shape != (n,) or scale.shape != (n,):
            raise ValueError(f"the action mapping must have {n} entries per array")
        if np.any(scale == 0.0):
            raise ValueError("an action scale of 0 cannot be inverted")
        policy = self.policy
        if policy is not None and policy.input_dim not in (None, self.obs_dim):
            raise ValueError(
                f"{self.name}: the network takes {policy.input_dim} inputs, the adapter builds "
                f"{self.obs_dim}"
            )
        self.n_envs = n_envs
        self.action_offset_rad = offset
        self.action_scale = scale
        self._every_slot = np.arange(n_envs)
        self.state = {
            key: np.zeros((n_envs, *shape), dtype=self.state_dtypes.get(key, np.float64))
            for key, shape in self.slot_state().items()
        }

    def reset(self, slots: np.ndarray) -> None:
        """Starts new episodes in `slots`: their per-slot state goes back to zeros."""
        for array in self.state.values():
            array[slots] = 0.0

    def act(
        self,
        obs: np.ndarray,
        actions: np.ndarray,
        built: np.ndarray | None = None,
        *,
        all_active: bool = False,
    ) -> np.ndarray:
        """One control step: resets the slots whose episode starts (`step == 0` or
        `FLAG_RESET`), builds the observation of every active slot, runs the network on them
        in one batch and writes their raw actions into `actions`, zeros into every other row
        (so the session need not zero the block: `run` asks it not to). Returns the network
        input of the active slots.

        `built` is the network input of every slot as the simulator built it (the session's
        `policy_inputs`, shape (n_envs, obs_dim)): taken as it is instead of `observe`.
        `all_active`: the simulator counted every slot active (`Session.n_active ==
        n_envs`), so the slots' flags are not read."""
        if len(obs) != self.n_envs:
            raise ValueError(f"a batch of {len(obs)} slots, bound to {self.n_envs}: call bind()")
        flags = None if all_active else obs["flags"]
        slots = self._every_slot if flags is None else np.flatnonzero((flags & FLAG_ACTIVE) != 0)
        # All active (the usual case): the batch itself, no copy; else the active records.
        every = len(slots) == len(obs)
        if not every or self.policy is None:
            actions[...] = 0.0  # the rows no action is written into below
        if len(slots) == 0:
            return np.zeros((0, self.obs_dim), dtype=np.float32)
        records = obs if every else np.take(obs, slots)
        if built is not None:
            inputs = built if every else built[slots]
        else:
            starting = (records["step"] == 0) | ((records["flags"] & FLAG_RESET) != 0)
            if starting.any():
                self.reset(slots[starting])
            inputs = self.observe(records, slots)
        if self.policy is not None:
            if self.network_s is None:
                outputs = self.policy(inputs, steps=records["step"])
            else:
                started = time.perf_counter()
                outputs = self.policy(inputs, steps=records["step"])
                self.network_s.append(time.perf_counter() - started)
            raw = self.actions_from_outputs(outputs, records)
            if every:
                actions[...] = raw  # a slice copy (and cast): a third of an index array's cost
            else:
                actions[slots] = raw
        return inputs

    def connect(self, session: str, **kwargs: Any) -> Session:
        """Joins `session` with this adapter's name, joint order and reference offsets;
        `kwargs` go to `thorarena.connect` (`timeout_s`, `spin_us`, or `name` or
        `profile` to override;
        `input=None` to build the observation here rather than in the simulator)."""
        kwargs.setdefault("name", self.name)
        kwargs.setdefault("input", self.simulator_input)
        kwargs.setdefault("profile", self.profile)
        return connect(
            session,
            joint_names=self.joint_names,
            reference_offsets_s=self.reference_offsets_s,
            **kwargs,
        )

    def run(self, session: Session) -> int:
        """Answers every step of `session` until the simulator ends the run; returns the
        number of steps answered."""
        asked = tuple(session.info.reference_offsets_s)
        if not np.allclose(asked, self.reference_offsets_s, rtol=0.0, atol=1e-12):
            raise ValueError(
                f"{self.name} needs reference offsets {self.reference_offsets_s} s, the session "
                f"was joined with {asked}: use adapter.connect()"
            )
        self.bind(
            n_envs=session.n_envs,
            action_offset_rad=session.action_offset_rad,
            action_scale=session.action_scale,
        )
        built = session.layout.n_inputs > 0
        if built and session.layout.n_inputs != self.obs_dim:
            raise ValueError(
                f"{self.name}: the session's policy inputs are {session.layout.n_inputs} wide, "
                f"the network takes {self.obs_dim}"
            )
        n_envs = session.n_envs
        for obs, actions in session.steps(zero_actions=False):
            all_active = session.n_active == n_envs
            self.act(obs, actions, session.policy_inputs if built else None, all_active=all_active)
        return session.steps_answered


def canonical_indices(names: list[str] | tuple[str, ...]) -> np.ndarray:
    """For each joint name of a policy's order, its index in the canonical G1 order. Names
    match with or without the `_joint` suffix; a name the G1 does not have is an error."""
    index = {n: i for i, n in enumerate(G1_JOINT_NAMES)}
    index.update({n.removesuffix("_joint"): i for i, n in enumerate(G1_JOINT_NAMES)})
    missing = [n for n in names if n not in index]
    if missing:
        raise ValueError(f"joints not on the G1: {missing}")
    out = np.array([index[n] for n in names], dtype=np.intp)
    if len(set(out.tolist())) != len(out):
        raise ValueError(f"a joint appears twice in {list(names)}")
    return out
