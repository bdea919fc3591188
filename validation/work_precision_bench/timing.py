"""Timing: the least of a few calls, and the progress log."""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any

REPEAT, BUDGET = 5, 1.0  # timing: least of up to REPEAT calls, fewer once a call exceeds BUDGET s


def log(msg: str) -> None:
    print(f"  [work_precision] {msg}", flush=True)


def least_time(fn: Callable[[], Any], repeat: int | None = None) -> tuple[float, Any]:
    best, out = math.inf, None
    for _ in range(repeat or REPEAT):
        s = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - s)
        if best > BUDGET:
            break
    return best, out
