"""One method's trajectory on the grid and what is measured from it: errors against the
reference (|Δx|/a) and the exact initial energy (|ΔE/E|), exponents of their running maxima,
and the least wall time of a few repeats."""

from __future__ import annotations

import dataclasses
import math
import time
from typing import Any

import numpy as np

from .case import LD
from .reference import Reference


@dataclasses.dataclass
class Run:
    """One method's trajectory on the grid and its cost."""

    method: str
    settings: str
    steps: int
    wall: float
    x: np.ndarray  # (3, n)
    energy: np.ndarray  # (n,) long double
    group: str = "ours"  # "ias15", "ours" (scene options), "prototype", "diagnostic"
    extra: dict[str, float] = dataclasses.field(default_factory=dict)
    pos_err: np.ndarray | None = None
    energy_err: np.ndarray | None = None

    def measure(self, ref: Reference | None, e0: Any) -> None:
        if ref is not None:
            d = np.asarray(self.x, dtype=LD) - ref.x[:, : self.x.shape[1]]
            self.pos_err = np.sqrt((d * d).sum(axis=0)).astype(float)  # a = 1
        self.energy_err = np.abs((np.asarray(self.energy, dtype=LD) - e0) / e0).astype(float)

    @property
    def final(self) -> float:
        return float(self.pos_err[-1])

    @property
    def max_energy(self) -> float:
        return float(self.energy_err.max())


def growth(t: np.ndarray, y: np.ndarray) -> float:
    """Slope of log(running max of y) against log t over the last two decades of t."""
    m = (t >= t[-1] / 100) & (t > 0)
    env = np.maximum.accumulate(np.where(np.isfinite(y), y, 0.0))[m]
    ok = env > 0
    if ok.sum() < 3:
        return math.nan
    return float(np.polyfit(np.log(t[m][ok]), np.log(env[ok]), 1)[0])


def least(fn: Any, repeat: int) -> tuple[float, Any]:
    """The least wall time of ``repeat`` calls of ``fn`` and the last call's result."""
    best, out = math.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out
