"""This user's iceoryx2 directory and file prefix, checked as the simulator checks them
(`ipc/src/session/private_root.rs`), so that another local user can neither read a
session's shared memory nor stop or block its processes."""

from __future__ import annotations

import contextlib
import fcntl
import os
import secrets
import stat as stat_module
import warnings
from collections.abc import Callable

from .errors import PrivateRootError

ROOT_ENV = "THORARENA_IPC_ROOT"
"""Overrides this user's iceoryx2 root directory (as for the simulator)."""

TOKEN_FILE = "session-token"
"""The file in the root holding this user's token (as for the simulator)."""

_TOKEN_LOCK = ".session-token.lock"
_TOKEN_DIGITS = 16


def private_root() -> tuple[str, str]:
    """This user's iceoryx2 root directory and file prefix, the same as the simulator's
    (`ipc/src/session/private_root.rs`): `$THORARENA_IPC_ROOT`, else
    `/tmp/thorarena-iceoryx2-<uid>`, made 0700 when missing and refused when it is a
    link, not a directory, another user's or writable by others; files
    `iox2_ta<uid>_<token>_*`, the token the root's (made when missing, replaced while
    another user's file carries its prefix: such a file is stepped around, never opened)."""
    uid = os.geteuid()
    root = os.environ.get(ROOT_ENV) or f"/tmp/thorarena-iceoryx2-{uid}"

    def refuse(path: str, problem: str) -> PrivateRootError:
        return PrivateRootError(f"iceoryx2 files: {path}: {problem}")

    if not os.path.isabs(root):
        raise refuse(root, f"{ROOT_ENV} must be an absolute path")
    with contextlib.suppress(FileExistsError):
        os.mkdir(root, 0o700)
    st = os.lstat(root)
    if stat_module.S_ISLNK(st.st_mode):
        raise refuse(
            root,
            "it is a symbolic link (it could lead into another user's directory): remove it",
        )
    if not stat_module.S_ISDIR(st.st_mode):
        raise refuse(root, "it is not a directory: remove it")
    if st.st_uid != uid:
        raise refuse(
            root,
            f"it belongs to uid {st.st_uid}, not to you (uid {uid}): another user made it; "
            f"remove it, or set {ROOT_ENV} to a directory of yours",
        )
    if st.st_mode & 0o022:
        raise refuse(root, f"others may write to it (mode {st.st_mode & 0o7777:o}): `chmod 700` it")
    return root, _current_prefix(root, uid, refuse)


def _prefix_of(uid: int, token: str) -> str:
    return f"iox2_ta{uid}_{token}_" if token else f"iox2_ta{uid}_"


def _read_token(root: str, uid: int) -> str | None:
    path = os.path.join(root, TOKEN_FILE)
    try:
        st = os.lstat(path)
        if not stat_module.S_ISREG(st.st_mode) or st.st_uid != uid or st.st_size > 64:
            return None
        with open(path, encoding="ascii") as f:
            token = f.read().strip()
    except (OSError, UnicodeDecodeError):
        return None
    valid = len(token) == _TOKEN_DIGITS and all(c in "0123456789abcdefABCDEF" for c in token)
    return token if valid else None


def _write_token(root: str, token: str) -> None:
    tmp = os.path.join(root, f".{TOKEN_FILE}.{os.getpid()}")
    with contextlib.suppress(FileNotFoundError):
        os.unlink(tmp)
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o600)
    with os.fdopen(fd, "w", encoding="ascii") as f:
        f.write(token)
    os.replace(tmp, os.path.join(root, TOKEN_FILE))


def _current_prefix(root: str, uid: int, refuse: Callable[[str, str], PrivateRootError]) -> str:
    """The prefix of this user's token, under the root's lock: made when missing, replaced
    while another user's file carries it (as the simulator does)."""
    lock_fd = os.open(
        os.path.join(root, _TOKEN_LOCK), os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW, 0o600
    )
    try:
        fcntl.flock(lock_fd, fcntl.LOCK_EX)
        token = _read_token(root, uid)
        if token is None:
            token = secrets.token_hex(_TOKEN_DIGITS // 2)
            _write_token(root, token)
        planted: list[str] = []
        for _ in range(4):
            foreign = [p for p, st in _own_shm_files(_prefix_of(uid, token)) if st.st_uid != uid]
            if not foreign:
                if planted:
                    warnings.warn(
                        f"iceoryx2 files: another user planted {', '.join(planted)} with your "
                        "session files' prefix; your sessions now use a new one",
                        stacklevel=3,
                    )
                return _prefix_of(uid, token)
            planted.extend(foreign)
            token = secrets.token_hex(_TOKEN_DIGITS // 2)
            _write_token(root, token)
        raise refuse(
            planted[0],
            "files with your session files' prefix keep appearing, owned by another user, "
            "as fast as the prefix changes; ask an administrator to see who plants them",
        )
    finally:
        os.close(lock_fd)


def _own_shm_files(prefix: str) -> list[tuple[str, os.stat_result]]:
    try:
        names = os.listdir("/dev/shm")
    except OSError:
        return []
    found = []
    for name in names:
        if name.startswith(prefix):
            path = os.path.join("/dev/shm", name)
            with contextlib.suppress(OSError):
                found.append((path, os.lstat(path)))
    return found


def make_shm_files_private(prefix: str) -> None:
    """iceoryx2 makes its management segment world-writable: this user's only."""
    uid = os.geteuid()
    for path, st in _own_shm_files(prefix):
        if st.st_uid == uid and stat_module.S_ISREG(st.st_mode) and st.st_mode & 0o077:
            with contextlib.suppress(OSError):
                os.chmod(path, 0o600)
