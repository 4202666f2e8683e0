"""The policy's end of a session through the C ABI of crate `thorarena-ipc`
(`libthorarena_ipc.so`, `ipc/include/thorarena.h`), loaded with ctypes.

Why a second transport: after the network call the interpreter's own code and data are
cold in the caches, and each of the dozen iceoryx2 binding calls and the Python wait logic
of `client.IceoryxSession` costs microseconds there (docs/performance.md, "Measured").
Here a step is two foreign calls — `thorarena_next_step` (wait as the Rust client waits,
receive, check the header, loan and zero the answer) and `thorarena_send` (send, notify) —
and the views over shared memory are the same numpy arrays as the pure-Python session's.

The library is not part of the Python package: build it with `cargo build --release -p
thorarena-ipc` and point `THORARENA_IPC_LIB` at it, or install the package from a checkout
where `target/release` holds it (`find_library`).
"""

from __future__ import annotations

import ctypes
import os
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .client import Session, SessionInfo
from .errors import (
    LayoutMismatch,
    NoSession,
    SessionRefused,
    SimulatorGone,
    ThorArenaError,
    Timeout,
    TransportError,
)
from .protocol import BATCH_HEADER_WORDS, PROTOCOL_VERSION, Layout, Profile, Status

LIBRARY_ENV = "THORARENA_IPC_LIB"
"""Environment variable naming the shared library (a path to `libthorarena_ipc.so`)."""
LIBRARY_FILE = "libthorarena_ipc.so"

# `ThorarenaStatus` values (`ipc/src/ffi/status.rs`); 1 to 8 are the handshake's refusals,
# the same numbers as `protocol.Status`.
_OK = 0
_LAST_REFUSAL = 8
_END = 10
_TIMEOUT = 11
_NO_SESSION = 20
_SESSION_NAME = 21
_SIMULATOR_GONE = 24
_LAYOUT = 25
_WAIT_FOREVER = -1
WAKE_EARLY_US = 150.0
"""How long before the next batch is due the library's wait stops blocking, µs
(`WaitPolicy::default().wake_early`; not an option of the C ABI)."""


class NativeProfile(ctypes.Structure):
    """`ThorarenaProfile`: a dynamics profile by its numbers."""

    _fields_ = [
        ("name", ctypes.c_char_p),
        ("control_dt_s", ctypes.c_double),
        ("physics_dt_s", ctypes.c_double),
        ("action_delay_steps", ctypes.c_uint32),
        ("action_clip", ctypes.c_double),
        ("kp", ctypes.POINTER(ctypes.c_double)),
        ("kd", ctypes.POINTER(ctypes.c_double)),
        ("action_scale", ctypes.POINTER(ctypes.c_double)),
        ("action_offset_rad", ctypes.POINTER(ctypes.c_double)),
    ]


class ConnectOptions(ctypes.Structure):
    """`ThorarenaConnectOptions`."""

    _fields_ = [
        ("session", ctypes.c_char_p),
        ("policy_name", ctypes.c_char_p),
        ("joint_names", ctypes.POINTER(ctypes.c_char_p)),
        ("n_joints", ctypes.c_size_t),
        ("reference_offsets_s", ctypes.POINTER(ctypes.c_double)),
        ("n_reference_offsets", ctypes.c_size_t),
        ("timeout_ms", ctypes.c_uint64),
        ("spin_us", ctypes.c_uint64),
        ("liveness_us", ctypes.c_uint64),
        ("protocol_version", ctypes.c_uint32),
        ("input", ctypes.c_char_p),
        ("profile_name", ctypes.c_char_p),
        ("profile", ctypes.POINTER(NativeProfile)),
    ]


