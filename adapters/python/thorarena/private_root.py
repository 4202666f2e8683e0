"""This user's iceoryx2 directory and file prefix, checked as the simulator checks them
(`ipc/src/session/private_root.rs`), so that another local user can neither read a
session's shared memory nor stop its processes."""

from __future__ import annotations

import contextlib
import os
import stat as stat_module

from .errors import PrivateRootError

ROOT_ENV = "THORARENA_IPC_ROOT"
"""Overrides this user's iceoryx2 root directory (as for the simulator)."""


def private_root() -> tuple[str, str]:
    """This user's iceoryx2 root directory and file prefix, the same as the simulator's
    (`ipc/src/session/private_root.rs`): `$THORARENA_IPC_ROOT`, else
    `/tmp/thorarena-iceoryx2-<uid>`, made 0700 when missing and refused when it is a
    link, not a directory, another user's or writable by others; files `iox2_ta<uid>_*`,
    none of them another user's."""
    uid = os.geteuid()
    root = os.environ.get(ROOT_ENV) or f"/tmp/thorarena-iceoryx2-{uid}"
    prefix = f"iox2_ta{uid}_"

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
    for path, st in _own_shm_files(prefix):
        if st.st_uid != uid:
            raise refuse(
                path,
                f"it carries your session files' prefix but belongs to uid {st.st_uid}: "
                "another user planted it; remove it (as root, or ask its owner)",
            )
    return root, prefix


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
