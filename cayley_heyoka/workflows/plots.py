"""Plots of result and sweep files: the drift against time here, and each family's own plots
(the rotation family's polhode and invariable-plane crossings, the orbit family's path), found
through the family registry (``Family.plot_kinds``, :mod:`cayley_heyoka.core.figures`).

Each drawing function takes a :class:`~cayley_heyoka.core.result.Result` and an optional
matplotlib ``Axes``. Without one it draws a whole figure (through pyplot, so it shows in a
notebook) and returns its main axes; ``ax.figure`` is the figure. A family's plot is an
attribute of this module by its kind (``plots.polhode(result)``). :func:`plot_file` and the
``cayley-heyoka plot FILE --kind KIND`` command draw a result or sweep file straight to a PNG.

matplotlib is an optional dependency (``pip install "cayley_heyoka[plots]"``); it is imported
when a plot is drawn, so importing this module and ``cayley-heyoka --help`` stay fast.
"""

from __future__ import annotations

import json
import warnings
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..core.figures import (
    INSTALL,
    TIME,
    Plot,
    PlotError,
    as_float,
    colours,
    pyplot_figure,
    refuse,
    scene_title,
    wrap,
)
from ..core.result import Result

if TYPE_CHECKING:
    from matplotlib.axes import Axes

#: The drift's figure size in inches (a family's plots give their own).
_DRIFT_SIZE = (10.5, 5.5)


def kinds() -> tuple[str, ...]:
    """Every kind of plot, as ``plot_file`` and ``--kind`` name them: the drift, then each
    registered family's (its ``plot_kinds``)."""
    from ..core.families import FAMILIES

    return ("drift", *(k for name in FAMILIES for k in FAMILIES[name].plot_kinds))


def _family_plots(result: Result) -> dict[str, Plot]:
    """The plots of the result's family (none for a scene no family claims)."""
    from ..core.errors import SceneError
    from ..core.families import FAMILIES, family_of

    try:
        family = FAMILIES[family_of(result.scene)]
    except SceneError:
        return {}
    return dict(family.plots()) if family.plots is not None else {}


def supported_kinds(result: Result) -> tuple[str, ...]:
    """The kinds of plot that ``result`` holds the data for: the drift, then its family's."""
    n = len(result.t)
    own = [k for k, plot in _family_plots(result).items() if n >= 1 and plot.available(result)]
    return ("drift",) * bool(result.conserved and n >= 2) + tuple(own)


def _refuse(result: Result, kind: str, why: str) -> PlotError:
    return PlotError(f"{refuse(kind, why)}{_supported(result)}")


def _supported(result: Result) -> str:
    return f"; kinds this result supports: {', '.join(supported_kinds(result)) or 'none'}"


def _require_rows(result: Result, kind: str) -> None:
    """Refuse a result with too few output rows for ``kind``: every plot needs one, the
    drift two (its first value is 0 by definition). A run that stopped early says why."""
    least = 2 if kind == "drift" else 1
    n = len(result.t)
    if n >= least:
        return
    rows = {0: "no output rows", 1: "one output row"}[n]
    ended = f" (the run ended: {result.message})" if result.message else ""
    needs = "two output times" if least == 2 else "an output time"
    raise PlotError(f"kind {kind!r} needs at least {needs}; this result has {rows}{ended}")


def _plot_of(result: Result, kind: str) -> Plot:
    """The family plot ``kind`` for ``result``, or a PlotError saying whose plot it is."""
    plot = _family_plots(result).get(kind)
    if plot is not None:
        _require_rows(result, kind)
        return plot
    from ..core.families import FAMILIES

    owners = [name for name in FAMILIES if kind in FAMILIES[name].plot_kinds]
    if not owners:
        raise PlotError(f"kind: {kind!r} is not one of {', '.join(kinds())}")
    raise _refuse(result, kind, f"is drawn for {' and '.join(owners)} results, not this one")


def _family_draw(kind: str) -> Any:
    """``result, ax=None -> Axes`` for a family's plot ``kind``, its refusals completed with
    the kinds the result supports."""

    def draw(result: Result, ax: Axes | None = None) -> Axes:
        plot = _plot_of(result, kind)
        try:
            return plot.draw(result, ax)
        except PlotError as exc:
            raise PlotError(f"{exc}{_supported(result)}") from None

    draw.__name__ = draw.__qualname__ = kind
    draw.__doc__ = f"The {kind} plot of the result's model family (:mod:`.core.figures`)."
    return draw


