"""Figures of result and sweep files (``import cayley_heyoka.plots``).

The public name of :mod:`cayley_heyoka.workflows.plots`, where the code and its documentation
live: the drift against time, :func:`plot_file` for a file straight to a PNG, and each
family's own plots by their kind (``plots.polhode(result)``), found through the family
registry.

Examples
--------
>>> from cayley_heyoka import plots
>>> "drift" in plots.kinds()
True
"""

from __future__ import annotations

from typing import Any

from .workflows import plots as _plots
from .workflows.plots import PlotError, drift, drift_of, kinds, plot_file, supported_kinds

__all__ = ["PlotError", "drift", "drift_of", "kinds", "plot_file", "supported_kinds"]


def __getattr__(name: str) -> Any:
    # A family's plot, by its kind (resolved by the workflows module through the registry).
    return getattr(_plots, name)


def __dir__() -> list[str]:
    return sorted({*__all__, *dir(_plots)})
