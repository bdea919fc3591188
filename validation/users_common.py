"""Side-by-side timing of what users run against raw heyoka (validation/bench_users.py).

Each ``users_<topic>.py`` module exposes ``rows(quick: bool) -> list[Row]``: one row per path a
user runs (a whole ``run()``, a sweep, a reference, the command line's start), timed
interleaved with its floor — the same work written directly against heyoka — in one process,
so that the ratio holds on a noisy machine. A row reports the median ratio and its spread over
the repeats; it judges nothing (the target is printed beside it).
"""

from __future__ import annotations

import gc
import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass, field


@dataclass
class Row:
    """One path a user runs, measured against its floor.

    Attributes
    ----------
    what
        What the user runs, in words.
    ratios
        ours ÷ floor, one per repeat (each pair timed back to back).
    target
        The ratio this path should not exceed (None: reported, not judged).
    floor
        What the floor is, in words.
    note
        Anything the reader needs to weigh the figure (sizes, steps, errors reached).
    """

    what: str
    ratios: list[float]
    target: float | None
    floor: str
    note: str = ""
    seconds: dict[str, float] = field(default_factory=dict)

    @property
    def median(self) -> float:
        return statistics.median(self.ratios)

    @property
    def spread(self) -> tuple[float, float]:
        return min(self.ratios), max(self.ratios)

    @property
    def met(self) -> bool | None:
        """Whether the median meets the target (None: a row reported, not judged)."""
        return None if self.target is None else self.median <= self.target


#: Rows a script could not measure on this machine, and why (said under the section's table,
#: so that a missing row is never mistaken for one removed).
SKIPPED: list[str] = []


def interleaved(
    ours: Callable[[], object],
    floor: Callable[[], object],
    repeats: int = 7,
    inner: int = 1,
) -> tuple[list[float], float, float]:
    """Time ``ours`` and ``floor`` alternately ``repeats`` times (each call ``inner`` times).

    Returns the per-repeat ratios ours ÷ floor and the least wall time of each (seconds per
    call). The order alternates between repeats so that neither always runs first.
    """
    ours(), floor()  # warm caches on both sides
    ratios, best_o, best_f = [], float("inf"), float("inf")
    for k in range(repeats):
        pair = []
        for fn in (ours, floor) if k % 2 == 0 else (floor, ours):
            gc.collect()
            t0 = time.perf_counter()
            for _ in range(inner):
                fn()
            pair.append(((time.perf_counter() - t0) / inner, fn is ours))
        o = next(t for t, is_ours in pair if is_ours)
        f = next(t for t, is_ours in pair if not is_ours)
        ratios.append(o / f)
        best_o, best_f = min(best_o, o), min(best_f, f)
    return ratios, best_o, best_f


def table(rows: list[Row]) -> str:
    """The Markdown table of ``rows``."""
    lines = [
        "| what a user runs | floor | ours ÷ floor: median (min–max) | target | met | note |",
        "|---|---|---|---|---|---|",
    ]
    for r in rows:
        lo, hi = r.spread
        target = "–" if r.target is None else f"≤ {r.target:g}"
        met = {None: "–", True: "yes", False: "**no**"}[r.met]
        lines.append(
            f"| {r.what} | {r.floor} | {r.median:.2f} ({lo:.2f}–{hi:.2f}) | {target} | "
            f"{met} | {r.note} |"
        )
    return "\n".join(lines)


def main(
    rows: Callable[[bool], list[Row]], description: str, quick: str, argv: list[str] | None
) -> int:
    """A users script's command line: ``--quick`` (what ``quick`` says it is), then its table."""
    import argparse

    import heyoka as hy

    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--quick", action="store_true", help=quick)
    args = parser.parse_args(argv)
    print(f"heyoka {hy.__version__}")
    print(table(rows(args.quick)))
    return 0
