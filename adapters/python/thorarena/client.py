"""The policy's end of a ThorArena session over iceoryx2 (`ipc/src/client.rs` in Python).

`connect` says hello and returns a `Session`; `Session.steps()` yields, per control step,
the observation batch as a read-only numpy structured array straight over the shared-memory
request and a writable float64 array straight over the loaned response. When the loop body
returns, the actions are sent and the simulator woken.

In iceoryx2 terms the policy is a *client* of the `hello` service and the *server* of the
`step` service (it answers the simulator's requests); it listens on `obs_ready` and
notifies `action_ready`.
"""

from __future__ import annotations

import ctypes
import os
import time
from collections import deque
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import iceoryx2 as iox2
import numpy as np

from .errors import (
    LayoutMismatch,
    NoSession,
    SessionRefused,
    SimulatorGone,
    ThorArenaError,
    Timeout,
    TransportError,
)
from .private_root import make_shm_files_private, private_root
from .protocol import (
    ACTION_HEADER_BYTES,
    BATCH_HEADER_WORDS,
    COMMAND_END,
    INPUT_NAME_BYTES,
    MAGIC,
    MAX_REFERENCE_OFFSETS,
    NAME_BYTES,
    PROTOCOL_VERSION,
    WORD_BYTES,
    ActionHeader,
    BatchHeader,
    Hello,
    Layout,
    Profile,
    Status,
    Welcome,
    declare_profile,
    from_fixed,
    joint_names_hash,
    to_fixed,
)

RECENT_TURNAROUNDS = 8
"""The simulator's turnarounds remembered to predict when the next batch is due."""
LIVENESS_EVERY_S = 0.002
"""While blocked on `obs_ready`, how often the simulator's liveness is checked."""
NODE_CHECK_EVERY_S = 0.010
"""How often the simulator's iceoryx2 node is looked up at most (a directory listing)."""


def process_alive(pid: int) -> bool:
    """True while process `pid` exists and is not a zombie; `0` means unknown (alive)."""
    if pid == 0:
        return True
    try:
        fd = os.open(f"/proc/{pid}/stat", os.O_RDONLY)
    except FileNotFoundError:
        return False
    except OSError:
        # No procfs: existence only.
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return False
        except PermissionError:
            return True
        return True
    try:
        stat = os.read(fd, 512)
    finally:
        os.close(fd)
    # The state is the first field after the parenthesised command name.
    fields = stat.rpartition(b")")[2].split()
    return not fields or fields[0] not in (b"Z", b"X")


class SimulatorWatch:
    """Whether the simulator lives, judged by its iceoryx2 node, as the simulator judges
    the policy: the kernel releases a node's lock when its process dies, in whatever pid
    namespace it ran. The pid in the welcome is only for logs — in another container it
    names no process here, or another one. Without the node (not found at connect), the
    pid is checked instead."""

    def __init__(self, step_service: Any, node_id: int | None, pid: int) -> None:
        self._step = step_service
        self._id = node_id
        self._pid = pid
        self._checked_at = 0.0
        self._alive = True

    @staticmethod
    def find(step_service: Any, session: str, own_id: int) -> int | None:
        """The id of the live simulator node attached to the step service (the node
        `thorarena-sim-<session>`, not ours), or None when there is not exactly one."""
        ids = []
        for state in step_service.nodes:
            if not isinstance(state, iox2.NodeState.Alive):
                continue
            view = state[0]
            if view.id.value != own_id and view.details.name.as_str() == (
                f"thorarena-sim-{session}"
            ):
                ids.append(view.id.value)
        return ids[0] if len(ids) == 1 else None

    def alive(self) -> bool:
        """True while the simulator lives (or its node cannot be read)."""
        if self._id is None:
            return process_alive(self._pid)
        now = time.perf_counter()
        if not self._alive or now - self._checked_at < NODE_CHECK_EVERY_S:
            return self._alive
        self._checked_at = now
        alive = False  # absent: it closed and removed its node
        try:
            states = self._step.nodes if self._step is not None else []
        except Exception:
            return True  # the listing failed: not a sign of death
        for state in states:
            inner = state[0]  # a node view, or the bare id of an unreadable node
            node_id = getattr(inner, "id", inner)
            if getattr(node_id, "value", None) == self._id:
                alive = not isinstance(state, iox2.NodeState.Dead)
                break
        self._alive = alive
        return alive

    def release(self) -> None:
        """Drops the service handle (before the node it was opened by)."""
        self._step = None