def __getattr__(name: str) -> Any:
    # A family's plot by its kind: plots.polhode(result). Never for private or dunder names,
    # which tools probe for (loading the families to answer them would import heyoka).
    if not name.startswith("_") and name in kinds()[1:]:
        return _family_draw(name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


# ------------------------------------------------------------------ drift
def drift_of(result: Result) -> dict[str, np.ndarray]:
    """``|relative drift|`` of each conserved monitor of ``result``, by monitor name.

    A vector monitor (``momentum_space``, ``angular_momentum``) is reduced to its largest
    ``|component|`` at each time, the component drifts being relative to the initial vector's norm
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
    _require_rows(result, "drift")
    out = {}
    for name in result.conserved:
        d = np.abs(as_float(result.drift(name), f"the drift of {name}"))
        out[name] = d.max(axis=1) if d.ndim > 1 else d
    return out


def drift(
    t: np.ndarray | Result,
    series: Mapping[str, np.ndarray] | None = None,
    ax: Axes | None = None,
    title: str = "",
) -> Axes:
    """``|relative drift|`` against time on log–log axes.

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
        title = title or scene_title(t.scene)
        t, series = t.t, drift_of(t)
    elif len(t) < 2:
        raise PlotError(f"t: a drift needs at least two output times, got {len(t)}")
    if not series:
        raise PlotError("series: empty; give at least one drift series")
    t = as_float(t)
    ax = ax if ax is not None else pyplot_figure(_DRIFT_SIZE).add_subplot()
    positive = t > 0
    early: list[np.ndarray] = []  # drift over the first decade, to anchor the reference slopes
    t_first = t[positive].min() if positive.any() else np.nan
    for (name, values), colour in zip(series.items(), colours(len(series)), strict=True):
        d = np.abs(as_float(values))
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
    ax.set_xlabel(TIME)
    ax.set_ylabel("|relative drift|")
    ax.set_title(wrap(title), fontsize=10)
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
# ------------------------------------------------------------------ orbit
# ------------------------------------------------------------------ crossings
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
        One of :func:`kinds`.
    out
        Where to write; default ``path``'s stem + ``_KIND.png``, beside it.

    Returns
    -------
    Path
        The file written.
    """
    if kind not in kinds():
        raise PlotError(f"kind: {kind!r} is not one of {', '.join(kinds())}")
    path = Path(path)
    out = Path(out) if out is not None else path.with_name(f"{path.stem}_{kind}.png")
    fmt = _file_format(path)
    try:
        from matplotlib.figure import Figure
    except ImportError as exc:
        raise ImportError(INSTALL) from exc
    # A bare Figure, not pyplot: nothing is shown and no pyplot state is left behind.
    result = None if fmt == "cayley_heyoka.sweep" else Result.load(path)
    plot = None if kind == "drift" or result is None else _plot_of(result, kind)
    fig = Figure(figsize=_DRIFT_SIZE if plot is None else plot.size, layout="constrained")
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
    elif plot is None:
        drift(result, ax=fig.add_subplot())
    else:
        try:
            plot.figure(fig, result)
        except PlotError as exc:
            raise PlotError(f"{exc}{_supported(result)}") from None
    import io

    from ..core.files import PNG_SOFTWARE, write_bytes

    # The Software tag is how a later `plot` recognises a PNG it may replace.
    tag = {"metadata": {"Software": f"{PNG_SOFTWARE} plot"}} if fmt_out == "png" else {}
    image = io.BytesIO()
    fig.savefig(image, dpi=110, format=fmt_out, **tag)
    write_bytes(out, image.getbuffer())
    return out


def _file_format(path: Path) -> str:
    """The ``format`` of a result or sweep file; anything else is refused as the file reader
    refuses it (missing, a name too long, not HDF5, damaged, another kind of our files)."""
    from ..core.files import FORMATS, identify, open_ours

    kind = identify(path)
    if kind in ("result", "sweep"):
        return FORMATS[kind]
    with open_ours(path, "result"):  # raises ResultFileError, saying what the file is
        pass
    raise PlotError(f"is a {kind} file, not a result or sweep file")


def _read_sweep(path: Path) -> tuple[np.ndarray, dict[str, np.ndarray], str]:
    from ..core.files import open_ours

    with open_ours(path, "sweep") as f:  # checksum verified: a damaged file is not drawn
        study = json.loads(f.attrs["study"]) if "study" in f.attrs else {}
        if int(f.attrs["format_version"]) >= 3:  # drift over (monitor, member, time)
            monitors = json.loads(f.attrs["order"])["drift"]
            drift = np.asarray(f["drift"][()], dtype=np.float64)
            series = {name: drift[i] for i, name in enumerate(monitors)}
            times = f["time"]
        else:
            series = {name: np.asarray(d[()], dtype=np.float64) for name, d in f["drift"].items()}
            times = f["t"]
        t = np.asarray(times[()], dtype=np.float64)  # decimal text beyond double
    if not series:
        raise PlotError("the sweep recorded no drift (its scene conserves no monitor)")
    return t, series, study.get("title") or f"sweep {path.name}"


# ------------------------------------------------------------------ helpers
