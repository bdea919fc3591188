"""Validation of the orbit integrators (Cayley 1860): Cayley vs quaternion vs Cartesian.

Run:  python validation/orbit_report.py            (full run; writes the ``orbit`` section of
                                                    validation/REPORT.md and
                                                    validation/figures/orbit_*.png)
      python validation/orbit_report.py --quick    (smoke run: short spans, written to a
                                                    temporary directory unless --out is given)

Four parts (cases in :mod:`orbit_cases`):

1. reference values R1–R4 (:data:`orbit_cases.REFERENCE`): every formulation in double and
   real128 at the cases' time t, every listed quantity;
2. two 1000-orbit problems in double and real128: Cayley and quaternion against the Cartesian
   system in the same precision, double against a real128 Cartesian reference, real128 against a
   160-bit Cartesian reference; conserved-quantity drifts;
3. an inclination sweep (1 … 1e-8 rad) in double against a real128 Cartesian reference that
   carries the departure-point vector (docs/orbits.md), so Θ, Σ, Φ have a reference too;
4. an eccentricity sweep (0 … 0.99) in double against a real128 Cartesian reference.

Tolerances are fixed before any number is seen, from the round-off laws (the comment block
"the laws" in ``orbit_validation/tolerances.py``, written out in the report) or taken from the
brief (``REQUIREMENTS``). A row that misses one is reported as FAIL with the measured number.
The tolerances and the runners are the package ``validation/orbit_validation/``; this script
writes the report and re-exports the names the tests use.
"""

from __future__ import annotations

import argparse
import concurrent.futures as cf
import math
import multiprocessing
import os
import platform
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import mpmath
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
HERE = Path(__file__).resolve().parent
for _p in (str(ROOT), str(HERE)):
    if _p not in sys.path:
        sys.path.insert(0, _p)

from orbit_cases import (  # noqa: E402
    ECCENTRICITIES,
    EPSILON,
    FORMULATIONS,
    INCLINATION_E,
    INCLINATIONS,
    LONG,
    LONG_BY_NAME,
    QUANTITIES,
    REFERENCE,
    scene,
)
from orbit_validation.long_runs import (  # noqa: E402
    drift_rows,
    long_comparisons,
    long_job,
    position_error,
)
from orbit_validation.reference import reference_job  # noqa: E402
from orbit_validation.runs import columns, integrate, output_times, steps_at  # noqa: E402
from orbit_validation.sweeps import eccentricity_job, inclination_job  # noqa: E402
from orbit_validation.tolerances import (  # noqa: E402
    C_BROUWER,
    C_LAW,
    REQUIREMENTS,
    K_x,
    law,
    reference_tolerance,
)
from report_sections import write_section  # noqa: E402

__all__ = [
    "K_x",
    "columns",
    "drift_rows",
    "inclination_job",
    "integrate",
    "law",
    "long_comparisons",
    "long_job",
    "main",
    "output_times",
    "position_error",
    "reference_job",
    "reference_tolerance",
    "scene",
    "steps_at",
]


def _e(x: Any) -> str:
    x = float(x)
    return "nan" if math.isnan(x) else f"{x:.1e}"


def verdict(ok: bool) -> str:
    return "PASS" if ok else "**FAIL**"


# ---------------------------------------------------------------------------- figures
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


# ---------------------------------------------------------------------------- report text
def machine_lines(total_seconds: float, workers: int, mode: str) -> list[str]:
    import heyoka

    return [
        f"* Machine: {platform.platform()}, {os.cpu_count()} cores, {workers} worker processes; "
        f"Python {platform.python_version()}, heyoka {heyoka.__version__}, "
        f"numpy {np.__version__}, mpmath {mpmath.__version__}.",
        f"* Mode: {mode}; total wall time {total_seconds / 60:.1f} min; generated "
        f"{time.strftime('%Y-%m-%d %H:%M %Z')}.",
    ]


