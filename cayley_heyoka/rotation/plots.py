"""The rotation family's plots: the polhode and the invariable-plane crossings
(``cayley-heyoka plot --kind polhode|crossings``, :mod:`cayley_heyoka.core.figures`)."""

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

#: Figure sizes in inches.
SIZES = {"polhode": (12.0, 7.0), "crossings": (11.0, 5.0)}


_AXIS_LABELS = ("x1", "y1", "z1")


_AXIS_COLOURS = ("C0", "C1", "C2")


_SUBSCRIPTED = ("x₁", "y₁", "z₁")


def _rates(result: Result, kind: str) -> tuple[np.ndarray, np.ndarray]:
    """Body rates as a (3, n) float array and the principal moments (A, B, C)."""
    have = ", ".join(result.variables) or "none"
    if "body" not in result.scene:
        raise refuse(
            kind,
            f"needs a rigid-body result (a [body] scene, rates p, q, r); this one has: {have}",
        )
    missing = [k for k in ("p", "q", "r") if k not in result.variables]
    if missing:
        raise refuse(kind, f"needs the body rates p, q, r (missing: {', '.join(missing)})")
    rates = np.array([as_float(result.variables[k], k) for k in ("p", "q", "r")])
    inertia = np.array([float(x) for x in result.scene["body"]["inertia"]])
    return rates, inertia


def _torque_free(result: Result) -> bool:
    return not result.scene.get("forces")


def polhode(result: Result, ax: Axes | None = None) -> Axes:
    """The polhode: the angular velocity (p, q, r) in body axes, in 3-D.

    For a torque-free body it lies on the energy ellipsoid Ap² + Bq² + Cr² = 2T (drawn
    faintly) and on the momentum ellipsoid ``A²p² + B²q² + C²r² = |L|²``, and it is closed. Under
    a torque neither is fixed: the curve is drawn alone and the title says so.

    Parameters
    ----------
    result
        A rigid-body result (variables p, q, r).
    ax
        A 3-D axes (``projection="3d"``) for the curve alone; if None, a new figure with the
        curve and its projections on the three principal planes.

    Returns
    -------
    Axes
        The 3-D axes.
    """
    rates, inertia = _rates(result, "polhode")  # refuse before a figure is made
    if ax is not None:
        require_3d(ax, "polhode")
        _polhode_3d(ax, result, rates, inertia)
        return ax
    return _polhode_figure(pyplot_figure(SIZES["polhode"]), result)


def _polhode_figure(fig: Figure, result: Result) -> Axes:
    rates, inertia = _rates(result, "polhode")
    grid = beside_3d(fig, 3, 1.9)
    ax = fig.add_subplot(grid[:, 0], projection="3d")
    _polhode_3d(ax, result, rates, inertia)
    semi = _energy_semi_axes(rates, inertia) if _torque_free(result) else None
    names = ("p", "q", "r")
    for row, (i, j) in enumerate(((1, 2), (0, 2), (0, 1))):
        sub = fig.add_subplot(grid[row, 1])
        if semi is not None:  # the outline of the energy ellipsoid seen along the third axis
            angle = np.linspace(0, 2 * np.pi, 200)
            sub.plot(semi[i] * np.cos(angle), semi[j] * np.sin(angle), color="0.75", lw=0.8)
        sub.plot(rates[i], rates[j], color="C3", lw=1.0)
        sub.plot(rates[i, 0], rates[j, 0], "o", color="k", ms=4)
        sub.set_xlabel(names[i])
        sub.set_ylabel(names[j])
        sub.set_aspect("equal", adjustable="datalim")
        sub.set_title(f"seen along the {_SUBSCRIPTED[3 - i - j]} axis", fontsize=9)
    fig.suptitle(wrap(scene_title(result.scene), 110), fontsize=11)
    return ax


def _energy_semi_axes(rates: np.ndarray, inertia: np.ndarray) -> np.ndarray:
    """Semi-axes of Ap² + Bq² + Cr² = 2T, with 2T from the first sample."""
    two_t = float(inertia @ rates[:, 0] ** 2)
    return np.sqrt(two_t / inertia)


