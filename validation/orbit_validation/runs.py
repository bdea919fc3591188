"""One integration and its outputs: the run, its steps, its columns as exact mpf values."""

from __future__ import annotations

import time
from typing import Any

import mpmath
import numpy as np

import cayley_heyoka as ch

from .tolerances import DPS


def to_mpf(x: Any) -> mpmath.mpf:
    """A double, real128 or real as an exact mpf (text round-trips the extended types)."""
    if isinstance(x, float | np.floating | int):
        return mpmath.mpf(float(x))
    return mpmath.mpf(str(x))


def output_times(period: float, t_end: float, count: int) -> list[float]:
    """0 and ``count`` log-spaced binary64 times from P/4 to t_end (exact in every type)."""
    t = np.geomspace(period / 4, t_end, count)
    return [0.0, *sorted({float(x) for x in t})]


def integrate(data: dict) -> tuple[ch.Result, np.ndarray, float]:
    """Run a scene; the result, the time reached after each step, and the run's seconds
    without compilation."""
    steps: list[float] = []
    t0 = time.perf_counter()
    result = ch.run(ch.Scene.from_dict(data), progress=lambda t: steps.append(float(t)))
    seconds = time.perf_counter() - t0 - result.metadata.get("compile_seconds", 0.0)
    return result, np.asarray(steps), seconds


def steps_at(steps: np.ndarray, t: np.ndarray) -> np.ndarray:
    return np.searchsorted(steps, t, side="right").astype(float)


def columns(result: ch.Result, names: tuple[str, ...]) -> dict[str, list[mpmath.mpf]]:
    """Output columns as exact mpf lists (picklable; comparisons at DPS digits)."""
    with mpmath.workdps(DPS):
        return {k: [to_mpf(x) for x in result[k]] for k in names if k in result.variables}


def angle_difference(a: mpmath.mpf, b: mpmath.mpf) -> mpmath.mpf:
    """a − b reduced into (−π, π]."""
    d = a - b
    two_pi = 2 * mpmath.pi
    return d - two_pi * mpmath.floor((d + mpmath.pi) / two_pi)