def _service_name(session: str, leaf: str) -> Any:
    ok = 0 < len(session) <= 64 and all(
        c.isascii() and (c.isalnum() or c in "_.-") for c in session
    )
    if not ok:
        raise ValueError(
            f"bad session name {session!r}: use 1 to 64 characters from [A-Za-z0-9_.-]"
        )
    return iox2.ServiceName.new(f"thorarena/{session}/{leaf}")


def _transport(what: str, error: BaseException) -> TransportError:
    return TransportError(f"{what}: {type(error).__name__}: {error}")


@dataclass(frozen=True, kw_only=True)
class SessionInfo:
    """The session as the simulator described it in its `Welcome`."""

    layout: Layout
    """Batch layout (environment slots, joints, reference frames)."""
    control_dt_s: float
    """Control period, s."""
    budget_s: float
    """Latency budget per step, s (0: none, lock-step)."""
    simulator_pid: int
    """The simulator's process id."""
    action_offset_rad: np.ndarray
    """target = action_offset_rad + action_scale * action, rad (read-only, n_joints)."""
    action_scale: np.ndarray
    """See `action_offset_rad`."""
    reference_offsets_s: tuple[float, ...]
    """Times ahead of each step of the reference frames, s (as asked)."""

    @classmethod
    def welcomed(
        cls,
        layout: Layout,
        *,
        control_dt_s: float,
        budget_s: float,
        simulator_pid: int,
        action_offset_rad: Any,
        action_scale: Any,
        reference_offsets_s: Sequence[float],
    ) -> SessionInfo:
        """The session a welcome describes, whichever transport read it: the action
        mapping's first `n_joints` values as read-only float64 arrays."""
        n = layout.n_joints

        def frozen(values: Any) -> np.ndarray:
            array = np.array(values[:n], dtype=np.float64)
            array.flags.writeable = False
            return array

        return cls(
            layout=layout,
            control_dt_s=control_dt_s,
            budget_s=budget_s,
            simulator_pid=simulator_pid,
            action_offset_rad=frozen(action_offset_rad),
            action_scale=frozen(action_scale),
            reference_offsets_s=tuple(float(o) for o in reference_offsets_s),
        )


