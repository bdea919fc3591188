"""The two figures: the long run's position and energy errors, and the ensemble's median
running maximum of the energy error; and how each method is drawn and named."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np

from .case import PERIOD
from .results import Run

STYLES = {
    "IAS15 (REBOUND)": ("k", "-", 2.2),
    "ours, cartesian": ("tab:blue", "-", 1.2),
    "ours, cayley": ("tab:orange", "-", 1.2),
    "ours, quaternion": ("tab:olive", "-", 1.0),
    "prototype: compensated state": ("tab:purple", "--", 1.4),
    "prototype: extended precision": ("tab:green", "--", 1.4),
    "ours, encke": ("tab:red", "-", 1.6),
}


def short_label(r: Run) -> str:
    """'IAS15', 'cartesian, tol ε', 'Encke, tol 1e-18', … for legends."""
    if r.group == "ias15":
        return "IAS15"
    name = r.method.replace("prototype: ", "").replace("ours, ", "")
    tol = re.search(r"tol [^,(]+", r.settings)
    return f"{name}, {tol.group(0).strip()}" if tol else name


def plot(long: dict[str, Any], ens: dict[str, Any], figures: Path) -> list[str]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    orbits = long["times"][1:] / PERIOD
    seen: dict[str, int] = {}
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8))
    for r in long["runs"]:
        if r.group == "diagnostic" or "high_accuracy" in r.settings:
            continue
        color, ls, lw = STYLES.get(r.method, ("gray", ":", 1.0))
        k = seen[r.method] = seen.get(r.method, -1) + 1
        kw = {"color": color, "ls": ls if k == 0 else ":", "lw": lw}
        label = short_label(r)
        axes[0].loglog(orbits, np.maximum(r.pos_err[1:], 1e-18), label=label, **kw)
        axes[1].loglog(orbits, np.maximum(r.energy_err[1:], 1e-20), **kw)
    axes[0].loglog(
        orbits,
        np.maximum(long["ref"].check[1:], 1e-18),
        color="gray",
        ls=":",
        lw=0.8,
        label="real128 at 1e-20 (reference check)",
    )
    axes[0].set_ylabel("|Δx| / a")
    axes[1].set_ylabel("|ΔE / E|")
    for ax in axes:
        ax.set_xlabel("orbits")
        ax.grid(True, which="major", alpha=0.3)
    axes[0].legend(fontsize=7, loc="upper left")
    axes[0].set_title("position error against real128 (one orbit)")
    axes[1].set_title("energy error, each method's own state in long double")
    fig.tight_layout()
    names = ["bench_ias15_errors.png"]
    fig.savefig(figures / names[0], dpi=110)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(6.5, 4.6))
    o = ens["times"][1:] / PERIOD
    for key, s in ens["stats"].items():
        r = s["run"]
        color, ls, lw = STYLES.get(r.method, ("gray", ":", 1.0))
        if key in ("cartesian ha", "compensated acc"):
            ls = ":"
        ax.loglog(
            o,
            np.maximum(s["median_env"][1:], 1e-20),
            color=color,
            ls=ls,
            lw=lw,
            label=ENSEMBLE_LABELS.get(key, key),
        )
    ax.set_xlabel("orbits")
    ax.set_ylabel("median over the ensemble of max |ΔE/E| so far")
    ax.set_title(f"energy, {ens['members']} starting mean anomalies")
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    names.append("bench_ias15_ensemble.png")
    fig.savefig(figures / names[1], dpi=110)
    plt.close(fig)
    return names


ENSEMBLE_LABELS = {
    "ias15": "IAS15",
    "cartesian": "ours, cartesian",
    "cartesian ha": "ours, cartesian, high_accuracy",
    "cayley": "ours, cayley",
    "quaternion": "ours, quaternion",
    "compensated": "compensated state (Python)",
    "compensated acc": "compensated state + long double acceleration",
    "extended": "extended precision, tol 2⁻⁵²",
    "encke": "ours, encke",
}