def laws_text() -> list[str]:
    return [
        "### Tolerances (fixed before the runs)",
        "",
        "ε is the run's epsilon (2⁻⁵², 2⁻¹¹², 2⁻¹⁵⁹), n(t) the steps taken up to t (recorded "
        "through the progress callback), N_orb = t/P, e the initial eccentricity. A comparison "
        "of two runs uses the sum of their tolerances; a row passes when the error is below the "
        "tolerance at every output time.",
        "",
        f"* **Brouwer** (conserved energy, polar momentum k̂·(x × v), Jacobi constant): |drift| ≤ "
        f"{C_BROUWER:g} ε √n.",
        "* **Phase law** (position/a, r, h, angles): each step perturbs the energy by ~ε κ "
        "relatively, κ = (|T| + |V|)/|E| at pericentre = (3 + e)/(1 − e); as a random walk the "
        "mean motion errs by (3/2) ε (κ/3) √n, so the phase lags by 2π ε (κ/3) N_orb √n "
        "(∫√n ds = ⅔ t √n, n ∝ t), and the position by that times the largest speed in units of "
        "na, √((1+e)/(1−e)). The rounding of ρ itself (~2π per orbit) adds a walk of the same "
        f"form. Tolerance: {C_LAW:g} ε (1 + 2π N_orb √n K_x(e)), "
        "K_x = √((1+e)/(1−e)) (3+e)/(3(1−e)) "
        "(K_x(0) = 1, K_x(0.99) ≈ 1.9e3). Velocities and ṙ: the same with the largest "
        "acceleration in units of n²a, K_v = (3+e)/(3(1−e)³). "
        "This is the ε·n^{3/2} law (N_orb ∝ n).",
        f"* **Plane angles** near Φ = 0: |ΔΘ|, |ΔΣ| ≤ {C_LAW:g} ε (√n / sin Φ_min + 1 + "
        "2π N_orb √n K_x) (an error δ of the orbit normal moves Θ, Σ by δ/sin Φ); Φ "
        "and Θ − Σ (well defined at Φ = 0) follow the position law.",
        f"* **Brief**: real128 within {REQUIREMENTS['quad_reference_relative']:.0e} relative of "
        "every reference value (the values' 20-digit resolution; rounding them costs ≤ 5e-20). "
        "Double reference rows are judged by the phase law on |Δq| / max(|q|, 1) (μ = 1, a ≈ 1: "
        "the natural scales are 1).",
        "",
    ]


FORM_LABEL = {
    "cayley": "cayley",
    "quaternion": "quaternion",
    "cartesian": "cartesian",
    "departure": "cartesian + d̂ (this script)",
}


def reference_section(jobs: list[dict[str, Any]]) -> tuple[list[str], list[str]]:
    """Tables per case; returns (lines, failures)."""
    lines, fails = [], []
    forms = ("cayley", "quaternion", "cartesian", "departure")
    for case in REFERENCE:
        sel = {(j["formulation"], j["precision"]): j for j in jobs if j["case"] == case.name}
        if not sel:
            continue
        lines += [
            f"#### {case.name}: {case.title} (t = {case.t})",
            "",
            "Relative error |Δq|/|q| of each quantity at t; in double a cell is marked ✗ if "
            "|Δq|/max(|q|, 1) exceeds the phase law, in real128 if the relative error exceeds "
            '1e-19. "–": not a function of the formulation\'s state (ρ, Σ need the history of '
            "the plane).",
            "",
            "| formulation | precision | steps | " + " | ".join(QUANTITIES) + " | verdict |",
            "|---|---|---|" + "---|" * len(QUANTITIES) + "---|",
        ]
        for prec in ("double", "quad"):
            for f in forms:
                j = sel.get((f, prec))
                if j is None:
                    continue
                cells, ok = [], True
                for q in QUANTITIES:
                    err = j["errors"].get(q)
                    if err is None:
                        cells.append("–")
                        continue
                    tol = reference_tolerance(case.name, prec, q, j["steps"])
                    value = err["scaled"] if prec == "double" else err["relative"]
                    good = value <= tol
                    ok &= good
                    cells.append(_e(err["relative"]) + ("" if good else " ✗"))
                    if not good:
                        fails.append(
                            f"reference {case.name} / {f} / {prec} / {q}: {_e(value)} against "
                            f"{_e(tol)}"
                        )
                lines.append(
                    f"| {FORM_LABEL[f]} | {prec} | {j['steps']} | "
                    + " | ".join(cells)
                    + f" | {verdict(ok)} |"
                )
        lines.append("")
    return lines, fails


