"""pytest hooks for the whole repository (tools/tests and adapters/python/tests; `./test.sh`
runs pytest with `--confcutdir=.` so this file applies to both).

Under ``CI=true`` a skipped test fails: a skip means a prerequisite is missing, and no
claim may rest on a test that did not run. Locally it stays a skip and ``./test.sh``
counts it in its closing line.
"""

from __future__ import annotations

import os
from collections.abc import Generator

import pluggy
import pytest


def _in_ci() -> bool:
    return os.environ.get("CI", "") in ("true", "1")


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(
    item: pytest.Item, call: pytest.CallInfo[None]
) -> Generator[None, pluggy.Result[pytest.TestReport], None]:
    outcome = yield
    report = outcome.get_result()
    if _in_ci() and report.skipped:
        report.outcome = "failed"
        reason = report.longrepr[2] if isinstance(report.longrepr, tuple) else report.longrepr
        report.longrepr = f"skipped in CI (a prerequisite is missing): {reason}"