class Session:
    """A connected policy: the session's shape, and `steps()`, the control loop. `connect`
    returns one of its two transports: `IceoryxSession` (iceoryx2's Python binding) or
    `native.NativeSession` (the C ABI of `thorarena-ipc` through ctypes)."""

    def __init__(self, *, info: SessionInfo) -> None:
        self.info = info
        self.steps_answered = 0
        """Control steps answered so far."""
        self.seq = 0
        """`seq` of the newest observation batch received."""
        self.ended = False
        """True once the simulator ended the run."""
        self.n_active = 0
        """Slots flagged `FLAG_ACTIVE` in the current batch, as the simulator counted them:
        when it is `n_envs`, every slot is active and their flags need not be read."""
        self.policy_inputs: np.ndarray | None = None
        """The current step's policy-input block, when the session carries one (`input=` of
        `connect`): read-only float32 `(n_envs, n_inputs)` over shared memory, valid in the
        body of the `steps()` loop only, like `obs`."""

    # The session's shape, as flat attributes.
    @property
    def layout(self) -> Layout:
        """Batch layout."""
        return self.info.layout

    @property
    def n_envs(self) -> int:
        """Environment slots per batch."""
        return self.info.layout.n_envs

    @property
    def n_joints(self) -> int:
        """Joints per environment."""
        return self.info.layout.n_joints

    @property
    def n_refs(self) -> int:
        """Reference frames per environment."""
        return self.info.layout.n_refs

    @property
    def control_dt_s(self) -> float:
        """Control period, s."""
        return self.info.control_dt_s

    @property
    def budget_s(self) -> float:
        """Latency budget per step, s (0: lock-step)."""
        return self.info.budget_s

    @property
    def action_offset_rad(self) -> np.ndarray:
        """target = action_offset_rad + action_scale * action, rad."""
        return self.info.action_offset_rad

    @property
    def action_scale(self) -> np.ndarray:
        """See `action_offset_rad`."""
        return self.info.action_scale

    @property
    def closed(self) -> bool:
        """True once the session is closed."""
        raise NotImplementedError

    def steps(
        self, *, timeout_s: float | None = None, zero_actions: bool = True
    ) -> Iterator[tuple[np.ndarray, np.ndarray]]:
        """Yields `(obs, actions)` for each control step until the run ends.

        `obs` is a read-only structured array of `n_envs` records (`Layout.env_dtype`) over
        the request in shared memory; `actions` a writable `(n_envs, n_joints)` float64 array
        over the loaned response, zeroed — or, with `zero_actions=False`, holding whatever
        an earlier step left in that memory: for a loop that writes every active slot's
        row itself (the simulator reads only the active slots'), which spares zeroing
        the block each step. Their contents belong to the current step only
        (the memory is reused for later steps): copy what you keep. The views keep the
        session's shared memory mapped; `close()` unmaps it, after which they must not be
        touched. Leaving the body sends the actions and wakes the simulator; leaving the
        loop early (`break`, an exception) sends nothing for that step.

        Ends when the simulator ends the run. Raises `SimulatorGone` when the simulator dies,
        `Timeout` when no step arrives within `timeout_s` (default: wait as long as the
        simulator lives).
        """
        raise NotImplementedError

    def close(self) -> None:
        """Leaves the session, unmapping its shared memory: views from `steps()` must not
        be used afterwards. Idempotent."""
        raise NotImplementedError

    def __enter__(self) -> Session:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class IceoryxSession(Session):
    """A session over iceoryx2's Python binding (no compiled code of ours needed)."""

    def __init__(
        self,
        *,
        info: SessionInfo,
        node: Any,
        server: Any,
        obs_ready: Any,
        action_ready: Any,
        spin_s: float,
        wake_early_s: float = 0.0,
        simulator: SimulatorWatch,
    ) -> None:
        super().__init__(info=info)
        self._simulator = simulator
        self._node = node
        self._server = server
        self._obs_ready = obs_ready
        self._action_ready = action_ready
        self._spin_s = spin_s
        self._wake_early_s = wake_early_s
        # The simulator's last turnarounds (answer sent → next batch here), s: between the
        # quickest and the slowest the next batch is due.
        self._turnarounds: deque[float] = deque(maxlen=RECENT_TURNAROUNDS)
        self._slice = iox2.Duration.from_secs_f64(LIVENESS_EVERY_S)

    @property
    def closed(self) -> bool:
        """True once the session's ports are released."""
        return self._server is None

    def steps(
        self, *, timeout_s: float | None = None, zero_actions: bool = True
    ) -> Iterator[tuple[np.ndarray, np.ndarray]]:
        """See `Session.steps`."""
        if self._server is None:
            raise ThorArenaError("the session is closed")
        if self.ended:
            return
        layout = self.info.layout
        words = layout.action_words
        obs_block = ctypes.c_uint8 * layout.obs_bytes
        action_block = ctypes.c_uint8 * layout.action_bytes
        header = ActionHeader(MAGIC, PROTOCOL_VERSION, layout.n_envs, layout.n_joints, 0, 0)
        shape = layout.batch_shape
        unpack_header = BATCH_HEADER_WORDS.unpack_from
        # Per shared-memory address (the few chunks of each side's static pool recur): the
        # chunk as a ctypes block and its views, a view being only a pointer, a shape and
        # a dtype. A batch's length is checked when its chunk is first seen; its header,
        # every step. Each Python operation counts here: the network just ran and left
        # the interpreter's own code and data cold in the caches.
        obs_views: dict[int, tuple[Any, np.ndarray, np.ndarray | None]] = {}
        action_views: dict[int, np.ndarray] = {}
        while True:
            request = self._next_request(timeout_s)
            response = None
            try:
                address = request.payload_ptr
                views = obs_views.get(address)
                if views is None:
                    views = obs_views[address] = self._obs_views(request, address, obs_block)
                block, obs, self.policy_inputs = views
                fields = unpack_header(block)
                if fields[0] != MAGIC or fields[3:8] != shape:
                    problem = layout.check_batch_header(BatchHeader.from_buffer(block))
                    raise LayoutMismatch(problem or "batch header of another layout")
                self.seq = fields[8]
                self.n_active = fields[9]
                if fields[2] == COMMAND_END:
                    self.ended = True
                    return
                try:
                    response = request.loan_slice_uninit(words)
                except Exception as e:  # iceoryx2 raises its own error types
                    raise _transport("loaning the action batch", e) from e
                address = response.payload_ptr
                if zero_actions:
                    ctypes.memset(address, 0, words * WORD_BYTES)
                header.seq = self.seq
                ctypes.memmove(address, ctypes.addressof(header), ACTION_HEADER_BYTES)
                actions = action_views.get(address)
                if actions is None:
                    block = action_block.from_address(address)
                    block.session = self  # type: ignore[attr-defined]  # keeps the mapping alive
                    actions = action_views[address] = layout.action_view(block)
                yield obs, actions
                del obs, actions
                self.policy_inputs = None
                ready = response.assume_init()
                response = None
                try:
                    ready.send()
                except Exception:
                    # A simulator that gave up on this step dropped it: nothing to deliver.
                    ready.delete()
                try:
                    self._action_ready.notify()
                except Exception as e:
                    raise _transport("notifying action_ready", e) from e
                self.steps_answered += 1
            finally:
                self.policy_inputs = None
                if response is not None:
                    response.delete()
                request.delete()
            if len(obs_views) + len(action_views) > 64:  # not a static pool after all
                obs_views.clear()
                action_views.clear()

    def _obs_views(
        self, request: Any, address: int, block_type: Any
    ) -> tuple[Any, np.ndarray, np.ndarray | None]:
        """The block and views of an observation chunk seen for the first time, after
        checking that the batch is as long as the session's layout."""
        layout = self.info.layout
        # `header.number_of_elements`, not `Slice.len()` (bytes, iceoryx2 issue #1533).
        got = request.header.number_of_elements * WORD_BYTES
        if got < layout.obs_bytes:
            raise LayoutMismatch(
                f"batch of {got} bytes, the session's layout needs {layout.obs_bytes}"
            )
        block = block_type.from_address(address)
        block.session = self  # keeps the mapping alive
        inputs = layout.inputs_view(block) if layout.n_inputs else None
        return block, layout.obs_view(block), inputs

    def _next_request(self, timeout_s: float | None) -> Any:
        """The newest observation batch (older ones are dropped unanswered)."""
        server = self._server
        simulator = self._simulator
        now = time.perf_counter()
        deadline = None if timeout_s is None else now + timeout_s
        spin_until = now + self._spin_s
        early = self._wake_early_s
        turnarounds = self._turnarounds
        due = None  # the window to poll through, where the next batch is due
        if early > 0.0 and turnarounds:
            due = (now + min(turnarounds) - early, now + max(turnarounds) + early)
        newest = None
        try:
            while not server.has_requests and time.perf_counter() < spin_until:
                pass
            while newest is None:
                while not server.has_requests:
                    t = time.perf_counter()
                    if due is not None and due[0] <= t < due[1]:
                        until = due[1] if deadline is None else min(due[1], deadline)
                        while not server.has_requests and time.perf_counter() < until:
                            pass
                        due = None
                        continue
                    if deadline is not None:
                        left = deadline - time.perf_counter()
                        if left <= 0:
                            raise Timeout(f"timed out after {timeout_s} s waiting for observations")
                        wait = iox2.Duration.from_secs_f64(min(left, LIVENESS_EVERY_S))
                    else:
                        wait = self._slice
                    if due is not None and t < due[0]:
                        # Sleep until the window: the listener's timed wait rounds its
                        # timeout up to scheduler ticks (8 ms for 1 ms at HZ=250), a
                        # sleep holds to the timer slack (≈ 50 µs). A batch earlier than
                        # the quickest recent turn waits for the window.
                        until = due[0] if deadline is None else min(due[0], deadline)
                        time.sleep(max(min(until - t, LIVENESS_EVERY_S), 0.0))
                        continue
                    woken = self._obs_ready.timed_wait(wait)
                    if not woken and not server.has_requests and not simulator.alive():
                        pid = self.info.simulator_pid
                        raise SimulatorGone(f"the simulator (pid {pid}) is gone")
                while (request := server.receive()) is not None:
                    if newest is not None:
                        newest.delete()
                    newest = request
            if self.steps_answered:  # not the wait for the first batch
                turnarounds.append(time.perf_counter() - now)
        except ThorArenaError:
            raise
        except Exception as e:
            raise _transport("receiving observations", e) from e
        return newest

    def close(self) -> None:
        """Releases the session's ports (ports before their node), unmapping its shared
        memory: views from `steps()` must not be used afterwards. Idempotent; without it the
        ports go when the session and every view of it are garbage."""
        for port in (self._server, self._obs_ready, self._action_ready):
            if port is not None:
                port.delete()
        self._server = self._obs_ready = self._action_ready = None
        self._simulator.release()
        self._node = None


