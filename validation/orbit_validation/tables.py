"""The Markdown tables of the orbit section: one per part and the brief's requirements."""

from __future__ import annotations

import math
from typing import Any

from orbit_cases import FORMULATIONS, LONG_BY_NAME, QUANTITIES, REFERENCE

from .long_runs import drift_rows, long_comparisons
from .tolerances import REQUIREMENTS, K_x, reference_tolerance


def sci(x: Any) -> str:
    """A table number: two significant digits in e-notation, or "nan"."""
    x = float(x)
    return "nan" if math.isnan(x) else f"{x:.1e}"


def verdict(ok: bool) -> str:
    return "PASS" if ok else "**FAIL**"


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
                    cells.append(sci(err["relative"]) + ("" if good else " ✗"))
                    if not good:
                        fails.append(
                            f"reference {case.name} / {f} / {prec} / {q}: {sci(value)} against "
                            f"{sci(tol)}"
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
            f"| {sci(r['max'])} | {r['at']:.4g} | {sci(r['final'])} | {sci(r['tol_end'])} "
            f"| {r['ratio']:.2g} | {verdict(r['pass'])} |"
        )
        if not r["pass"]:
            fails.append(
                f"{case_name} {r['run']} vs {r['against']}: max |Δx|/a {sci(r['max'])} at "
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
            f"| {r['formulation']} {r['precision']} | {r['monitor']} | {sci(r['max'])} "
            f"| {sci(r['final'])} | {sci(r['tol_end'])} "
            + (
                f"| {r['ratio']:.2g} | {verdict(r['pass'])} |"
                if r["judged"]
                else "| – | not conserved here |"
            )
        )
        if not r["pass"]:
            fails.append(
                f"{case_name} {r['formulation']} {r['precision']} {r['monitor']} drift "
                f"{sci(r['max'])} (drift/tol {r['ratio']:.2g})"
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
                f"| {sci(m['position'])} | "
                + " | ".join(
                    sci(m[k]) if k in m else "–" for k in ("Theta", "Sigma", "Phi", "Theta-Sigma")
                )
                + f" | {ratio:.2g} | {verdict(ok)} |"
            )
            if not ok:
                worst = max(r["ratio"], key=r["ratio"].get)
                fails.append(
                    f"inclination {j['inclination']} / {f} / {worst}: {sci(m[worst])} "
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
                f"| {j['e']} | | {f} | {r['steps'] / j['orbits']:.1f} | {sci(r['max'])} "
                f"| {sci(r['final'])} | {sci(r['tol_end'])} | {r['ratio']:.2g} | {verdict(ok)} |"
            )
            if not ok:
                fails.append(
                    f"eccentricity {j['e']} / {f}: {sci(r['max'])} (err/tol {r['ratio']:.2g})"
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
            f"({len(quad)} values; worst {c} {FORM_LABEL[f]} {q}) | {sci(v)} | {tol:.0e} "
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
                f"{sci(w['max'])} | {sci(w['tol_end'])} (law at t_end) | "
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
            f"i = {worst[1]}) | {sci(worst[0])} | phase law | {verdict(ok)} |"
        )
    if ecc:
        worst = max(((r["max"], j["e"], f) for j in ecc for f, r in j["runs"].items()))
        ok = all(r["ratio"] <= 1 for j in ecc for r in j["runs"].values())
        lines.append(
            f"| eccentricity sweep {ecc[0]['e']}…{ecc[-1]['e']}, double, {ecc[0]['orbits']:g} "
            f"orbits: every row within its law; worst |Δx|/a ({worst[2]}, e = {worst[1]}) "
            f"| {sci(worst[0])} | phase law | {verdict(ok)} |"
        )
    return lines
