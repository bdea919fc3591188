"""Plots of result and sweep files: drift against time, the polhode, the orbit, the crossings.

Each drawing function takes a :class:`~cayley_heyoka.core.result.Result` and an optional matplotlib
``Axes``. Without one it draws a whole figure (through pyplot, so it shows in a notebook) and
returns its main axes; ``ax.figure`` is the figure. :func:`plot_file` and the ``cayley-heyoka
plot FILE --kind KIND`` command draw a result or sweep file straight to a PNG.

matplotlib is an optional dependency (``pip install "cayley_heyoka[plots]"``); it is imported
when a plot is drawn, so importing this module and ``cayley-heyoka --help`` stay fast.
"""

from __future__ import annotations

import json
import textwrap
import warnings
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..core.result import Result

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure
    from matplotlib.gridspec import GridSpec

#: The kinds of plot, as ``plot_file`` and ``--kind`` name them.
KINDS: tuple[str, ...] = ("drift", "polhode", "orbit", "crossings")

#: Figure sizes in inches, chosen so the PNGs read at their natural size.
_SIZES = {
    "drift": (10.5, 5.5),
    "polhode": (12.0, 7.0),
    "orbit": (12.0, 8.0),
    "crossings": (11.0, 5.0),
}
_AXIS_LABELS = ("x1", "y1", "z1")
_AXIS_COLOURS = ("C0", "C1", "C2")
_SUBSCRIPTED = ("x₁", "y₁", "z₁")
_TIME = "t (scene time units)"
#: The side panels of the orbit figure beside r: label and colour.
_ORBIT_PANELS = {
    "h": ("h = |x × v|", "C4"),
    "Theta": ("Θ, node (rad)", "C1"),
    "Phi": ("Φ, inclination (rad)", "C2"),
}
_INSTALL = 'plots need matplotlib: pip install "cayley_heyoka[plots]"'


class PlotError(ValueError):
    """The file or result cannot be drawn as the requested kind (the message says why)."""


# ------------------------------------------------------------------ what a result supports
def supported_kinds(result: Result) -> tuple[str, ...]:
    """The kinds of plot that ``result`` holds the data for, in :data:`KINDS` order."""
    rates = {"p", "q", "r"} <= result.variables.keys() and "body" in result.scene
    available = {
        "drift": bool(result.conserved),
        "polhode": rates,
        "orbit": {"x", "y", "z"} <= result.variables.keys(),
        "crossings": rates and "invariable_plane" in result.events,
    }
    return tuple(kind for kind in KINDS if available[kind])


def _refuse(result: Result, kind: str, why: str) -> PlotError:
    kinds = ", ".join(supported_kinds(result)) or "none"
    return PlotError(f"kind {kind!r} {why}; kinds this result supports: {kinds}")


def _rates(result: Result, kind: str) -> tuple[np.ndarray, np.ndarray]:
    """Body rates as a (3, n) float array and the principal moments (A, B, C)."""
    have = ", ".join(result.variables) or "none"
    if "body" not in result.scene:
        raise _refuse(
            result,
            kind,
            f"needs a rigid-body result (a [body] scene, rates p, q, r); this one has: {have}",
        )
    missing = [k for k in ("p", "q", "r") if k not in result.variables]
    if missing:
        raise _refuse(result, kind, f"needs the body rates p, q, r (missing: {', '.join(missing)})")
    rates = np.array([_float(result.variables[k]) for k in ("p", "q", "r")])
    inertia = np.array([float(x) for x in result.scene["body"]["inertia"]])
    return rates, inertia


def _torque_free(result: Result) -> bool:
    return not result.scene.get("forces")


