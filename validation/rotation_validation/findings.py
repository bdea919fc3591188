"""The findings ("What we learned"), each computed from the run's measurements."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from rotation_cases import BY_NAME, CASES, EPSILON

from .laws import C_BROUWER, ENSEMBLE_LAW, FIT_SLACK, REQUIREMENTS
from .verdicts import quantity_rows, sci


def brouwer_constants(jobs: list[dict[str, Any]]) -> dict[str, tuple[float, str]]:
    """Per precision, the largest conserved drift in units of ε √n, and where."""
    out: dict[str, tuple[float, str]] = {}
    for j in jobs:
        eps = EPSILON[j["precision"]]
        n = np.maximum(j["n"], 1)
        for k in ("energy", "momentum_squared", "momentum_space"):
            c = float(np.nanmax(j["drifts"][k] / (eps * np.sqrt(n))))
            if c > out.get(j["precision"], (-1.0, ""))[0]:
                out[j["precision"]] = (c, f"{j['case']}, {k}")
    return out


def learned(
    jobs: list[dict[str, Any]],
    ensembles: dict[tuple, dict],
    diagnostic: dict[str, Any] | None,
    closed: list[str],
) -> list[str]:
    """The findings, each computed from this run's measurements."""
    out = []
    by = {(j["case"], j["precision"]): j for j in jobs}
    fails = [
        f"{j['case']} / {j['precision']} / {r['quantity']}: {sci(r['value'])} at "
        f"t = {r['at']:.4g} against {sci(r['tol'])} (err/tol {r['ratio']:.2g})"
        for j in jobs
        for r in quantity_rows(j)
        if not r["pass"]
    ]
    for (name, prec, _periods), f in ensembles.items():
        for k, law in ENSEMBLE_LAW.items():
            if not f["slope"][k] <= law + FIT_SLACK:
                fails.append(f"ensemble {name} / {prec} / {k}: exponent {f['slope'][k]:.2f}")
    closed_fails = sum("**FAIL**" in line for line in closed)
    if closed_fails:
        fails.append(f"{closed_fails} closed-form comparison rows")
    out.append(f"* **FAIL rows: {len(fails)}.**" if fails else "* No judged row fails.")
    out += [f"  * {f}." for f in fails]

    # Brouwer's constant, and the step length of the runs that exceed it.
    consts = brouwer_constants(jobs)
    text = "; ".join(f"{p}: {c:.1f} ({w})" for p, (c, w) in consts.items())
    h_omega = {
        (j["case"], j["precision"]): j["law"].w0 * j["t_end"] / max(j["steps"], 1) for j in jobs
    }
    over = sorted(
        {
            (j["case"], j["precision"])
            for j in jobs
            for r in quantity_rows(j)
            if r["law"] == "Brouwer" and not r["pass"]
        }
    )
    line = (
        "* Conserved quantities follow Brouwer's law: the largest drift in units of ε√n is "
        f"{text} (tolerance {C_BROUWER:g}). The mean step h·|ω₀| is "
        f"{np.median(list(h_omega.values())):.2f} (median over the runs)"
    )
    if over:
        line += "; the runs over the tolerance take the longest steps: " + ", ".join(
            f"{c}/{p} (h·|ω₀| = {h_omega[(c, p)]:.2f})" for c, p in over
        )
    out.append(line + ".")
    if diagnostic:
        rows = diagnostic["rows"]
        out.append(
            "* Round-off of long high-order steps (diagnostic table): at 256 bits the symmetric "
            f"body takes {rows[0]['steps']} steps of h|ω₀| ≈ {rows[0]['h_omega']:.1f} over "
            f"{diagnostic['periods']} periods; its space-L drift is {rows[0]['space_L']:.3g} ε "
            f"with tolerance auto, {rows[1]['space_L']:.3g} ε with a tolerance 170× below ε "
            f"(so it is not truncation), {rows[2]['space_L']:.3g} ε with heyoka's compensated "
            "summation (so it is not the summation of the Taylor polynomial), and "
            f"{rows[3]['space_L']:.3g} ε with 320-bit arithmetic on the same steps (so it is "
            "256-bit round-off, consistent with the relative errors of the Taylor "
            "coefficients being weighted by Σ|c_k|h^k ≈ e^{h|ω|} ≫ |x| when a step spans "
            "half a period). Brouwer's law holds in shape, but its constant per step grows "
            "with h|ω|; at 256 bits the steps are long enough for that to matter."
        )
    # Growth exponents.
    if ensembles:
        parts = []
        for (name, prec, periods), f in ensembles.items():
            sl = f["slope"]
            parts.append(
                f"{name}/{prec}/{periods:g} periods: rates {sl['state']:.2f}, attitude "
                f"{sl['attitude']:.2f}, energy {sl['energy']:.2f}, |L|² "
                f"{sl['momentum_squared']:.2f}"
            )
        single = [v for j in jobs for k, v in j["fits"].items() if k in ("state", "attitude")]
        single = [v for v in single if not math.isnan(v)]
        out.append(
            "* Growth exponents, ensembles (RMS): " + "; ".join(parts) + ". Single runs scatter "
            f"over {min(single):.2f}–{max(single):.2f} for the rates and attitude: one run is "
            "one sample path of an integrated random walk, whose local slope over two "
            "decades is not 3/2; the exponent is a property of the ensemble."
        )
    # Separatrix amplification.
    sep = [
        (BY_NAME[j["case"]].target_distance, j)
        for j in jobs
        if BY_NAME[j["case"]].group == "separatrix" and j["precision"] == "double"
    ]
    if sep:
        items = ", ".join(
            f"δ = {d:.0e}: {sci(np.nanmax(j['errors']['state']))} (S_T = {j['law'].S_T:.2g})"
            for d, j in sorted(sep, key=lambda x: (abs(x[0]), x[0]))
        )
        digits = []
        for prec in ("quad", "real256"):
            js = [
                by[(c.name, prec)]
                for c in CASES
                if c.group == "separatrix"
                and abs(c.target_distance) < 1e-13
                and (c.name, prec) in by
            ]
            if js:
                worst_err = max(float(np.nanmax(j["errors"]["state"])) for j in js)
                digits.append(
                    f"{prec} keeps ~{-math.log10(worst_err):.0f} digits over "
                    f"{js[0]['periods']:g} periods"
                )
        out.append(
            "* Next to the separatrix the error is amplified as the period's sensitivity S_T "
            f"∝ 1/(δ log(1/δ)) predicts; worst rates error in double over "
            f"{sep[0][1]['periods']:g} periods: {items}. At δ = 1e-14 one ulp of the rates "
            "moves δ by ~1%, so double integration loses all digits within a few periods "
            "whatever the integrator"
            + (" (" + "; ".join(digits) + ")" if digits else "")
            + ". (Estimate, not measured: rounding the differences B − C, … of Euler's "
            "equations once in the run's precision, where they are not exact, is a fixed "
            "perturbation of relative size ε/2; its phase error grows like n, below the "
            "n^{3/2} of the round-off walk.)"
        )
    # Rodrigues vs quaternion.
    for prec in ("double", "quad", "real256"):
        q, r = by.get(("generic", prec)), by.get(("generic_rodrigues", prec))
        if not (q and r) or q["periods"] != r["periods"]:
            continue
        ea, eq = np.nanmax(r["errors"]["attitude"]), np.nanmax(q["errors"]["attitude"])
        out.append(
            f"* Rodrigues chart vs quaternion (generic, {prec}, {r['periods']:g} periods): "
            f"{r['steps']} vs {q['steps']} steps ({r['steps'] / q['steps']:.2f}×), "
            f"{r['rebasings']} re-basings over {r['half_turns']} passages of θ = π; attitude "
            f"error {sci(ea)} vs {sci(eq)} (ratio {ea / eq:.2g})."
        )
    # The brief's quad requirement outside the generic case.
    quads = [
        (float(np.nanmax(j["errors"]["state"])), j["case"])
        for j in jobs
        if j["precision"] == "quad" and BY_NAME[j["case"]].group == "regular"
    ]
    above = [(v, c) for v, c in quads if v > REQUIREMENTS["quad_generic_state"]]
    if above:
        parts = []
        for v, c in above:
            j = by[(c, "quad")]
            within = all(r["pass"] for r in quantity_rows(j))
            parts.append(
                f"{c} reaches {sci(v)} over {j['periods']:g} periods (S_T = {j['law'].S_T:.2g} "
                f"against {by[('generic', 'quad')]['law'].S_T:.2g} for the generic case, "
                f"{j['steps']} steps; {'within' if within else 'OUTSIDE'} its law)"
            )
        out.append(
            "* The 1e-30 real128 requirement is stated for the generic case; among the other "
            "regular cases " + "; ".join(parts) + ": closer to the separatrix the period is "
            "more sensitive to round-off and the steps per period are more."
        )
    # The exactly symmetric body: r is exact, so the frequency cannot random-walk.
    sym = [j for j in jobs if j["case"] == "symmetric" and not math.isnan(j["fits"]["state"])]
    if sym:
        out.append(
            "* Exactly symmetric body: ṙ = (A − B)/C·pq is identically zero, so r — and with "
            "it the frequency (C − A)r/A of (p, q) — is exact and cannot random-walk; the "
            "rates error then grows like the round-off walk itself, not n^{3/2}: single-run "
            "rates exponents "
            + ", ".join(f"{j['precision']} {j['fits']['state']:.2f}" for j in sym)
            + "."
        )
    # Reference accuracy, run by run: its error estimate against the smallest measured error.
    ratios = []
    for j in jobs:
        e = np.concatenate([j["errors"]["state"][1:], j["errors"]["attitude"][1:]])
        e = e[np.isfinite(e) & (e > 0)]
        if len(e):
            ratios.append((j["errors"]["reference_error"] / float(np.min(e)), j))
    if ratios:
        worst_ratio, j = max(ratios, key=lambda x: x[0])
        out.append(
            "* The reference never limits the comparison: in every run its certified error "
            "estimate is below the smallest measured error by a factor ≥ "
            f"{1 / worst_ratio:.1e} (tightest: {j['case']}/{j['precision']}, reference "
            f"{sci(j['errors']['reference_error'])})."
        )
    return out