class SessionDescription(ctypes.Structure):
    """`ThorarenaSessionInfo`."""

    _fields_ = [
        ("n_envs", ctypes.c_size_t),
        ("n_joints", ctypes.c_size_t),
        ("n_refs", ctypes.c_size_t),
        ("control_dt_s", ctypes.c_double),
        ("budget_s", ctypes.c_double),
        ("simulator_pid", ctypes.c_uint32),
        ("obs_bytes", ctypes.c_size_t),
        ("action_bytes", ctypes.c_size_t),
        ("env_stride", ctypes.c_size_t),
        ("ref_offset", ctypes.c_size_t),
        ("ref_stride", ctypes.c_size_t),
        ("n_inputs", ctypes.c_size_t),
        ("inputs_offset", ctypes.c_size_t),
        ("action_offset_rad", ctypes.POINTER(ctypes.c_double)),
        ("action_scale", ctypes.POINTER(ctypes.c_double)),
    ]


def find_library() -> Path | None:
    """The library to load: `$THORARENA_IPC_LIB` when set (whether or not it exists, so
    a wrong path is reported, not passed over), else the one cargo built in the checkout
    this package lives in (`target/release`, then `target/release/deps`), else None."""
    named = os.environ.get(LIBRARY_ENV)
    if named:
        return Path(named)
    root = Path(__file__).resolve().parents[3]
    for candidate in (root / "target/release", root / "target/release/deps"):
        if (candidate / LIBRARY_FILE).is_file():
            return candidate / LIBRARY_FILE
    return None


_loaded: dict[Path, ctypes.CDLL] = {}


def load_library(path: str | os.PathLike[str] | None = None) -> ctypes.CDLL:
    """The C ABI at `path` (default: `find_library()`), with every signature declared;
    raises `ThorArenaError` saying how to build it when there is none."""
    where = Path(path) if path is not None else find_library()
    if where is None:
        raise ThorArenaError(
            f"no {LIBRARY_FILE}: build it with `cargo build --release -p thorarena-ipc` "
            f"and set {LIBRARY_ENV} to its path (or use transport='python')"
        )
    lib = _loaded.get(where)
    if lib is not None:
        return lib
    try:
        lib = ctypes.CDLL(str(where))
    except OSError as e:
        raise ThorArenaError(f"loading {where}: {e}") from e
    c = ctypes
    status = c.c_int
    client = c.c_void_p
    signatures: dict[str, tuple[list[Any], Any]] = {
        "thorarena_connect_options_default": ([c.POINTER(ConnectOptions)], status),
        "thorarena_connect": ([c.POINTER(ConnectOptions), c.POINTER(client)], status),
        "thorarena_session_info": ([client, c.POINTER(SessionDescription)], status),
        "thorarena_next_step": (
            [client, c.c_int64, c.POINTER(c.c_void_p), c.POINTER(c.c_void_p)],
            status,
        ),
        "thorarena_send": ([client], status),
        "thorarena_close": ([client], None),
        "thorarena_last_error_message": ([], c.c_char_p),
        "thorarena_status_name": ([c.c_int], c.c_char_p),
        "thorarena_protocol_version": ([], c.c_uint32),
    }
    for name, (argtypes, restype) in signatures.items():
        function = getattr(lib, name)
        function.argtypes = argtypes
        function.restype = restype
    if lib.thorarena_protocol_version() != PROTOCOL_VERSION:
        raise ThorArenaError(
            f"{where} speaks protocol {lib.thorarena_protocol_version()}, this package "
            f"{PROTOCOL_VERSION}: rebuild it from the same checkout"
        )
    _loaded[where] = lib
    return lib


def _message(lib: ctypes.CDLL, status: int) -> str:
    """`STATUS_NAME: last error message` of the calling thread."""
    name = (lib.thorarena_status_name(status) or b"?").decode()
    detail = (lib.thorarena_last_error_message() or b"").decode("utf-8", "replace")
    return f"{name}: {detail}" if detail else name