def _create_node(session: str) -> Any:
    iox2.set_log_level_from_env_or(iox2.LogLevel.Error)
    root, prefix = private_root()
    config = iox2.config.global_config()
    config.global_cfg.root_path = iox2.Path.new(root)
    config.global_cfg.prefix = iox2.FileName.new(prefix)
    try:
        node = (
            iox2.NodeBuilder.new()
            .config(config)
            .name(iox2.NodeName.new(f"thorarena-policy-{session}"))
            # Python keeps its own signal handling (Ctrl-C raises KeyboardInterrupt).
            .signal_handling_mode(iox2.SignalHandlingMode.Disabled)
            .create(iox2.ServiceType.Ipc)
        )
    except Exception as e:
        raise _transport(
            f"creating the node (if no session of yours is running, remove "
            f"/dev/shm/{prefix}* and try again)",
            e,
        ) from e
    make_shm_files_private(prefix)
    node.try_cleanup_dead_nodes()
    return node


def connect(
    session: str,
    *,
    name: str,
    joint_names: Sequence[str],
    reference_offsets_s: Sequence[float] = (0.0,),
    timeout_s: float = 10.0,
    spin_us: float = 50.0,
    wake_early_us: float = 150.0,
    input: str | None = None,
    profile: str | Profile | None = None,
    protocol_version: int = PROTOCOL_VERSION,
    transport: str = "python",
) -> Session:
    """Joins `session`, waiting up to `timeout_s` for a simulator to serve it.

    `joint_names` is the joint order the policy assumes (checked against the robot's by
    hash); `reference_offsets_s` the times ahead of each step at which it wants reference
    frames; `spin_us` how long to busy-poll for each observation before blocking;
    `wake_early_us` how long before the next observation is due (the simulator's recent
    turnarounds) to stop blocking and busy-poll, until as long after (0: never); `input`
    a network input for the simulator to build into every batch (`"twist2"`), read as
    `Session.policy_inputs` (the simulator refuses a name it does not offer).
    `profile` the dynamics profile the policy was trained under: a bundled profile's
    name (`"wbc-mjlab"`; the built-in baselines' is `"default"`) or its numbers
    (`Profile(...)`). A run that names no profile (`--profile`) runs under the declared
    one; one that names another refuses the policy (unless `--profile-mismatch-ok`); with
    neither, the policy is refused (`SessionRefused`, status `PROFILE`).
    `protocol_version` is for tests that announce a wrong one on purpose.

    `transport`: `"python"` (default) runs the session over iceoryx2's Python binding;
    `"native"` over the C ABI of crate `thorarena-ipc` (`libthorarena_ipc.so`, see
    `thorarena.native`: fewer microseconds per step, with the Rust client's wait, whose
    wake-up is its own 150 µs — `wake_early_us` must be left at that); `"auto"` the
    library when `native.find_library()` finds one, else Python.

    Raises `NoSession`, `SessionRefused(status, message)`, `Timeout` or `TransportError`
    (`ThorArenaError` when `"native"` finds no library).
    """
    offsets = [float(o) for o in reference_offsets_s]
    if len(offsets) > MAX_REFERENCE_OFFSETS:
        raise SessionRefused(
            Status.REFERENCE_OFFSETS, f"at most {MAX_REFERENCE_OFFSETS} reference offsets"
        )
    input_name = (input or "").encode("utf-8")
    if len(input_name) >= INPUT_NAME_BYTES:
        raise SessionRefused(
            Status.INPUT, f"policy input name {input!r} is longer than {INPUT_NAME_BYTES - 1} bytes"
        )
    names = {
        leaf: _service_name(session, leaf)
        for leaf in ("hello", "step", "obs_ready", "action_ready")
    }
    if transport not in ("python", "native", "auto"):
        raise ValueError(f"transport {transport!r}: use 'python', 'native' or 'auto'")
    from . import native  # here: it builds on this module

    if transport == "native" or (transport == "auto" and native.find_library() is not None):
        if wake_early_us != native.WAKE_EARLY_US:
            raise ValueError(
                f"the native transport wakes {native.WAKE_EARLY_US} µs early, not {wake_early_us}"
            )
        return native.connect_native(
            session,
            name=name,
            joint_names=joint_names,
            reference_offsets_s=offsets,
            timeout_s=timeout_s,
            spin_us=spin_us,
            input=input,
            profile=profile,
            protocol_version=protocol_version,
        )
    hello = Hello(
        protocol_version=protocol_version,
        n_joints=len(joint_names),
        joint_names_hash=joint_names_hash(joint_names),
        pid=os.getpid(),
        n_refs=len(offsets),
    )
    hello.reference_offsets_s[: len(offsets)] = offsets
    ctypes.memmove(hello.name, to_fixed(name, NAME_BYTES), NAME_BYTES)
    ctypes.memmove(hello.input, to_fixed(input or "", INPUT_NAME_BYTES), INPUT_NAME_BYTES)
    try:
        declare_profile(hello, profile, len(joint_names))
    except ValueError as e:
        raise SessionRefused(Status.PROFILE, str(e)) from None
    node = _create_node(session)
    start = time.monotonic()
    while True:
        try:
            hello_service = (
                node.service_builder(names["hello"]).request_response(Hello, Welcome).open()
            )
            break
        except Exception:
            if time.monotonic() - start >= timeout_s:
                raise NoSession(session) from None
            time.sleep(0.005)
    try:
        step = (
            node.service_builder(names["step"])
            .request_response(iox2.Slice[ctypes.c_uint64], iox2.Slice[ctypes.c_uint64])
            .open()
        )
        obs_ready = (
            node.service_builder(names["obs_ready"]).event().open().listener_builder().create()
        )
        action_ready = (
            node.service_builder(names["action_ready"]).event().open().notifier_builder().create()
        )
    except Exception as e:
        raise NoSession(session) from e

    try:
        welcome = _say_hello(hello_service, step, session, hello, start, timeout_s)
    except SessionRefused:
        obs_ready.delete()
        action_ready.delete()
        raise
    if welcome.status != Status.OK:
        obs_ready.delete()
        action_ready.delete()
        raise SessionRefused(welcome.status, from_fixed(welcome.message))

    layout = Layout(
        n_envs=welcome.n_envs,
        n_joints=welcome.n_joints,
        n_refs=welcome.n_refs,
        n_inputs=welcome.n_inputs,
    )
    try:
        server = (
            step.server_builder()
            .initial_max_slice_len(layout.action_words)
            .allocation_strategy(iox2.AllocationStrategy.Static)
            .create()
        )
    except Exception as e:
        raise _transport("creating the step server", e) from e
    info = SessionInfo.welcomed(
        layout,
        control_dt_s=welcome.control_dt_s,
        budget_s=welcome.budget_s,
        simulator_pid=welcome.pid,
        action_offset_rad=welcome.action_offset_rad,
        action_scale=welcome.action_scale,
        reference_offsets_s=offsets,
    )
    return IceoryxSession(
        info=info,
        node=node,
        server=server,
        obs_ready=obs_ready,
        action_ready=action_ready,
        spin_s=spin_us * 1e-6,
        wake_early_s=wake_early_us * 1e-6,
        simulator=SimulatorWatch(
            step, SimulatorWatch.find(step, session, node.id.value), welcome.pid
        ),
    )


def _say_hello(
    hello_service: Any, step: Any, session: str, hello: Hello, start: float, timeout_s: float
) -> Welcome:
    """Sends `hello` and waits for the simulator's `Welcome` (a copy). Another policy that
    starts serving `step` meanwhile won a race for the session: this one is refused as busy
    at once, not left waiting for its whole timeout."""
    try:
        client = hello_service.client_builder().create()
        pending = client.send_copy(hello)
    except Exception as e:
        raise _transport("sending hello", e) from e
    try:
        while True:
            response = pending.receive()
            if response is not None:
                welcome = Welcome.from_buffer_copy(
                    (ctypes.c_uint8 * ctypes.sizeof(Welcome)).from_address(response.payload_ptr)
                )
                response.delete()
                return welcome
            if time.monotonic() - start > timeout_s:
                raise Timeout(f"timed out after {timeout_s} s waiting for the simulator's welcome")
            if step.dynamic_config.number_of_servers > 0:
                raise SessionRefused(
                    Status.BUSY,
                    f"session {session!r} is in use: another policy is connected "
                    "(a session serves one policy at a time)",
                )
            time.sleep(0.0002)
    finally:
        pending.delete()
        client.delete()
