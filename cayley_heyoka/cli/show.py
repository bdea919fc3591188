"""What the commands print: a run's summary and a progress bar of simulated time."""

from __future__ import annotations

import sys
from collections.abc import Iterable
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ..core.result import Result


def time_bar(t0: float, t1: float, desc: str | None = None, file: Any = None) -> Any:
    """A progress bar of simulated time on stderr: ``t = 3141.59 of 6283.19  50%``.

    ``update_to(t)`` moves it to time ``t``; times are shown to six significant digits (the
    bar's own counter, t − t0, would print every digit of a float).
    """
    from tqdm import tqdm

    class Bar(tqdm):
        @property
        def format_dict(self) -> dict:
            d = super().format_dict
            d["t_now"], d["t_end"] = f"{t0 + d['n']:.6g}", f"{t1:.6g}"
            return d

        def update_to(self, t: float) -> None:
            self.n = min(max(float(t) - t0, 0.0), self.total)
            self.refresh() if self.n >= self.total else self.update(0)

    label = f"{desc}: " if desc else ""
    return Bar(
        total=t1 - t0,
        file=file or sys.stderr,
        mininterval=0.2,
        dynamic_ncols=True,
        bar_format=label + "t = {t_now} of {t_end} {percentage:4.0f}%|{bar}| {elapsed}<{remaining}",
    )


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
        lines.append("  monitors      final relative drift (conserved) or largest value:")
        for name, arr in result.monitors.items():
            if name in result.conserved and len(arr):
                d = float(np.max(np.abs(result.drift(name)[-1])))
                lines.append(f"    {name:<20} {d:.3e}")
            elif len(arr):
                lines.append(f"    {name:<20} largest |value| {_sci(np.max(np.abs(arr)))}")
    for name, log in result.events.items():
        labels, counts = np.unique(log.label, return_counts=True)
        detail = ", ".join(f"{lab}: {c}" for lab, c in zip(labels, counts, strict=True))
        lines.append(f"  event {name:<12} {len(log)} occurrences ({detail or 'none'})")
    return "\n".join(lines)


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
        text = family.variables(scene, name) if family.variables is not None else None
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
