"""What the commands print: a run's summary and a progress bar of simulated time."""

from __future__ import annotations

import math
import sys
from collections.abc import Iterable
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ..core.result import Result


def time_bar(t0: Any, t1: Any, desc: str | None = None, file: Any = None) -> Any:
    """A progress bar of simulated time on stderr: ``t = 3141.59 of 6283.19  50%``.

    ``t0`` and ``t1`` are the first and last output times of the scene's checked grid
    (:attr:`~cayley_heyoka.core.scene.Scene.time_grid`), in the run's precision: a float, a
    heyoka ``real128`` or ``real``. ``update_to(t)`` moves the bar to time ``t`` (any of
    those types). The bar counts the fraction of the span done, computed on halves in the
    times' own type: ``t1 - t0`` overflows a double for ``[-1e308, 1e308]``, and a quad span
    beyond double's range has no float at all. Times are shown with six significant digits,
    or as many more as tell ``t0`` from ``t1`` (``[1e15, 1e15 + 1e-3]``), up to the
    precision's own.
    """
    from tqdm import tqdm

    span = _Span(t0, t1)

    class Bar(tqdm):
        t: Any = t0

        @property
        def format_dict(self) -> dict:
            d = super().format_dict
            d["t_now"], d["t_end"] = span.text(self.t), span.text(t1)
            return d

        def update_to(self, t: Any) -> None:
            self.t = t
            self.n = span.fraction(t)
            self.refresh() if self.n >= self.total else self.update(0)

    label = f"{desc}: " if desc else ""
    return Bar(
        total=1.0,
        file=file or sys.stderr,
        mininterval=0.2,
        dynamic_ncols=True,
        bar_format=label + "t = {t_now} of {t_end} {percentage:4.0f}%|{bar}| {elapsed}<{remaining}",
    )


class _Span:
    """The fraction of ``[t0, t1]`` reached, and times as text, in any precision."""

    def __init__(self, t0: Any, t1: Any) -> None:
        import mpmath

        self.mpmath = mpmath  # held: a bar closed at exit draws after imports are torn down
        self.t0 = t0
        # Halves: finite for any two finite numbers of the type, where t1 - t0 may overflow.
        self.half = t1 / 2 - t0 / 2
        self.empty = not self.half > 0
        bits = 113 if type(t0).__name__ == "real128" else int(getattr(t0, "prec", 53))
        self.most = int(bits * 0.30103) + 2  # the digits that round-trip the precision
        self.bits = bits + 64
        with mpmath.workprec(self.bits):
            a, b = _mpf(t0), _mpf(t1)
            width = b - a
            large = max(abs(a), abs(b))
            extra = 0 if self.empty or large == 0 else int(mpmath.log10(large / width))
        self.digits = max(6, min(self.most, 6 + extra))

    def fraction(self, t: Any) -> float:
        """``(t - t0) / (t1 - t0)`` in [0, 1] (0 for a NaN, 1 at or past ``t1`` of an empty
        span)."""
        if self.empty:
            return 1.0 if t >= self.t0 else 0.0
        try:
            f = float((t / 2 - self.t0 / 2) / self.half)
        except (ArithmeticError, TypeError, ValueError):
            return 0.0
        return min(max(f, 0.0), 1.0) if f == f else 0.0

    def text(self, t: Any) -> str:
        if isinstance(t, float) and math.isfinite(t):
            return f"{t:.{self.digits}g}"
        with self.mpmath.workprec(self.bits):
            return self.mpmath.nstr(_mpf(t), self.digits, min_fixed=-4, max_fixed=self.digits)


def _mpf(value: Any) -> Any:
    """A float, real128 or real as mpmath reads its decimal text (which round-trips)."""
    import mpmath

    return mpmath.mpf(repr(float(value)) if isinstance(value, float) else str(value))