def long_section(
    case_name: str, jobs: dict[tuple, dict], figure: str
) -> tuple[list[str], list[str], list[dict]]:
    case = LONG_BY_NAME[case_name]
    comps = long_comparisons(case_name, jobs)
    drifts = drift_rows(case_name, jobs)
    fails = []
    any_job = next(iter(jobs.values()))
    lines = [
        f"#### {case_name}: {case.title}",
        "",
        f"a = {case.a:g}, e = {case.e:g}, period P = {case.period:.4g}, {any_job['orbits']:g} "
        f"orbits (t_end = {any_job['t'][-1]:.6g}); {len(any_job['t'])} log-spaced output times. "
        "min sin Φ over the run (Cayley form): "
        + ", ".join(
            f"{p} {jobs[('cayley', p)]['min_sin_phi']:.3f}"
            for p in ("double", "quad")
            if ("cayley", p) in jobs
        )
        + ".",
        "",
        f"![{case_name}](figures/{figure})",
        "",
        "| run | steps | steps/orbit | run (s) | compile (s) | µs/step |",
        "|---|---|---|---|---|---|",
    ]
    for (f, p), j in sorted(jobs.items(), key=lambda x: (x[0][1], x[0][0])):
        lines.append(
            f"| {f} {p} | {j['steps']} | {j['steps'] / j['orbits']:.1f} | {j['seconds']:.1f} "
            f"| {j['compile_seconds']:.1f} | {1e6 * j['seconds'] / max(j['steps'], 1):.0f} |"
        )
    lines += [
        "",
        "| run | against | max |Δx|/a | at t | final |Δx|/a | tolerance at t_end | max err/tol "
        "| verdict |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in comps:
        lines.append(
            f"| {r['run'][0]} {r['run'][1]} | {r['against'][0]} {r['against'][1]} "
            f"| {_e(r['max'])} | {r['at']:.4g} | {_e(r['final'])} | {_e(r['tol_end'])} "
            f"| {r['ratio']:.2g} | {verdict(r['pass'])} |"
        )
        if not r["pass"]:
            fails.append(
                f"{case_name} {r['run']} vs {r['against']}: max |Δx|/a {_e(r['max'])} at "
                f"t = {r['at']:.4g} (err/tol {r['ratio']:.2g})"
            )
    lines += [
        "",
        "| run | monitor | max |drift| | final |drift| | Brouwer tolerance at t_end | max "
        "drift/tol | verdict |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in sorted(drifts, key=lambda r: (r["precision"], r["formulation"], r["monitor"])):
        lines.append(
            f"| {r['formulation']} {r['precision']} | {r['monitor']} | {_e(r['max'])} "
            f"| {_e(r['final'])} | {_e(r['tol_end'])} "
            + (
                f"| {r['ratio']:.2g} | {verdict(r['pass'])} |"
                if r["judged"]
                else "| – | not conserved here |"
            )
        )
        if not r["pass"]:
            fails.append(
                f"{case_name} {r['formulation']} {r['precision']} {r['monitor']} drift "
                f"{_e(r['max'])} (drift/tol {r['ratio']:.2g})"
            )
    return [*lines, ""], fails, comps


def inclination_section(jobs: list[dict[str, Any]]) -> tuple[list[str], list[str]]:
    fails = []
    lines = [
        "![inclination](figures/orbit_inclination.png)",
        "",
        "| i (rad) | min sin Φ | formulation | steps | max |Δx|/a | max |ΔΘ| | max |ΔΣ| "
        "| max |ΔΦ| | max |Δ(Θ−Σ)| | max err/tol | verdict |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for j in jobs:
        for f in FORMULATIONS:
            r = j["runs"][f]
            ratio = max(r["ratio"].values())
            ok = ratio <= 1
            m = r["max"]
            lines.append(
                f"| {j['inclination']} | {j['sin_phi_min']:.3g} | {f} | {r['steps']} "
                f"| {_e(m['position'])} | "
                + " | ".join(
                    _e(m[k]) if k in m else "–" for k in ("Theta", "Sigma", "Phi", "Theta-Sigma")
                )
                + f" | {ratio:.2g} | {verdict(ok)} |"
            )
            if not ok:
                worst = max(r["ratio"], key=r["ratio"].get)
                fails.append(
                    f"inclination {j['inclination']} / {f} / {worst}: {_e(m[worst])} "
                    f"(err/tol {r['ratio'][worst]:.2g})"
                )
    return [*lines, ""], fails


def eccentricity_section(jobs: list[dict[str, Any]]) -> tuple[list[str], list[str]]:
    fails = []
    lines = [
        "![eccentricity](figures/orbit_eccentricity.png)",
        "",
        "| e | K_x(e) | formulation | steps/orbit | max |Δx|/a | final |Δx|/a | tolerance at "
        "t_end | max err/tol | verdict |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for j in jobs:
        lines.append(
            f"| {j['e']} | {K_x(float(j['e'])):.3g} | real128 cartesian (reference) "
            f"| {j['reference_steps'] / j['orbits']:.1f} | – | – | – | – | – |"
        )
        for f in FORMULATIONS:
            r = j["runs"][f]
            ok = r["ratio"] <= 1
            lines.append(
                f"| {j['e']} | | {f} | {r['steps'] / j['orbits']:.1f} | {_e(r['max'])} "
                f"| {_e(r['final'])} | {_e(r['tol_end'])} | {r['ratio']:.2g} | {verdict(ok)} |"
            )
            if not ok:
                fails.append(
                    f"eccentricity {j['e']} / {f}: {_e(r['max'])} (err/tol {r['ratio']:.2g})"
                )
    return [*lines, ""], fails


def requirement_rows(
    reference: list[dict], long_comps: dict[str, list[dict]], long_jobs: dict, inc: list, ecc: list
) -> list[str]:
    lines = ["| requirement | measured | tolerance | verdict |", "|---|---|---|---|"]
    quad = [
        (err["relative"], j["case"], j["formulation"], q)
        for j in reference
        if j["precision"] == "quad"
        for q, err in j["errors"].items()
    ]
    if quad:
        v, c, f, q = max(quad)
        tol = REQUIREMENTS["quad_reference_relative"]
        lines.append(
            f"| R1–R4, real128, every formulation and listed quantity: max relative error "
            f"({len(quad)} values; worst {c} {FORM_LABEL[f]} {q}) | {_e(v)} | {tol:.0e} "
            f"| {verdict(v <= tol)} |"
        )
    for name, comps in long_comps.items():
        jobs = long_jobs[name]
        orbits = min(j["orbits"] for j in jobs.values())
        for prec in ("double", "quad"):
            sel = [r for r in comps if r["run"][1] == prec]
            if not sel:
                continue
            w = max(sel, key=lambda r: r["ratio"])
            enough = orbits >= REQUIREMENTS["long_orbits"]
            ok = all(r["pass"] for r in sel)
            lines.append(
                f"| {name}, {prec}, {orbits:g} orbits: {len(sel)} comparisons (Cayley, quaternion "
                f"vs Cartesian; each vs the higher-precision Cartesian); worst err/tol: "
                f"{w['run'][0]} vs {w['against'][0]} {w['against'][1]}, max |Δx|/a | "
                f"{_e(w['max'])} | {_e(w['tol_end'])} (law at t_end) | "
                + (verdict(ok) if enough else f"not judged ({orbits:g} < 1000 orbits)")
                + " |"
            )
    if inc:
        worst = max(
            ((r["max"]["position"], j["inclination"], f) for j in inc for f, r in j["runs"].items())
        )
        ok = all(max(r["ratio"].values()) <= 1 for j in inc for r in j["runs"].values())
        lines.append(
            f"| inclination sweep {inc[0]['inclination']}…{inc[-1]['inclination']} rad, double, "
            f"{inc[0]['orbits']:g} orbits: every row within its law; worst |Δx|/a ({worst[2]}, "
            f"i = {worst[1]}) | {_e(worst[0])} | phase law | {verdict(ok)} |"
        )
    if ecc:
        worst = max(((r["max"], j["e"], f) for j in ecc for f, r in j["runs"].items()))
        ok = all(r["ratio"] <= 1 for j in ecc for r in j["runs"].values())
        lines.append(
            f"| eccentricity sweep {ecc[0]['e']}…{ecc[-1]['e']}, double, {ecc[0]['orbits']:g} "
            f"orbits: every row within its law; worst |Δx|/a ({worst[2]}, e = {worst[1]}) "
            f"| {_e(worst[0])} | phase law | {verdict(ok)} |"
        )
    return lines


def write_report(results: list[dict], out: Path, total: float, workers: int, mode: str) -> Path:
    figures = out / "figures"
    figures.mkdir(parents=True, exist_ok=True)
    reference = [r for r in results if r["kind"] == "reference"]
    long_jobs: dict[str, dict] = {}
    for r in results:
        if r["kind"] == "long":
            long_jobs.setdefault(r["case"], {})[(r["formulation"], r["precision"])] = r
    inc = sorted(
        (r for r in results if r["kind"] == "inclination"), key=lambda r: -float(r["inclination"])
    )
    ecc = sorted((r for r in results if r["kind"] == "eccentricity"), key=lambda r: float(r["e"]))

    ref_lines, fails = reference_section(reference)
    long_lines, long_comps = [], {}
    for name in [c.name for c in LONG if c.name in long_jobs]:
        fig = f"orbit_long_{name}.png"
        lines, f, comps = long_section(name, long_jobs[name], fig)
        plot_long(name, comps, figures / fig)
        long_lines += lines
        fails += f
        long_comps[name] = comps
    inc_lines, f = inclination_section(inc) if inc else ([], [])
    fails += f
    ecc_lines, f = eccentricity_section(ecc) if ecc else ([], [])
    fails += f
    if inc:
        plot_inclination(inc, figures / "orbit_inclination.png")
    if ecc:
        plot_eccentricity(ecc, figures / "orbit_eccentricity.png")

    lines = [
        "# Validation of the orbit integrators (Cayley 1860)",
        "",
        "Regenerate this section (and `validation/figures/orbit_*.png`) with "
        "`python validation/orbit_report.py` (`--quick` for a smoke run, `--jobs N` for the "
        "worker count). Cases: `validation/orbit_cases.py`. Tests: "
        "`tests/validation/test_orbit_validation.py` (`-m slow` for the long ones).",
        "",
        *machine_lines(total, workers, mode),
        "* Integrator: `cayley_heyoka.run(Scene.from_dict(...))`, tolerance `auto` (ε), every "
        "scene number a decimal string (the same exact inputs in every precision), output times "
        "binary64 values (the same grid in every precision). Formulations: `cayley` (r, ṙ, ρ, h, "
        'Θ, Σ, Φ), `quaternion`, `cartesian`; "real128" is `precision = "quad"`, "real160" '
        "`{bits = 160}`.",
        "* Comparisons in 60-digit mpmath from the exact values of each run. Timings: the `run()` "
        "call without its compilation (compiled code is cached by heyoka on disk, so compile "
        "times depend on what ran before), including the per-step progress callback.",
        "",
        "### Requirements of the brief",
        "",
        *requirement_rows(reference, long_comps, long_jobs, inc, ecc),
        "",
        *laws_text(),
        "### 1. Reference values R1–R4",
        "",
        "Inputs and 20-digit values at t from `validation/orbit_cases.py`. The "
        'Cartesian rows derive r, ṙ, h, Θ, Φ from (x, ẋ); the row "cartesian + d̂" '
        "is this script's own Cartesian integration carrying the departure-point vector (§9.2 "
        "step 6), which gives ρ and Σ as well — it is the reference of the inclination sweep.",
        "",
        *ref_lines,
        "### 2. Long runs",
        "",
        "Solid lines: against the Cartesian run of the same precision; dashed: against the "
        "Cartesian run of the next precision (double → real128, real128 → 160 bits); dotted: "
        "the law's tolerance of the dashed Cartesian comparison.",
        "",
        *long_lines,
        "### 3. Inclination sweep",
        "",
        f"J2 = 0.001 (radius 0.5) about z and a third body (Gm 0.001, a 3) in the reference plane; "
        f"a = 1, e = {INCLINATION_E}, {inc[0]['orbits'] if inc else '–'} orbits, 16 output times "
        'per orbit, double; Cayley with `equatorial_limit = "0"` so that it runs at every '
        "inclination. Reference: real128 Cartesian run carrying the departure-point vector d̂ "
        "(docs/orbits.md), from which Θ, Σ, Φ follow at each output time (validated on R1–R4 "
        "above). "
        "Θ, Σ differences are taken modulo 2π.",
        "",
        *inc_lines,
        "### 4. Eccentricity sweep",
        "",
        "J2 = 0.001 with radius a(1 − e)/2 (pericentre at twice the radius) and a third body "
        f"(Gm 0.001, a 5, i 0.3); a = 1, i = 0.5, {ecc[0]['orbits'] if ecc else '–'} orbits, 4 "
        "output times per orbit, double against a real128 Cartesian reference.",
        "",
        *ecc_lines,
        "### Findings",
        "",
        f"* **FAIL rows: {len(fails)}.**" if fails else "* No judged row fails.",
        *[f"  * {f}." for f in fails],
        *findings(reference, long_comps, long_jobs, inc, ecc),
        "",
    ]
    return write_section(out / "REPORT.md", "orbit", "\n".join(lines))


def findings(reference, long_comps, long_jobs, inc, ecc) -> list[str]:
    """Observations computed from this run's numbers."""
    out = []
    for name, comps in long_comps.items():
        for prec in ("double", "quad"):
            by = {(r["run"][0], r["against"]): r for r in comps if r["run"][1] == prec}
            ref_prec = "quad" if prec == "double" else "real160"
            parts = [
                f"{f} {_e(by[(f, ('cartesian', ref_prec))]['max'])}"
                for f in FORMULATIONS
                if (f, ("cartesian", ref_prec)) in by
            ]
            jobs = long_jobs[name]
            steps = ", ".join(
                f"{f} {jobs[(f, prec)]['steps']}" for f in FORMULATIONS if (f, prec) in jobs
            )
            if parts:
                out.append(
                    f"* {name}, {prec}: max |Δx|/a against the {ref_prec} Cartesian reference: "
                    + ", ".join(parts)
                    + f" (steps: {steps})."
                )
    if inc:
        c = [j["runs"]["cayley"]["max"] for j in inc]
        out.append(
            "* Inclination sweep: the Cayley form at i = "
            f"{inc[-1]['inclination']} keeps |Δx|/a = {_e(c[-1]['position'])}, |ΔΘ| = "
            f"{_e(c[-1]['Theta'])}, |ΔΣ| = {_e(c[-1]['Sigma'])} (at i = {inc[0]['inclination']}: "
            f"{_e(c[0]['position'])}, {_e(c[0]['Theta'])}, {_e(c[0]['Sigma'])}). With this "
            "perturbation the normal force is itself ∝ sin Φ, so the orbit normal's error is "
            "relative to sin Φ and Θ, Σ do not degrade like ε/sin Φ (the §10 amplification needs "
            "a forcing that moves the normal by more than sin Φ, e.g. a perturber out of the "
            "plane)."
        )
    if ecc:
        parts = [
            f"e = {j['e']}: {j['runs']['cayley']['steps'] / j['orbits']:.0f} / "
            f"{j['runs']['cartesian']['steps'] / j['orbits']:.0f}"
            for j in ecc
        ]
        out.append("* Steps per orbit, Cayley / Cartesian (double): " + "; ".join(parts) + ".")
    return out


# ---------------------------------------------------------------------------- driver
# Estimated seconds (measured on the development machine), for load balance.
_COST = {
    ("long", "double"): 1,
    ("long", "quad"): 100,
    ("long", "real160"): 80,
}


def plan(mode: str, parts: set[str]) -> list[tuple[float, Any, tuple]]:
    tasks = []
    if "reference" in parts:
        for case in REFERENCE:
            for prec in ("double", "quad"):
                for f in (*FORMULATIONS, "departure"):
                    cost = 5 if prec == "quad" else 0.5
                    tasks.append((cost, reference_job, (case.name, f, prec)))
    if "long" in parts:
        for case in LONG:
            scale = case.orbits[mode] / 1000 * (2 if case.name == "L2" else 1)
            for f in FORMULATIONS:
                for prec in ("double", "quad"):
                    cost = _COST[("long", prec)] * scale * (2 if f != "cartesian" else 0.5)
                    tasks.append((cost, long_job, (case.name, f, prec, mode)))
            tasks.append(
                (
                    _COST[("long", "real160")] * scale,
                    long_job,
                    (case.name, "cartesian", "real160", mode),
                )
            )
    if "inclination" in parts:
        for i in INCLINATIONS:
            tasks.append((5, inclination_job, (i, mode)))
    if "eccentricity" in parts:
        for e in ECCENTRICITIES:
            tasks.append((2 + 40 * float(e) ** 8, eccentricity_job, (e, mode)))
    return sorted(tasks, key=lambda x: -x[0])


PARTS = ("reference", "long", "inclination", "eccentricity")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="short spans: a smoke run")
    parser.add_argument("--jobs", type=int, default=2, help="worker processes (default 2)")
    parser.add_argument("--parts", default=",".join(PARTS), help=f"subset of {PARTS}")
    parser.add_argument(
        "--out", default=None, help="output directory (default validation/; --quick: a temp dir)"
    )
    args = parser.parse_args(argv)
    mode = "quick" if args.quick else "full"
    parts = set(args.parts.split(","))
    if parts - set(PARTS):
        parser.error(f"unknown parts {sorted(parts - set(PARTS))}; known: {PARTS}")
    out = Path(args.out) if args.out else (HERE if mode == "full" else Path(tempfile.mkdtemp()))
    t0 = time.perf_counter()
    results = []
    ctx = multiprocessing.get_context("spawn")  # heyoka's LLVM/TBB state must not be forked
    with cf.ProcessPoolExecutor(max_workers=args.jobs, mp_context=ctx) as pool:
        futures = {pool.submit(fn, *a): a for _, fn, a in plan(mode, parts)}
        for fut in cf.as_completed(futures):
            r = fut.result()
            results.append(r)
            label = " ".join(str(x) for x in futures[fut])
            print(
                f"[{time.perf_counter() - t0:7.1f} s] {r['kind']:12s} {label} "
                f"({r['wall_seconds']:.1f} s)",
                flush=True,
            )
    path = write_report(results, out, time.perf_counter() - t0, args.jobs, mode)
    print(f"wrote {path} ({(time.perf_counter() - t0) / 60:.1f} min)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
