"""Shared pieces of the benchmark scripts (validation/benchmarks.py drives them).

Benchmarks print figures; they never judge wall time. Every ratio is measured side by side in
one process, on the same machine state, because these machines are noisy.
"""

from __future__ import annotations

import importlib.util
import math
import platform
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np


def available(module: str) -> bool:
    """Whether an optional peer (scipy, rebound, reboundx, …) can be imported."""
    return importlib.util.find_spec(module) is not None


def wall(fn: Callable[[], Any], repeat: int = 3, budget: float = 2.0) -> tuple[float, Any]:
    """Smallest wall time of up to ``repeat`` calls (fewer if one call exceeds ``budget`` s),
    and the last call's result. The minimum is the least disturbed measurement."""
    best, result = math.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        result = fn()
        elapsed = time.perf_counter() - t0
        best = min(best, elapsed)
        if elapsed > budget:
            break
    return best, result


@dataclass
class Curve:
    """A work–precision curve: one method's (wall time, error) over a tolerance sweep."""

    method: str
    times: list[float]
    errors: list[float]
    settings: list[str]

    def time_at(self, error: float) -> float:
        """Wall time this method needs for ``error``, interpolated in log–log between the
        sweep's points (NaN outside the range it reached)."""
        pts = sorted(
            (e, t)
            for e, t in zip(self.errors, self.times, strict=True)
            if e > 0 and math.isfinite(e) and math.isfinite(t)
        )
        if not pts or error < pts[0][0] or error > pts[-1][0]:
            return math.nan
        # The cheapest time reaching at least this accuracy (curves need not be monotone):
        # sorted by error, the running minimum from the most accurate point on.
        le, lt = np.log([p[0] for p in pts]), np.log([p[1] for p in pts])
        lt = np.minimum.accumulate(lt)
        return float(np.exp(np.interp(math.log(error), le, lt)))


def ratios_at_equal_error(
    curves: Sequence[Curve], reference: str, levels: Sequence[float]
) -> list[dict[str, Any]]:
    """For each error level: every method's time divided by ``reference``'s time there."""
    ref = next(c for c in curves if c.method == reference)
    rows = []
    for level in levels:
        base = ref.time_at(level)
        row: dict[str, Any] = {"error": level}
        for c in curves:
            t = c.time_at(level)
            row[c.method] = t / base if math.isfinite(t) and math.isfinite(base) else math.nan
        rows.append(row)
    return rows


def machine() -> str:
    import heyoka as hy

    versions = [f"heyoka {hy.__version__}", f"numpy {np.__version__}"]
    for name in ("scipy", "rebound", "reboundx", "mpmath"):
        if available(name):
            mod = importlib.import_module(name)
            versions.append(f"{name} {getattr(mod, '__version__', '?')}")
    return f"{platform.platform()}, Python {platform.python_version()}; " + ", ".join(versions)


def fmt(x: float, digits: int = 2) -> str:
    """A number for a table: 3 significant figures, '–' for NaN."""
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "–"
    return f"{x:.{digits}e}" if abs(x) < 1e-2 or abs(x) >= 1e4 else f"{x:.{digits + 1}g}"
