"""The orbit section of REPORT.md: its text around the tables, the findings, the figures."""

from __future__ import annotations

from pathlib import Path

from orbit_cases import FORMULATIONS, INCLINATION_E, LONG
from report_sections import machine_lines, write_section

from .figures import plot_eccentricity, plot_inclination, plot_long
from .tables import (
    eccentricity_section,
    inclination_section,
    long_section,
    reference_section,
    requirement_rows,
    sci,
)
from .tolerances import C_BROUWER, C_LAW, REQUIREMENTS


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
                f"{f} {sci(by[(f, ('cartesian', ref_prec))]['max'])}"
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
            f"{inc[-1]['inclination']} keeps |Δx|/a = {sci(c[-1]['position'])}, |ΔΘ| = "
            f"{sci(c[-1]['Theta'])}, |ΔΣ| = {sci(c[-1]['Sigma'])} (at i = {inc[0]['inclination']}: "
            f"{sci(c[0]['position'])}, {sci(c[0]['Theta'])}, {sci(c[0]['Sigma'])}). With this "
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
