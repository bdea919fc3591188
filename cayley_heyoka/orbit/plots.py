"""The orbit family's plot: the path in 3-D beside r(t), h(t) and the orbit plane's angles
(``cayley-heyoka plot --kind orbit``, :mod:`cayley_heyoka.core.figures`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..core.figures import (
    TIME,
    Plot,
    as_float,
    beside_3d,
    pyplot_figure,
    refuse,
    require_3d,
    scene_title,
    wrap,
)

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from ..core.result import Result

#: Figure size in inches.
SIZES = {"orbit": (12.0, 8.0)}


#: The side panels of the orbit figure beside r: label and colour.
_ORBIT_PANELS = {
    "h": ("h = |x × v|", "C4"),
    "Theta": ("Θ, node (rad)", "C1"),
    "Phi": ("Φ, inclination (rad)", "C2"),
}


def orbit(result: Result, ax: Axes | None = None) -> Axes:
    """The path x, y, z in frame 0, in 3-D at equal scale, with the central mass and the start.

    Parameters
    ----------
    result
        An orbit result (variables x, y, z).
    ax
        A 3-D axes (``projection="3d"``) for the path alone; if None, a new figure with the
        path and, beside it, r(t) (apsides marked if recorded), h(t) and the orbit plane's
        Θ(t), Φ(t) where the result holds them.

    Returns
    -------
    Axes
        The 3-D axes.
    """
    _position(result)  # refuse before a figure is made
    if ax is not None:
        require_3d(ax, "orbit")
        _orbit_3d(ax, result)
        return ax
    return _orbit_figure(pyplot_figure(SIZES["orbit"]), result)


def _position(result: Result) -> np.ndarray:
    missing = [k for k in ("x", "y", "z") if k not in result.variables]
    if missing:
        have = ", ".join(result.variables) or "none"
        raise refuse(
            "orbit",
            f"needs the position x, y, z of an orbit result (missing: {', '.join(missing)}; "
            f"variables: {have})",
        )
    return np.array([as_float(result.variables[k], k) for k in ("x", "y", "z")])


def _orbit_3d(ax: Axes, result: Result) -> None:
    xyz = _position(result)
    ax.plot([0], [0], [0], "+", color="k", ms=8, label="central mass (origin)")
    ax.plot(*xyz, color="C0", lw=0.8, label="path")
    ax.plot(*xyz[:, :1], "o", color="C2", ms=6, label=f"start, t = {as_float(result.t)[0]:g}")
    ax.plot(*xyz[:, -1:], "s", color="C3", ms=5, label=f"end, t = {as_float(result.t)[-1]:g}")
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.set_zlabel("z")
    ax.set_aspect("equal")
    ax.set_title("path in frame 0", fontsize=10)
    ax.legend(fontsize=8, loc="upper left")


def _orbit_figure(fig: Figure, result: Result) -> Axes:
    xyz = _position(result)
    t = as_float(result.t, "time")
    have = result.variables
    panels = ["r"] + [k for k in ("h", "Theta", "Phi") if k in have]
    grid = beside_3d(fig, len(panels), 1.3)
    ax = fig.add_subplot(grid[:, 0], projection="3d")
    _orbit_3d(ax, result)
    side = None
    for row, panel in enumerate(panels):
        side = fig.add_subplot(grid[row, 1], sharex=side)
        if panel == "r":
            r = as_float(have["r"], "r") if "r" in have else np.linalg.norm(xyz, axis=0)
            side.plot(t, r, color="C0", lw=1.0)
            _apsides(side, result, t, r)
            side.set_ylabel("r = |x|")
        else:
            side.plot(t, as_float(have[panel], panel), color=_ORBIT_PANELS[panel][1], lw=1.0)
            side.set_ylabel(_ORBIT_PANELS[panel][0])
        side.grid(True, alpha=0.3)
        side.tick_params(labelbottom=row == len(panels) - 1)
    side.set_xlabel(TIME)
    fig.suptitle(wrap(scene_title(result.scene), 110), fontsize=11)
    return ax


def _apsides(ax: Axes, result: Result, t: np.ndarray, r: np.ndarray) -> None:
    log = result.events.get("apsis")
    if log is None or not len(log):
        return
    times = as_float(log.time)
    for label, marker, colour in (("pericentre", "v", "C3"), ("apocentre", "^", "C2")):
        at = times[log.label == label]
        # r at the event from the output grid: a marker placed on the line as drawn
        ax.plot(at, np.interp(at, t, r), marker, color=colour, ms=4, ls="none")
    ax.set_title("▼ pericentre, ▲ apocentre (apsis events)", fontsize=9)


def plots() -> dict[str, Plot]:
    """The orbit family's plot (its ``Family.plots``)."""
    return {
        "orbit": Plot(
            SIZES["orbit"],
            orbit,
            _orbit_figure,
            lambda result: {"x", "y", "z"} <= result.variables.keys(),
        )
    }