# ------------------------------------------------------------------ drift
def drift_of(result: Result) -> dict[str, np.ndarray]:
    """|Relative drift| of each conserved monitor of ``result``, by monitor name.

    A vector monitor (``momentum_space``, ``angular_momentum``) is reduced to its largest
    |component| at each time, the component drifts being relative to the initial vector's norm
    (:meth:`Result.drift`).

    Raises
    ------
    PlotError
        If the result lists no conserved monitor.
    """
    if not result.conserved:
        monitors = ", ".join(result.monitors) or "none"
        raise _refuse(
            result,
            "drift",
            f"needs conserved monitors, and this result lists none (its monitors: {monitors}; "
            "none is conserved by this scene's flow)",
        )
    out = {}
    for name in result.conserved:
        d = np.abs(_float(result.drift(name)))
        out[name] = d.max(axis=1) if d.ndim > 1 else d
    return out


def drift(
    t: np.ndarray | Result,
    series: Mapping[str, np.ndarray] | None = None,
    ax: Axes | None = None,
    title: str = "",
) -> Axes:
    """|Relative drift| against time on log–log axes.

    Parameters
    ----------
    t
        Times, shape ``(n,)``; or a :class:`Result`, whose conserved monitors are drawn
        (:func:`drift_of`) under its scene's title, with ``series`` left out.
    series
        Drift by name: shape ``(n,)`` for one run (a line), or ``(members, n)`` for a sweep
        (the median, the 10–90 % band across members, and the worst member: the largest
        drift at the last time reached, as in the sweep's summary). NaN marks times a member
        did not reach. Signs are dropped.
    ax
        Axes to draw in; a new figure if None.
    title
        Axes title.

    Returns
    -------
    Axes
        The axes drawn in.

    Notes
    -----
    Log axes cannot show t ≤ 0 or a drift of exactly zero, so those points are left out and
    the line joins its neighbours. Two light reference lines start at the drift's level over
    its first decade of time: ∝ t^½, the random walk of round-off (Brouwer's law), and ∝ t,
    a systematic drift.
    """
    if isinstance(t, Result):
        if series is not None:
            raise PlotError("series: give it with an array of times t, not with a Result")
        title = title or _scene_title(t.scene)
        t, series = t.t, drift_of(t)
    if not series:
        raise PlotError("series: empty; give at least one drift series")
    t = _float(t)
    ax = ax if ax is not None else _pyplot_figure("drift").add_subplot()
    positive = t > 0
    early: list[np.ndarray] = []  # drift over the first decade, to anchor the reference slopes
    t_first = t[positive].min() if positive.any() else np.nan
    for (name, values), colour in zip(series.items(), _colours(len(series)), strict=True):
        d = np.abs(_float(values))
        if d.ndim not in (1, 2) or d.shape[-1] != len(t):
            raise PlotError(
                f"series[{name!r}]: shape {d.shape}; expected ({len(t)},) or "
                f"(members, {len(t)}) to match t"
            )
        if d.ndim == 1:
            line = d
            ax.plot(*_loggable(t, d), color=colour, lw=1.1, label=name)
        else:
            reached = np.flatnonzero(~np.isnan(d).all(axis=0))
            if not reached.size:
                raise PlotError(f"series[{name!r}]: no member has a drift value (all NaN)")
            with warnings.catch_warnings():
                # A member that stopped early is NaN after; where none got there, NaN is right.
                warnings.simplefilter("ignore", RuntimeWarning)
                line = np.nanmedian(d, axis=0)
                # Members' own values, not interpolants: an interpolant between an exact zero
                # and ε would reach far below round-off on the log axis.
                low, high = np.nanpercentile(d, [10, 90], axis=0, method="nearest")
            band = positive & (low > 0)
            ax.fill_between(
                t,
                low,
                high,
                where=band,
                color=colour,
                alpha=0.22,
                lw=0,
                label=f"{name}: 10–90 % of members",
            )
            worst = int(np.nanargmax(d[:, reached[-1]]))
            ax.plot(
                *_loggable(t, d[worst]),
                color=colour,
                lw=0.8,
                ls="--",
                label=f"{name}: worst member (#{worst})",
            )
            ax.plot(*_loggable(t, line), color=colour, lw=1.6, label=f"{name}: median of {len(d)}")
        first_decade = positive & (t <= 10 * t_first) & (line > 0)
        early.append(line[first_decade])
    if not any(len(line.get_xdata()) for line in ax.get_lines()):
        # matplotlib's own refusal ("Data cannot be log-scaled") would come at savefig.
        raise PlotError(
            "series: nothing to draw on log axes (every drift is exactly 0, or no time is > 0)"
        )
    _reference_slopes(ax, t[positive], np.concatenate(early))
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(_TIME)
    ax.set_ylabel("|relative drift|")
    ax.set_title(_wrap(title), fontsize=10)
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    return ax


