"""The two figures of the set-up section: compile time and step cost against scene size,
ensemble throughput against the number of members (PNG; False when matplotlib is missing)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from cayley_heyoka.core import compiler

from .cases import FAMILIES_BY_SIZE, PATIENCE
from .results import Point, Throughput


def plot_compile(points: list[Point], path: Path) -> bool:
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return False
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.2))
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for fam, colour in zip(FAMILIES_BY_SIZE, colours, strict=False):
        pts = sorted((p for p in points if p.family == fam.label), key=lambda p: p.size)
        if not pts:
            continue
        s = [p.size / 1e3 for p in pts]
        ax.loglog(s, [p.cpu[False] for p in pts], "o-", color=colour, label=fam.label)
        ax.loglog(s, [p.cpu[True] for p in pts], "o--", color=colour, mfc="none")
        bx.semilogx(s, [p.ratio for p in pts], "o-", color=colour, label=fam.label)
    for a in (ax, bx):
        a.axvline(compiler.COMPACT_THRESHOLD / 1e3, color="grey", lw=0.8, ls=":")
        a.set_xlabel("Model.size() (kB of pickled right-hand sides)")
        a.grid(True, which="both", alpha=0.3)
    ax.axhline(PATIENCE, color="grey", lw=0.8)
    ax.set_ylabel("cold compile, CPU s: solid non-compact, dashed compact")
    ax.legend(fontsize=7)
    bx.axhline(1.0, color="grey", lw=0.8)
    bx.set_ylabel("step cost, compact / non-compact")
    fig.suptitle("Compile time and step cost against scene size (dotted: current threshold)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return True


def plot_ensembles(results: dict[str, list[Throughput]], path: Path) -> bool:
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return False
    fig, axes = plt.subplots(1, len(results), figsize=(11, 4.2), sharey=True)
    for ax, (label, rows) in zip(np.atleast_1d(axes), results.items(), strict=True):
        methods = list(dict.fromkeys(r.method for r in rows))
        for method in methods:
            pts = sorted((r for r in rows if r.method == method), key=lambda r: r.n)
            meas = [(r.n, r.rate) for r in pts if r.measured]
            line = ax.loglog(*zip(*meas, strict=True), "o-", label=method)[0] if meas else None
            extra = [(r.n, r.rate) for r in pts if not r.measured and math.isfinite(r.rate)]
            if extra and meas:
                xs, ys = zip(*([meas[-1], *extra]), strict=True)
                ax.loglog(xs, ys, "o:", color=line.get_color(), mfc="none")
        ax.set_title(label, fontsize=9)
        ax.set_xlabel("members N")
        ax.grid(True, which="both", alpha=0.3)
    np.atleast_1d(axes)[0].set_ylabel("members per second (hollow: extrapolated)")
    np.atleast_1d(axes)[0].legend(fontsize=6)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return True
