"""The figures: errors against time per case, crossing times, ensemble RMS (PNG)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from rotation_cases import BY_NAME, EPSILON

from .laws import REQUIREMENTS

COLORS = {"double": "tab:blue", "quad": "tab:orange", "real256": "tab:green"}


def plot_case(name: str, jobs: list[dict[str, Any]], out: Path) -> None:
    """Error against time, log-log, every precision, with each law's tolerance dashed."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(15, 4.2), constrained_layout=True)
    panels = [
        ("rates error / |ω₀|", lambda j: j["errors"]["state"], "tol_state"),
        ("attitude error (quaternion)", lambda j: j["errors"]["attitude"], "tol_attitude"),
        ("|relative drift|: energy (—), |L|² (··)", lambda j: j["drifts"]["energy"], None),
    ]
    for ax, (title, get, tol_key) in zip(axes, panels, strict=True):
        for job in jobs:
            t, color = job["t"], COLORS[job["precision"]]
            keep = t > 0
            y = np.abs(get(job))[keep]
            ax.loglog(t[keep], np.where(y > 0, y, np.nan), color=color, label=job["precision"])
            if tol_key:
                ax.loglog(t[keep], job[tol_key][keep], "--", color=color, lw=0.8)
            else:
                d2 = job["drifts"]["momentum_squared"][keep]
                ax.loglog(t[keep], np.where(d2 > 0, d2, np.nan), ":", color=color)
                ax.loglog(t[keep], job["tol_conserved"][keep], "--", color=color, lw=0.8)
        ax.set_title(title)
        ax.set_xlabel("t")
        ax.grid(True, which="major", alpha=0.3)
    axes[0].legend(title="dashed: law tolerance", fontsize=8)
    case = BY_NAME[name]
    fig.suptitle(f"{name}: {case.title}")
    fig.savefig(out, dpi=90)
    plt.close(fig)


def plot_crossings(jobs: list[dict[str, Any]], out: Path) -> None:
    """|Δt|/t of every matched crossing, double precision, one series per case."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 4.5), constrained_layout=True)
    for job in jobs:
        if job["precision"] != "double" or not len(job["crossings"]["t"]):
            continue
        c = job["crossings"]
        ax.loglog(c["t"], np.maximum(c["abs"] / c["t"], 1e-18), ".", ms=3, label=job["case"])
    ax.axhline(REQUIREMENTS["double_generic_crossings"], color="k", ls="--", lw=0.8)
    ax.set_xlabel("crossing time t")
    ax.set_ylabel("|Δt| / t  (zeros drawn at 1e-18)")
    ax.set_title("invariable-plane crossings, double: heyoka events vs closed form")
    ax.legend(fontsize=7, ncol=2)
    fig.savefig(out, dpi=90)
    plt.close(fig)


def plot_ensembles(fits: dict[tuple, dict], out: Path) -> None:
    """RMS error of each ensemble against the step count, with n^{1/2} and n^{3/2} guides."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cols = min(3, len(fits))
    rows = -(-len(fits) // cols)
    fig, axes = plt.subplots(
        rows, cols, figsize=(5.5 * cols, 4.2 * rows), constrained_layout=True, squeeze=False
    )
    for ax in axes.ravel()[len(fits) :]:
        ax.set_visible(False)
    for ax, ((name, prec, periods), f) in zip(axes.ravel(), fits.items(), strict=False):
        n, keep = f["n"], f["n"] > 0
        for k, style in (
            ("state", "-"),
            ("attitude", "-"),
            ("energy", ":"),
            ("momentum_squared", ":"),
        ):
            y = f["rms"][k][keep]
            ax.loglog(
                n[keep], np.where(y > 0, y, np.nan), style, label=f"{k} ({f['slope'][k]:.2f})"
            )
        eps = EPSILON[prec]
        ax.loglog(n[keep], eps * n[keep] ** 1.5, "k--", lw=0.7, label="ε n^{3/2}")
        ax.loglog(n[keep], eps * n[keep] ** 0.5, "k-.", lw=0.7, label="ε n^{1/2}")
        ax.set_title(f"{name}, {prec}, {periods:g} periods, {f['members']} runs (RMS)")
        ax.set_xlabel("steps n")
        ax.legend(fontsize=7)
        ax.grid(True, alpha=0.3)
    fig.savefig(out, dpi=90)
    plt.close(fig)
