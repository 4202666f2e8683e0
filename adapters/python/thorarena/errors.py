"""The errors of this package: what went wrong joining or running a session."""

from __future__ import annotations

import contextlib

from .protocol import Status


class ThorArenaError(Exception):
    """Base of every error of this package."""


class NoSession(ThorArenaError):
    """No ThorArena run serves the session."""

    def __init__(self, session: str) -> None:
        super().__init__(
            f"no ThorArena run serves session {session!r} (start `thorarena eval --policy "
            f"ipc:{session}` or `thorarena serve --session {session}` first)"
        )
        self.session = session


class SessionRefused(ThorArenaError):
    """The simulator refused the handshake; `status` says why as a code, `message` in words."""

    def __init__(self, status: Status | int, message: str) -> None:
        with contextlib.suppress(ValueError):
            status = Status(status)
        name = status.name if isinstance(status, Status) else str(status)
        super().__init__(f"session refused ({name}): {message}")
        self.status = status
        self.message = message


class SimulatorGone(ThorArenaError):
    """The simulator's process died or left the session."""


class Timeout(ThorArenaError):
    """Nothing arrived within the timeout."""


class LayoutMismatch(ThorArenaError):
    """A received batch does not match the session's layout."""


class TransportError(ThorArenaError):
    """iceoryx2 failed; the message names the operation and carries its error."""


class PrivateRootError(ThorArenaError):
    """This user's iceoryx2 directory, or a file in /dev/shm with this user's prefix,
    cannot be trusted; the message names it and says what to do."""