def summary(result: Result) -> str:
    """A one-screen account of a run: counts, timing, drifts, events."""
    import numpy as np

    meta, counters = result.metadata, result.counters
    title = result.scene.get("title") or "(untitled scene)"
    lines = [title, ""]
    status = "completed" if result.success else "STOPPED EARLY"
    t_last = f"{float(result.t[-1]):.6g}" if len(result.t) else "-"
    lines.append(f"  status        {status}: {result.message}")
    if meta.get("tolerance") is None and meta.get("order") is None:
        # A closed form's values (cayley-heyoka reference): no integrator made them.
        lines.append(f"  precision     {result.precision.name}, no integration")
    else:
        lines.append(
            f"  precision     {result.precision.name}, tolerance {meta.get('tolerance')}, "
            f"order {meta.get('order')}"
        )
    lines.append(f"  outputs       {len(result.t)} times, last t = {t_last}")
    for name, value in counters.items():
        lines.append(f"  {name:<13} {value}")
    ref = meta.get("reference")
    if ref and ref.get("attempts"):
        last = ref["attempts"][-1]
        verdict = "certified" if ref["certified"] else "NOT certified"
        lines.append(
            f"  reference     {verdict} to {ref['digits']} digits: largest scaled error "
            f"{last['scaled_error']:.2e} against {last['compared_with']}"
        )
    wall = meta.get("wall_seconds", float("nan"))
    compile_s = meta.get("compile_seconds", 0.0)
    cached = " (compiled code from cache)" if meta.get("compiled_from_cache") else ""
    lines.append(f"  wall time     {wall:.3f} s, of which compiling {compile_s:.3f} s{cached}")
    steps = counters.get("steps", 0)
    if steps and wall - compile_s > 0:
        lines.append(f"  throughput    {steps / (wall - compile_s):,.0f} steps/s (incl. recording)")
    if result.monitors:
        lines.append(
            "  monitors      largest relative drift (conserved) and when, or largest value:"
        )
        for name, arr in result.monitors.items():
            if name in result.conserved and len(arr):
                lines.append(f"    {name:<20} {_drift_line(result, name)}")
            elif len(arr):
                lines.append(f"    {name:<20} largest |value| {_sci(np.max(np.abs(arr)))}")
    for name, log in result.events.items():
        labels, counts = np.unique(log.label, return_counts=True)
        detail = ", ".join(f"{lab}: {c}" for lab, c in zip(labels, counts, strict=True))
        lines.append(f"  event {name:<12} {len(log)} occurrences ({detail or 'none'})")
    return "\n".join(lines)


def _drift_line(result: Result, name: str) -> str:
    """A conserved monitor's largest drift, when it occurred and the final one: a run whose
    drift peaked midway ends lower than its worst."""
    import numpy as np

    value, at = result.largest_drift(name)
    if at is None:
        return "not finite at any output time"
    final = float(np.max(np.abs(np.asarray(result.drift(name)[-1], dtype=float))))
    if value == 0.0:
        return "0 (the same value, to the last bit, at every output time)"
    return f"{value:.3e} at t = {float(at):.6g} (final {final:.3e})"


def variable_lines(scene: dict[str, Any], names: Iterable[str]) -> list[str]:
    """What each of ``names`` (a result's variables and monitors, a sweep's) is in
    ``scene``'s family's words (``Family.variables``; the record loads without heyoka)."""
    from ..core.errors import SceneError
    from ..core.families import FAMILIES, family_of

    try:
        family = FAMILIES[family_of(scene)]
    except SceneError as exc:  # a family of another package, not installed here
        return [f"  variables     not described: {exc.constraint}"]
    lines = ["  variables     what each output and monitor is:"]
    for name in names:
        try:
            text = family.variables(scene, name) if family.variables is not None else None
        except SceneError as exc:  # a family of another package failing to say
            text = f"(not described: {exc.constraint})"
        lines.append(
            f"    {name:<20} {text or '(not described by the ' + family.name + ' family)'}"
        )
    return lines


def _sci(value: Any) -> str:
    """``value`` to four digits; a quad or MPFR number beyond double's range is not 'inf'."""
    import math

    if math.isfinite(x := float(value)):
        return f"{x:.3e}"
    import mpmath

    from ..core.exact import exact

    return mpmath.nstr(exact(value), 4, min_fixed=0, max_fixed=0)
