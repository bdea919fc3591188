"""Drawing results: what every plot shares, and what a family's plots provide.

A family lists the kinds of plot it draws (``Family.plot_kinds``) and gives, when asked
(``Family.plots``), a :class:`Plot` for each: its figure size, the drawing function users call
(``result, ax=None -> Axes``), the whole figure ``cayley-heyoka plot`` writes, and whether a
result holds the data for it. :mod:`cayley_heyoka.workflows.plots` draws the drift, which every
family's conserved monitors give, and dispatches the rest.

matplotlib is imported only when something is drawn.
"""

from __future__ import annotations

import textwrap
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from .labelled import to_double

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure
    from matplotlib.gridspec import GridSpec


INSTALL = 'plots need matplotlib: pip install "cayley_heyoka[plots]"'
TIME = "t (scene time units)"


class PlotError(ValueError):
    """The file or result cannot be drawn as the requested kind (the message says why)."""


def refuse(kind: str, why: str) -> PlotError:
    """The refusal of a plot ``kind``: ``kind 'polhode' needs ...`` (the workflow adds which
    kinds the result supports)."""
    return PlotError(f"kind {kind!r} {why}")


def as_float(a: Any, name: str = "a plotted quantity") -> np.ndarray:
    """Plot coordinates: any precision's numbers as float64 (real128 and real convert), or a
    :class:`PlotError` for one beyond double's range (:func:`.labelled.to_double`)."""
    try:
        return to_double(a, name, "a plot draws doubles")
    except ValueError as exc:
        raise PlotError(str(exc)) from None


def pyplot_figure(size: tuple[float, float]) -> Figure:
    """A new pyplot figure of ``size`` inches (shown in a notebook), constrained layout."""
    try:
        import matplotlib.pyplot as plt
    except ImportError as exc:
        raise ImportError(INSTALL) from exc
    return plt.figure(figsize=size, layout="constrained")


def beside_3d(fig: Figure, rows: int, width: float) -> GridSpec:
    """A grid for a 3-D axes spanning column 0 and ``rows`` panels in column 1."""
    from matplotlib.layout_engine import ConstrainedLayoutEngine

    # Constrained layout does not see a 3-D axes' z label: widen the gap so it stays clear.
    engine = fig.get_layout_engine()
    if not isinstance(engine, ConstrainedLayoutEngine):
        raise ValueError(f"beside_3d needs a figure with constrained layout, not {engine!r}")
    engine.set(wspace=0.08)
    return fig.add_gridspec(rows, 2, width_ratios=(width, 1))


def require_3d(ax: Axes, kind: str) -> None:
    if getattr(ax, "name", "") != "3d":
        raise PlotError(f"ax: the {kind} needs 3-D axes (add_subplot(projection='3d'))")


def colours(n: int) -> list[str]:
    return [f"C{i % 10}" for i in range(n)]


def scene_title(scene: Mapping[str, Any]) -> str:
    return str(scene.get("title") or "(untitled scene)")


def wrap(text: str, width: int = 90) -> str:
    return "\n".join(textwrap.fill(line, width) for line in text.splitlines())


@dataclass(frozen=True)
class Plot:
    """One kind of plot a family draws.

    Attributes
    ----------
    size
        The figure's size in inches, chosen so the PNG reads at its natural size.
    draw
        ``draw(result, ax=None) -> Axes``: into ``ax``, or a new pyplot figure.
    figure
        ``figure(fig, result)``: the whole figure into a bare matplotlib ``Figure``.
    available
        Whether a result holds the data for this plot.
    """

    size: tuple[float, float]
    draw: Callable[..., Any]
    figure: Callable[[Any, Any], Any]
    available: Callable[[Any], bool]