def _polhode_3d(ax: Axes, result: Result, rates: np.ndarray, inertia: np.ndarray) -> None:
    if _torque_free(result):
        semi = _energy_semi_axes(rates, inertia)
        u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 41), np.linspace(0, np.pi, 21))
        ax.plot_wireframe(
            semi[0] * np.cos(u) * np.sin(v),
            semi[1] * np.sin(u) * np.sin(v),
            semi[2] * np.cos(v),
            color="0.6",
            lw=0.4,
            alpha=0.35,
        )
        title = "polhode: ω in body axes on the energy ellipsoid Ap² + Bq² + Cr² = 2T"
    else:
        title = "ω in body axes under torque: no fixed energy ellipsoid, curve only"
    ax.plot(*rates, color="C3", lw=1.2, label="ω(t) = (p, q, r)")
    ax.plot(*rates[:, :1], "o", color="k", ms=5, label=f"start, t = {as_float(result.t)[0]:g}")
    ax.set_xlabel("p")
    ax.set_ylabel("q")
    ax.set_zlabel("r")
    ax.set_aspect("equal")
    ax.set_title(title, fontsize=10)
    ax.legend(fontsize=8, loc="upper left")


def crossings(result: Result, ax: Axes | None = None) -> Axes:
    """The invariable-plane crossings: each body axis's elevation above that plane.

    The sine of axis x₁'s elevation is its component along L, ``Ap/|L|`` (y₁: ``Bq/|L|``,
    z₁: ``Cr/|L|``), from the body rates and the principal moments of the scene. Each recorded
    ``invariable_plane`` event is marked on the zero line in its axis's colour, ▲ for an
    upward crossing and ▼ for a downward one. Under a torque L is not conserved: the plane is
    the one perpendicular to the instantaneous L (as the event uses), and the title says so.

    Parameters
    ----------
    result
        A rigid-body result run with ``output.events = ["invariable_plane"]``.
    ax
        Axes to draw in; a new figure if None.

    Returns
    -------
    Axes
        The axes drawn in.
    """
    rates, inertia = _rates(result, "crossings")
    log = result.events.get("invariable_plane")
    if log is None:
        recorded = ", ".join(result.events) or "none"
        raise refuse(
            "crossings",
            f"needs the invariable_plane event, which this run did not record (events: "
            f'{recorded}); add output.events = ["invariable_plane"] to the scene and run again',
        )
    ax = ax if ax is not None else pyplot_figure(SIZES["crossings"]).add_subplot()
    t = as_float(result.t, "time")
    momentum = inertia[:, None] * rates
    sines = momentum / np.linalg.norm(momentum, axis=0)
    times = as_float(log.time)
    ax.axhline(0.0, color="0.4", lw=0.8)
    components = ("Ap", "Bq", "Cr")
    for j, (axis, colour) in enumerate(zip(_AXIS_LABELS, _AXIS_COLOURS, strict=True)):
        ax.plot(t, sines[j], color=colour, lw=1.0, label=f"{axis}: {components[j]}/|L|")
        for direction, marker, word in ((1, "^", "up"), (-1, "v", "down")):
            at = times[(log.label == axis) & (log.direction == direction)]
            if len(at):
                ax.scatter(
                    at,
                    np.zeros_like(at),
                    marker=marker,
                    color=colour,
                    s=28,
                    zorder=3,
                    edgecolors="k",
                    linewidths=0.4,
                    label=f"{axis} crossing {word} ({len(at)})",
                )
    plane = "the plane perpendicular to L"
    if not _torque_free(result):
        plane += " at each instant (L is not conserved under a torque)"
    ax.set_title(wrap(f"{scene_title(result.scene)}\n{len(log)} crossings; {plane}"), fontsize=10)
    ax.set_xlabel(TIME)
    ax.set_ylabel("sin(elevation above the invariable plane)")
    ax.set_ylim(-1.05, 1.05)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    return ax


def plots() -> dict[str, Plot]:
    """The rotation family's plots (its ``Family.plots``)."""

    def rates(result: Result) -> bool:
        return {"p", "q", "r"} <= result.variables.keys() and "body" in result.scene

    return {
        "polhode": Plot(SIZES["polhode"], polhode, _polhode_figure, rates),
        "crossings": Plot(
            SIZES["crossings"],
            crossings,
            lambda fig, result: crossings(result, ax=fig.add_subplot()),
            lambda result: rates(result) and "invariable_plane" in result.events,
        ),
    }
