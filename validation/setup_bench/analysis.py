"""The compact-mode threshold read from the compile sweep: per family, where a cold non-compact
compile reaches :data:`.cases.PATIENCE` and how the step costs compare; pooled, the power-law
fit of the compile time against the scene's size (Markdown lines)."""

from __future__ import annotations

import math

import numpy as np

from .cases import FAMILIES_BY_SIZE, PATIENCE
from .results import Point


def _crossing(xs: list[float], ys: list[float], level: float) -> float | None:
    """First x (log–log interpolation) where y reaches ``level`` from below; None if never."""
    for i in range(1, len(xs)):
        if ys[i - 1] < level <= ys[i]:
            f = (math.log(level) - math.log(ys[i - 1])) / (math.log(ys[i]) - math.log(ys[i - 1]))
            return math.exp(math.log(xs[i - 1]) + f * (math.log(xs[i]) - math.log(xs[i - 1])))
    if ys and ys[0] >= level:
        return xs[0]
    return None


def span(values: list[float]) -> str:
    """The least and largest value to two decimals (one number when they print alike)."""
    lo, hi = min(values), max(values)
    return f"{lo:.2f}" if f"{lo:.2f}" == f"{hi:.2f}" else f"{lo:.2f}–{hi:.2f}"


def _fit(xs: list[float], ys: list[float]) -> tuple[float, float, float]:
    """Least squares log y = a + b log x: (a, b, scatter factor exp(rms residual))."""
    lx, ly = np.log(xs), np.log(ys)
    b, a = np.polyfit(lx, ly, 1)
    return float(a), float(b), float(np.exp(np.std(ly - (a + b * lx))))


def threshold_analysis(points: list[Point]) -> tuple[list[str], float | None]:
    """Per family: the size where a cold non-compact compile reaches PATIENCE and how the step
    costs compare; pooled over the families, the power-law fit of the compile time against
    ``Model.size()`` (and against the decomposition's length), whose PATIENCE crossing is the
    recommended threshold."""
    lines = []
    for fam in FAMILIES_BY_SIZE:
        pts = sorted((p for p in points if p.family == fam.label), key=lambda p: p.size)
        if not pts:
            continue
        sizes = [float(p.size) for p in pts]
        at = _crossing(sizes, [p.cpu[False] for p in pts], PATIENCE)
        even = next((p.size for p in pts if p.ratio <= 1.0), None)
        longest = max(p.cpu[False] for p in pts)
        wait = (
            f"takes {PATIENCE:.0f} s at ≈ {at / 1e3:.0f} kB"
            if at is not None
            else f"stays under {PATIENCE:.0f} s up to {sizes[-1] / 1e3:.0f} kB ({longest:.1f} s)"
        )
        ratios = [p.ratio for p in pts]
        steps = f"compact steps cost {span(ratios)}× the non-compact ones"
        if even is not None:
            steps += f" (no more than them from {even / 1e3:.0f} kB)"
        lines.append(f"* {fam.label}: a cold non-compact compile {wait}; {steps}.")
    distinct = {p.size for p in points}
    if len(distinct) < 3:
        return lines, None
    slow = [p.cpu[False] for p in points]
    a, b, scatter = _fit([p.size for p in points], slow)
    ad, bd, scatter_d = _fit([p.decomposition for p in points], slow)
    at = math.exp((math.log(PATIENCE) - a) / b)
    text = (
        f"Pooled over the families, a cold non-compact compile grows like size^{b:.2f} "
        f"(scattered by a factor {scatter:.2f} about the fit) and reaches {PATIENCE:.0f} s at "
        f"≈ {at / 1e3:.0f} kB; against the decomposition's length it grows like n^{bd:.2f} "
        f"(scatter {scatter_d:.2f}) and reaches {PATIENCE:.0f} s at "
        f"≈ {math.exp((math.log(PATIENCE) - ad) / bd):.0f} operations."
    )
    if max(slow) < PATIENCE:
        # The crossing would be an extrapolation beyond every measured compile.
        text += f" No measured compile reached {PATIENCE:.0f} s: no threshold is derived."
        return [*lines, "", text], None
    return [*lines, "", text], at