class NativeSession(Session):
    """A connected policy served by the C ABI; `steps()` as `Session.steps()`.

    Differences from the pure-Python session: the answer is always zeroed
    (`zero_actions` is ignored: the library zeroes it, ≈ 1 µs for 64 slots); the wait is
    the Rust client's (`WaitPolicy`: spin, then block with a wake-up 150 µs before the
    next batch is due); a loop left early holds its step, so the session can then only
    be closed. Use it on the thread that connected (the library refuses others)."""

    def __init__(self, *, info: SessionInfo, lib: ctypes.CDLL, client: ctypes.c_void_p) -> None:
        super().__init__(info=info)
        self._lib = lib
        self._client: ctypes.c_void_p | None = client
        self._holding = False

    @property
    def closed(self) -> bool:
        """True once the client is freed."""
        return self._client is None

    def steps(
        self, *, timeout_s: float | None = None, zero_actions: bool = True
    ) -> Iterator[tuple[np.ndarray, np.ndarray]]:
        """See `Session.steps`."""
        del zero_actions  # the library zeroes the answer
        if self._client is None:
            raise ThorArenaError("the session is closed")
        if self._holding:
            raise ThorArenaError(
                "an earlier steps() loop was left without answering its step: close the session"
            )
        if self.ended:
            return
        lib, client = self._lib, self._client
        next_step, send = lib.thorarena_next_step, lib.thorarena_send
        timeout_us = _WAIT_FOREVER if timeout_s is None else max(int(timeout_s * 1e6), 0)
        obs_at, actions_at = ctypes.c_void_p(), ctypes.c_void_p()
        obs_out, actions_out = ctypes.byref(obs_at), ctypes.byref(actions_at)
        unpack_header = BATCH_HEADER_WORDS.unpack_from
        # Per pair of shared-memory addresses (a few chunks recur): the observation block
        # and the views over both.
        views: dict[tuple[int | None, int | None], tuple[Any, np.ndarray, Any, np.ndarray]] = {}
        while True:
            status = next_step(client, timeout_us, obs_out, actions_out)
            if status != _OK:
                if status == _END:
                    self.ended = True
                    return
                raise self._error(status, timeout_s)
            self._holding = True
            key = (obs_at.value, actions_at.value)
            chunk = views.get(key)
            if chunk is None:
                if len(views) > 64:  # not a static pool after all
                    views.clear()
                chunk = views[key] = self._views(key)
            block, obs, inputs, actions = chunk
            fields = unpack_header(block)
            self.seq = fields[8]
            self.n_active = fields[9]
            self.policy_inputs = inputs
            yield obs, actions
            self.policy_inputs = None
            status = send(client)
            if status != _OK:
                raise TransportError(f"sending the actions: {_message(lib, status)}")
            self._holding = False
            self.steps_answered += 1

    def _views(
        self, key: tuple[int | None, int | None]
    ) -> tuple[Any, np.ndarray, np.ndarray | None, np.ndarray]:
        """The observation block and the views over a chunk pair seen for the first time."""
        layout = self.info.layout
        obs_at, actions_at = key
        if not obs_at or not actions_at:
            raise TransportError("thorarena_next_step returned OK without its pointers")
        block = (ctypes.c_uint8 * layout.obs_bytes).from_address(obs_at)
        block.session = self  # type: ignore[attr-defined]  # keeps the mapping alive
        slots = (ctypes.c_double * (layout.n_envs * layout.n_joints)).from_address(actions_at)
        slots.session = self  # type: ignore[attr-defined]
        actions = np.ctypeslib.as_array(slots).reshape(layout.n_envs, layout.n_joints)
        inputs = layout.inputs_view(block) if layout.n_inputs else None
        return block, layout.obs_view(block), inputs, actions

    def _error(self, status: int, timeout_s: float | None) -> ThorArenaError:
        if status == _TIMEOUT:
            return Timeout(f"timed out after {timeout_s} s waiting for observations")
        if status == _SIMULATOR_GONE:
            return SimulatorGone(f"the simulator (pid {self.info.simulator_pid}) is gone")
        message = _message(self._lib, status)
        if status == _LAYOUT:
            return LayoutMismatch(message)
        return TransportError(f"waiting for observations: {message}")

    def close(self) -> None:
        """Leaves the session and frees the client (a step still held is dropped
        unanswered); views from `steps()` must not be used afterwards. Idempotent."""
        if self._client is not None:
            self._lib.thorarena_close(self._client)
            self._client = None

    def __del__(self) -> None:
        self.close()


