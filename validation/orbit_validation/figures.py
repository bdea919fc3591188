"""The PNG plots of the orbit section (matplotlib, Agg backend)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from orbit_cases import EPSILON, FORMULATIONS, LONG_BY_NAME

STYLE = {"cayley": "tab:blue", "quaternion": "tab:orange", "cartesian": "tab:green"}


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_long(case_name: str, rows: list[dict[str, Any]], out: Path) -> None:
    """Position error/a against time, log-log, one panel per precision of the run."""
    plt = _plt()
    fig, axes = plt.subplots(1, 2, figsize=(13, 4.5), constrained_layout=True)
    for ax, prec in zip(axes, ("double", "quad"), strict=True):
        for r in rows:
            if r["run"][1] != prec:
                continue
            f, against = r["run"][0], r["against"]
            same = against[1] == prec
            keep = r["t"] > 0
            y = np.where(r["err"][keep] > 0, r["err"][keep], np.nan)
            label = f"{f} vs {against[0]} {against[1]}"
            ax.loglog(r["t"][keep], y, "-" if same else "--", color=STYLE[f], label=label)
            if not same and f == "cartesian":
                ax.loglog(r["t"][keep], r["tol"][keep], "k:", lw=0.8, label="law tolerance")
        ax.set_title(f"{case_name}, {prec} runs")
        ax.set_xlabel("t")
        ax.set_ylabel("|Δx| / a")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle(f"{case_name}: {LONG_BY_NAME[case_name].title}", fontsize=9)
    fig.savefig(out, dpi=90)
    plt.close(fig)


def plot_inclination(jobs: list[dict[str, Any]], out: Path) -> None:
    plt = _plt()
    inc = np.array([float(j["inclination"]) for j in jobs])
    fig, axes = plt.subplots(1, 2, figsize=(13, 4.5), constrained_layout=True)
    for f in FORMULATIONS:
        axes[0].loglog(
            inc, [j["runs"][f]["max"]["position"] for j in jobs], "o-", color=STYLE[f], label=f
        )
    axes[0].set_title("max |Δx|/a over the run, double vs real128 reference")
    for f, marker in (("cayley", "o"), ("quaternion", "s")):
        for k, ls in (("Theta", "-"), ("Sigma", "--"), ("Phi", ":"), ("Theta-Sigma", "-.")):
            y = np.array([j["runs"][f]["max"][k] for j in jobs])
            axes[1].loglog(
                inc, np.maximum(y, 1e-30), marker + ls, color=STYLE[f], ms=3, label=f"{f} {k}"
            )
    axes[1].loglog(inc, EPSILON["double"] / inc, "k:", lw=0.8, label="ε / i")
    axes[1].set_title("max angle error (rad); zeros drawn at 1e-30")
    for ax in axes:
        ax.set_xlabel("inclination i (rad)")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    fig.savefig(out, dpi=90)
    plt.close(fig)


def plot_eccentricity(jobs: list[dict[str, Any]], out: Path) -> None:
    plt = _plt()
    e = np.array([float(j["e"]) for j in jobs])
    fig, axes = plt.subplots(1, 2, figsize=(13, 4.5), constrained_layout=True)
    for f in FORMULATIONS:
        axes[0].semilogy(e, [j["runs"][f]["max"] for j in jobs], "o-", color=STYLE[f], label=f)
        axes[1].semilogy(
            e, [j["runs"][f]["steps"] / j["orbits"] for j in jobs], "o-", color=STYLE[f], label=f
        )
    axes[1].semilogy(
        e, [j["reference_steps"] / j["orbits"] for j in jobs], "k--", label="real128 cartesian"
    )
    axes[0].set_title("max |Δx|/a, double vs real128 cartesian")
    axes[1].set_title("steps per orbit")
    for ax in axes:
        ax.set_xlabel("eccentricity e")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    fig.savefig(out, dpi=90)
    plt.close(fig)
