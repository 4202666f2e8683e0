"""What the policy's end does without a simulator: a missing session is `NoSession` after the
timeout, bad session names are refused before touching iceoryx2, errors read well, and the
liveness check tells a live process from a dead one. Sessions against a real simulator are
tested from Rust: `ipc/tests/python_client.rs`."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

import thorarena as ta
from thorarena.protocol import Status


def test_connecting_to_a_missing_session_says_so() -> None:
    session = f"pytest-nobody-{os.getpid()}"
    with pytest.raises(ta.NoSession) as e:
        ta.connect(session, name="p", joint_names=ta.G1_JOINT_NAMES, timeout_s=0.05)
    assert session in str(e.value)
    assert e.value.session == session


@pytest.mark.parametrize("session", ["", "a/b", "x" * 65, "naïve", "with space"])
def test_bad_session_names_are_refused(session: str) -> None:
    with pytest.raises(ValueError, match="bad session name"):
        ta.connect(session, name="p", joint_names=ta.G1_JOINT_NAMES, timeout_s=0.01)


def test_too_many_reference_offsets_are_refused_locally() -> None:
    with pytest.raises(ta.SessionRefused) as e:
        ta.connect("s", name="p", joint_names=ta.G1_JOINT_NAMES, reference_offsets_s=[0.0] * 65)
    assert e.value.status == Status.REFERENCE_OFFSETS


def test_a_refusal_names_its_status_and_message() -> None:
    e = ta.SessionRefused(2, "23 joints but the robot has 29")
    assert e.status is Status.JOINT_COUNT
    assert e.message == "23 joints but the robot has 29"
    assert str(e) == "session refused (JOINT_COUNT): 23 joints but the robot has 29"
    assert str(ta.SessionRefused(99, "?")) == "session refused (99): ?"
    assert isinstance(e, ta.ThorArenaError)


def test_liveness_tells_live_from_dead_processes() -> None:
    assert ta.process_alive(os.getpid())
    assert ta.process_alive(0), "0 means unknown: alive"
    child = subprocess.Popen([sys.executable, "-c", "pass"])
    child.wait()
    assert not ta.process_alive(child.pid)


def test_an_unreaped_child_counts_as_dead() -> None:
    child = subprocess.Popen([sys.executable, "-c", "pass"])
    try:
        os.waitid(os.P_PID, child.pid, os.WEXITED | os.WNOWAIT)  # exited, still a zombie
        assert not ta.process_alive(child.pid)
    finally:
        child.wait()
