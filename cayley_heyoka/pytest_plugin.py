"""The pytest plugin's entry point (``pytest11``, or ``-p cayley_heyoka.pytest_plugin``): the
``drift_golden`` fixture and the ``--update-golden`` option of
:mod:`cayley_heyoka.workflows.pytest_plugin`, registered under this public name."""

from __future__ import annotations

from .workflows.pytest_plugin import (
    drift_golden,
    pytest_addoption,
    pytest_configure,
    pytest_terminal_summary,
)

__all__ = ["drift_golden", "pytest_addoption", "pytest_configure", "pytest_terminal_summary"]
