"""The work–precision figure of a case: error against wall time, one line per method."""

from __future__ import annotations

import math
from pathlib import Path

from bench_common import Curve

from .records import Case


def plot(case: Case, cs: list[Curve], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.6))
    for c in cs:
        # In sweep order (tolerance tightening): where round-off takes over, the error turns
        # back, and the line shows it.
        pts = [(e, t) for e, t in zip(c.errors, c.times, strict=True) if e > 0 and math.isfinite(t)]
        if not pts:
            continue
        style = "-o" if c.method.startswith("ours") else "--s"
        ax.loglog([p[0] for p in pts], [p[1] * 1e3 for p in pts], style, ms=4, label=c.method)
    ax.set_xlabel("error at the final time")
    ax.set_ylabel("wall time (ms)")
    ax.set_title(f"work–precision: {case.name}")
    ax.invert_xaxis()
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="best")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
