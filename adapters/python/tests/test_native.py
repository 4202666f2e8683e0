"""The C ABI transport without a simulator: its ctypes mirrors are the header's structs
field by field, the library is found and refused as documented, and a missing session or
a bad argument reads as with the Python transport. Sessions against a real simulator over
this transport are tested from Rust (`ipc/tests/python_client.rs`, `*_over_the_c_abi_*`).
"""

from __future__ import annotations

import ctypes
import os
import re
from pathlib import Path

import pytest

import thorarena as ta
from thorarena import native

HEADER = Path(__file__).resolve().parents[3] / "ipc/include/thorarena.h"

C_TYPES = {
    "const char *": ctypes.c_char_p,
    "const char *const *": ctypes.POINTER(ctypes.c_char_p),
    "const double *": ctypes.POINTER(ctypes.c_double),
    "const struct ThorarenaProfile *": ctypes.POINTER(native.NativeProfile),
    "size_t": ctypes.c_size_t,
    "uint64_t": ctypes.c_uint64,
    "uint32_t": ctypes.c_uint32,
    "double": ctypes.c_double,
}


def header_struct(name: str) -> list[tuple[str, str]]:
    """`(C type, field name)` of `typedef struct NAME { ... } NAME;` in the C header."""
    text = HEADER.read_text()
    body = re.search(r"typedef struct " + name + r" \{(.*?)\} " + name + ";", text, re.S)
    assert body, f"{name} not in {HEADER}"
    code = re.sub(r"/\*.*?\*/", "", body.group(1), flags=re.S)
    fields = []
    for line in code.splitlines():
        m = re.fullmatch(r"\s*(.+?)\s*(\w+);\s*", line)
        if m:
            fields.append((m.group(1), m.group(2)))
    return fields


@pytest.mark.parametrize(
    ("mirror", "c_name"),
    [
        (native.ConnectOptions, "ThorarenaConnectOptions"),
        (native.SessionDescription, "ThorarenaSessionInfo"),
        (native.NativeProfile, "ThorarenaProfile"),
    ],
)
def test_ctypes_mirrors_are_the_headers_structs(mirror: type, c_name: str) -> None:
    want = [(n, C_TYPES[t]) for t, n in header_struct(c_name)]
    got = [(n, t) for n, t in mirror._fields_]  # type: ignore[attr-defined]
    assert got == want


def test_the_environment_variable_names_the_library(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv(native.LIBRARY_ENV, "/nonexistent/libthorarena_ipc.so")
    assert native.find_library() == Path("/nonexistent/libthorarena_ipc.so")
    with pytest.raises(
        ta.ThorArenaError, match=re.escape("loading /nonexistent/libthorarena_ipc.so")
    ):
        native.load_library()


def test_asking_for_the_native_transport_without_a_library_says_how_to_build_it(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.delenv(native.LIBRARY_ENV, raising=False)
    monkeypatch.setattr(native, "find_library", lambda: None)
    with pytest.raises(ta.ThorArenaError, match="cargo build --release -p thorarena-ipc"):
        ta.connect("s", name="p", joint_names=ta.G1_JOINT_NAMES, transport="native")


def test_an_unknown_transport_or_another_wake_up_is_refused() -> None:
    with pytest.raises(ValueError, match="transport 'zmq'"):
        ta.connect("s", name="p", joint_names=ta.G1_JOINT_NAMES, transport="zmq")
    with pytest.raises(ValueError, match=re.escape("wakes 150.0 µs early")):
        ta.connect(
            "s", name="p", joint_names=ta.G1_JOINT_NAMES, transport="native", wake_early_us=10
        )


def library_or_skip() -> Path:
    """The library cargo built in this checkout (`./test.sh` builds it before pytest)."""
    lib = native.find_library()
    if lib is None or not lib.is_file():
        pytest.skip(
            "no libthorarena_ipc.so in target/release or target/release/deps (cargo build "
            "--release -p thorarena-ipc, or set THORARENA_IPC_LIB)"
        )
    return lib


def test_the_library_speaks_this_packages_protocol() -> None:
    lib = native.load_library(library_or_skip())
    assert lib.thorarena_protocol_version() == ta.PROTOCOL_VERSION


def test_a_missing_session_is_no_session_over_the_c_abi_too() -> None:
    library_or_skip()
    session = f"pytest-native-nobody-{os.getpid()}"
    with pytest.raises(ta.NoSession) as e:
        ta.connect(
            session, name="p", joint_names=ta.G1_JOINT_NAMES, timeout_s=0.05, transport="native"
        )
    assert e.value.session == session


def test_a_refusal_reads_the_simulators_words_as_over_python() -> None:
    reported = "thorarena_connect: session refused (JointCount): 23 joints but the robot has 29"
    assert native._simulators_message(reported) == "23 joints but the robot has 29"
    assert native._simulators_message("something else: (x)") == "something else: (x)"
