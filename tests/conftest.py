"""Session-wide hooks. The hostile suite's tally of outcomes (tests/hostile/conftest.py) is
counted in each pytest-xdist worker; the controller, which runs no test, adds them up here and
prints the sum ("hostile-input cases: ...")."""

from __future__ import annotations

import collections
from typing import Any

import pytest

_TALLY: collections.Counter[str] = collections.Counter()


@pytest.hookimpl(optionalhook=True)
def pytest_testnodedown(node: Any, error: Any) -> None:
    _TALLY.update(getattr(node, "workeroutput", {}).get("hostile_tally", {}))


def pytest_terminal_summary(terminalreporter: Any) -> None:
    if _TALLY:
        counts = ", ".join(f"{k} {v}" for k, v in sorted(_TALLY.items()))
        terminalreporter.write_line(f"hostile-input cases: {counts}")


@pytest.fixture(autouse=True)
def _structures_of_this_test_only():
    """Each test builds its own model structures (cayley_heyoka.core.structures): a structure
    built while a test patched a family's function (a handler made to fail, an equation made
    wrong) would otherwise be filled for the scenes of later tests."""
    from cayley_heyoka.core import structures

    structures.clear()
    yield
    structures.clear()