def _loggable(t: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    keep = (t > 0) & (d > 0)
    return t[keep], d[keep]


def _reference_slopes(ax: Axes, t: np.ndarray, early: np.ndarray) -> None:
    if not len(t) or not len(early):
        ax.text(
            0.5,
            0.5,
            "no nonzero drift at t > 0 to draw on log axes",
            transform=ax.transAxes,
            ha="center",
        )
        return
    t0, level = t.min(), float(np.median(early))
    span = np.array([t0, t.max()])
    for power, style, label in (
        (0.5, ":", r"$\propto t^{1/2}$: round-off random walk (Brouwer)"),
        (1.0, "-.", r"$\propto t$: systematic drift"),
    ):
        ax.plot(span, level * (span / t0) ** power, color="0.55", lw=0.9, ls=style, label=label)


# ------------------------------------------------------------------ polhode
def polhode(result: Result, ax: Axes | None = None) -> Axes:
    """The polhode: the angular velocity (p, q, r) in body axes, in 3-D.

    For a torque-free body it lies on the energy ellipsoid Ap² + Bq² + Cr² = 2T (drawn
    faintly) and on the momentum ellipsoid A²p² + B²q² + C²r² = |L|², and it is closed. Under
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
        _require_3d(ax, "polhode")
        _polhode_3d(ax, result, rates, inertia)
        return ax
    return _polhode_figure(_pyplot_figure("polhode"), result)


def _polhode_figure(fig: Figure, result: Result) -> Axes:
    rates, inertia = _rates(result, "polhode")
    grid = _beside_3d(fig, 3, 1.9)
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
    fig.suptitle(_wrap(_scene_title(result.scene), 110), fontsize=11)
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
    ax.plot(*rates[:, :1], "o", color="k", ms=5, label=f"start, t = {_float(result.t)[0]:g}")
    ax.set_xlabel("p")
    ax.set_ylabel("q")
    ax.set_zlabel("r")
    ax.set_aspect("equal")
    ax.set_title(title, fontsize=10)
    ax.legend(fontsize=8, loc="upper left")


# ------------------------------------------------------------------ orbit
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
        _require_3d(ax, "orbit")
        _orbit_3d(ax, result)
        return ax
    return _orbit_figure(_pyplot_figure("orbit"), result)


def _position(result: Result) -> np.ndarray:
    missing = [k for k in ("x", "y", "z") if k not in result.variables]
    if missing:
        have = ", ".join(result.variables) or "none"
        raise _refuse(
            result,
            "orbit",
            f"needs the position x, y, z of an orbit result (missing: {', '.join(missing)}; "
            f"variables: {have})",
        )
    return np.array([_float(result.variables[k]) for k in ("x", "y", "z")])


def _orbit_3d(ax: Axes, result: Result) -> None:
    xyz = _position(result)
    ax.plot([0], [0], [0], "+", color="k", ms=8, label="central mass (origin)")
    ax.plot(*xyz, color="C0", lw=0.8, label="path")
    ax.plot(*xyz[:, :1], "o", color="C2", ms=6, label=f"start, t = {_float(result.t)[0]:g}")
    ax.plot(*xyz[:, -1:], "s", color="C3", ms=5, label=f"end, t = {_float(result.t)[-1]:g}")
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.set_zlabel("z")
    ax.set_aspect("equal")
    ax.set_title("path in frame 0", fontsize=10)
    ax.legend(fontsize=8, loc="upper left")


def _orbit_figure(fig: Figure, result: Result) -> Axes:
    xyz = _position(result)
    t = _float(result.t)
    have = result.variables
    panels = ["r"] + [k for k in ("h", "Theta", "Phi") if k in have]
    grid = _beside_3d(fig, len(panels), 1.3)
    ax = fig.add_subplot(grid[:, 0], projection="3d")
    _orbit_3d(ax, result)
    side = None
    for row, panel in enumerate(panels):
        side = fig.add_subplot(grid[row, 1], sharex=side)
        if panel == "r":
            r = _float(have["r"]) if "r" in have else np.linalg.norm(xyz, axis=0)
            side.plot(t, r, color="C0", lw=1.0)
            _apsides(side, result, t, r)
            side.set_ylabel("r = |x|")
        else:
            side.plot(t, _float(have[panel]), color=_ORBIT_PANELS[panel][1], lw=1.0)
            side.set_ylabel(_ORBIT_PANELS[panel][0])
        side.grid(True, alpha=0.3)
        side.tick_params(labelbottom=row == len(panels) - 1)
    side.set_xlabel(_TIME)
    fig.suptitle(_wrap(_scene_title(result.scene), 110), fontsize=11)
    return ax


def _apsides(ax: Axes, result: Result, t: np.ndarray, r: np.ndarray) -> None:
    log = result.events.get("apsis")
    if log is None or not len(log):
        return
    times = _float(log.time)
    for label, marker, colour in (("pericentre", "v", "C3"), ("apocentre", "^", "C2")):
        at = times[log.label == label]
        # r at the event from the output grid: a marker placed on the line as drawn
        ax.plot(at, np.interp(at, t, r), marker, color=colour, ms=4, ls="none")
    ax.set_title("▼ pericentre, ▲ apocentre (apsis events)", fontsize=9)


# ------------------------------------------------------------------ crossings
def crossings(result: Result, ax: Axes | None = None) -> Axes:
    """The invariable-plane crossings: each body axis's elevation above that plane.

    The sine of axis x₁'s elevation is its component along L, Ap/|L| (y₁: Bq/|L|, z₁: Cr/|L|),
    from the body rates and the principal moments of the scene. Each recorded
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
        raise _refuse(
            result,
            "crossings",
            f"needs the invariable_plane event, which this run did not record (events: "
            f'{recorded}); add output.events = ["invariable_plane"] to the scene and run again',
        )
    ax = ax if ax is not None else _pyplot_figure("crossings").add_subplot()
    t = _float(result.t)
    momentum = inertia[:, None] * rates
    sines = momentum / np.linalg.norm(momentum, axis=0)
    times = _float(log.time)
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
    ax.set_title(_wrap(f"{_scene_title(result.scene)}\n{len(log)} crossings; {plane}"), fontsize=10)
    ax.set_xlabel(_TIME)
    ax.set_ylabel("sin(elevation above the invariable plane)")
    ax.set_ylim(-1.05, 1.05)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    return ax


# ------------------------------------------------------------------ files and the command
def plot_file(path: str | Path, kind: str, out: str | Path | None = None) -> Path:
    """Draw a result or sweep file as a figure file (PNG unless ``out`` says otherwise).

    Parameters
    ----------
    path
        A result file (``cayley_heyoka.core.result``) or a sweep file
        (``cayley_heyoka.workflows.sweep``:
        dataset ``t``, group ``drift`` of (members, n) arrays; ``kind="drift"`` only).
    kind
        One of :data:`KINDS`.
    out
        Where to write; default ``path``'s stem + ``_KIND.png``, beside it.

    Returns
    -------
    Path
        The file written.
    """
    if kind not in KINDS:
        raise PlotError(f"kind: {kind!r} is not one of {', '.join(KINDS)}")
    path = Path(path)
    out = Path(out) if out is not None else path.with_name(f"{path.stem}_{kind}.png")
    fmt = _file_format(path)
    try:
        from matplotlib.figure import Figure
    except ImportError as exc:
        raise ImportError(_INSTALL) from exc
    # A bare Figure, not pyplot: nothing is shown and no pyplot state is left behind.
    fig = Figure(figsize=_SIZES[kind], layout="constrained")
    fmt_out = out.suffix[1:].lower() or "png"
    formats = fig.canvas.get_supported_filetypes()
    if fmt_out not in formats:
        raise PlotError(
            f"out: {out.name} asks for format {fmt_out!r} (its suffix); give one of "
            f"{', '.join(sorted(formats))}"
        )
    if fmt == "cayley_heyoka.sweep":
        if kind != "drift":
            raise PlotError(
                f"kind {kind!r} needs a result file; {path.name} is a sweep file, which "
                "supports only: drift"
            )
        t, series, title = _read_sweep(path)
        drift(t, series, ax=fig.add_subplot(), title=title)
    else:
        result = Result.load(path)
        if kind == "drift":
            drift(result, ax=fig.add_subplot())
        elif kind == "polhode":
            _polhode_figure(fig, result)
        elif kind == "orbit":
            _orbit_figure(fig, result)
        else:
            crossings(result, ax=fig.add_subplot())
    from ..core.files import PNG_SOFTWARE, write_atomically

    # The Software tag is how a later `plot` recognises a PNG it may replace.
    tag = {"metadata": {"Software": f"{PNG_SOFTWARE} plot"}} if fmt_out == "png" else {}
    write_atomically(out, lambda tmp: fig.savefig(tmp, dpi=110, format=fmt_out, **tag))
    return out


def _file_format(path: Path) -> str:
    import h5py

    if not path.is_file():
        raise PlotError("no such file" if not path.exists() else "is not a regular file")
    try:
        with h5py.File(path, "r") as f:
            fmt = f.attrs.get("format")
    except OSError as exc:
        raise PlotError(f"not an HDF5 file ({exc})") from exc
    known = ("cayley_heyoka.result", "cayley_heyoka.sweep")
    if fmt not in known:
        raise PlotError(f"format attribute is {fmt!r}; expected one of {', '.join(known)}")
    return str(fmt)


def _read_sweep(path: Path) -> tuple[np.ndarray, dict[str, np.ndarray], str]:
    from ..core.files import open_ours

    with open_ours(path, "sweep") as f:  # checksum verified: a damaged file is not drawn
        complete = "t" in f and "drift" in f and len(f["drift"])
        if complete:
            t = np.asarray(f["t"][()], dtype=np.float64)  # decimal text beyond double
            series = {name: np.asarray(d[()], dtype=np.float64) for name, d in f["drift"].items()}
            study = json.loads(f.attrs["study"]) if "study" in f.attrs else {}
    if not complete:
        raise PlotError("a sweep file needs a dataset t and a non-empty group drift")
    return t, series, study.get("title") or f"sweep {path.name}"


# ------------------------------------------------------------------ helpers
def _float(a: Any) -> np.ndarray:
    """Plot coordinates: any precision's numbers as float64 (real128 and real convert)."""
    return np.asarray(a, dtype=np.float64)


def _pyplot_figure(kind: str) -> Figure:
    try:
        import matplotlib.pyplot as plt
    except ImportError as exc:
        raise ImportError(_INSTALL) from exc
    return plt.figure(figsize=_SIZES[kind], layout="constrained")


def _beside_3d(fig: Figure, rows: int, width: float) -> GridSpec:
    """A grid for a 3-D axes spanning column 0 and ``rows`` panels in column 1."""
    # Constrained layout does not see a 3-D axes' z label: widen the gap so it stays clear.
    fig.get_layout_engine().set(wspace=0.08)
    return fig.add_gridspec(rows, 2, width_ratios=(width, 1))


def _require_3d(ax: Axes, kind: str) -> None:
    if getattr(ax, "name", "") != "3d":
        raise PlotError(f"ax: the {kind} needs 3-D axes (add_subplot(projection='3d'))")


def _colours(n: int) -> list[str]:
    return [f"C{i % 10}" for i in range(n)]


def _scene_title(scene: Mapping[str, Any]) -> str:
    return str(scene.get("title") or "(untitled scene)")


def _wrap(text: str, width: int = 90) -> str:
    return "\n".join(textwrap.fill(line, width) for line in text.splitlines())