def _simulators_message(detail: str) -> str:
    """The simulator's own words in a refusal the library reports as
    `thorarena_connect: session refused (Status): MESSAGE`, so `SessionRefused` reads the
    same over either transport; `detail` whole when it is not in that form."""
    marker = "session refused ("
    start = detail.find(marker)
    if start < 0:
        return detail
    end = detail.find("): ", start + len(marker))
    return detail if end < 0 else detail[end + 3 :]


def connect_native(
    session: str,
    *,
    name: str,
    joint_names: Sequence[str],
    reference_offsets_s: Sequence[float],
    timeout_s: float,
    spin_us: float,
    input: str | None,
    protocol_version: int,
    profile: str | Profile | None = None,
    library: str | os.PathLike[str] | None = None,
) -> NativeSession:
    """`thorarena.connect` through the C ABI (its arguments, checked there already)."""
    lib = load_library(library)
    options = ConnectOptions()
    lib.thorarena_connect_options_default(ctypes.byref(options))
    names = (ctypes.c_char_p * len(joint_names))(*[n.encode() for n in joint_names])
    offsets = (ctypes.c_double * len(reference_offsets_s))(*reference_offsets_s)
    options.session = session.encode()
    options.policy_name = name.encode()
    options.joint_names = names
    options.n_joints = len(joint_names)
    options.reference_offsets_s = offsets
    options.n_reference_offsets = len(offsets)
    options.timeout_ms = max(round(timeout_s * 1e3), 0)
    options.spin_us = max(round(spin_us), 0)
    options.protocol_version = protocol_version
    options.input = (input or "").encode()
    # The arrays stay alive (locals) until the call returns; the library copies them.
    if isinstance(profile, str):
        options.profile_name = profile.encode()
    elif profile is not None:
        arrays = {}
        for field in ("kp", "kd", "action_scale", "action_offset_rad"):
            values = [float(v) for v in getattr(profile, field)]
            if len(values) != len(joint_names):
                raise SessionRefused(
                    Status.PROFILE,
                    f"profile {profile.name!r}: {field} has {len(values)} values for "
                    f"{len(joint_names)} joints",
                )
            arrays[field] = (ctypes.c_double * len(values))(*values)
        native_profile = NativeProfile(
            name=profile.name.encode(),
            control_dt_s=float(profile.control_dt_s),
            physics_dt_s=float(profile.physics_dt_s),
            action_delay_steps=int(profile.action_delay_steps),
            action_clip=float(profile.action_clip or 0.0),
            **arrays,
        )
        options.profile = ctypes.pointer(native_profile)
    client = ctypes.c_void_p()
    status = lib.thorarena_connect(ctypes.byref(options), ctypes.byref(client))
    if status != _OK:
        detail = (lib.thorarena_last_error_message() or b"").decode("utf-8", "replace")
        if status <= _LAST_REFUSAL:
            raise SessionRefused(status, _simulators_message(detail))
        if status == _NO_SESSION:
            raise NoSession(session)
        if status == _TIMEOUT:
            raise Timeout(f"timed out after {timeout_s} s waiting for the simulator's welcome")
        if status == _SESSION_NAME:
            raise ValueError(f"bad session name {session!r}: {detail}")
        raise TransportError(f"connecting: {_message(lib, status)}")
    described = SessionDescription()
    lib.thorarena_session_info(client, ctypes.byref(described))
    layout = Layout(
        n_envs=described.n_envs,
        n_joints=described.n_joints,
        n_refs=described.n_refs,
        n_inputs=described.n_inputs,
    )
    if (described.obs_bytes, described.inputs_offset) != (layout.obs_bytes, layout.inputs_offset):
        lib.thorarena_close(client)
        raise LayoutMismatch(
            f"the library lays out a batch of {described.obs_bytes} bytes (inputs at "
            f"{described.inputs_offset}), this package {layout.obs_bytes} (at "
            f"{layout.inputs_offset}): rebuild it from the same checkout"
        )
    info = SessionInfo.welcomed(
        layout,
        control_dt_s=described.control_dt_s,
        budget_s=described.budget_s,
        simulator_pid=described.simulator_pid,
        action_offset_rad=described.action_offset_rad,
        action_scale=described.action_scale,
        reference_offsets_s=reference_offsets_s,
    )
    return NativeSession(info=info, lib=lib, client=client)
