"""The report's Markdown tables and fixed texts: machine, requirements, summary, cases, laws."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from rotation_cases import BY_NAME

from .laws import C_BROUWER, C_LAW, ENSEMBLE_LAW, FIT_SLACK, REQUIREMENTS
from .verdicts import fit_rows, quantity_rows, sci, verdict


def requirement_rows(jobs: list[dict[str, Any]]) -> list[str]:
    """The brief's fixed requirements."""
    lines = ["| requirement | measured | tolerance | verdict |", "|---|---|---|---|"]
    by = {(j["case"], j["precision"]): j for j in jobs}
    q = by.get(("generic", "quad"))
    if q:
        value = max(np.nanmax(q["errors"]["state"]), np.nanmax(q["errors"]["attitude"]))
        tol = REQUIREMENTS["quad_generic_state"]
        lines.append(
            f"| real128, generic, quaternion, {q['periods']:g} periods: max(rates, attitude) "
            f"error | {sci(value)} | {tol:.0e} | {_required(value <= tol, q['periods'])} |"
        )
    d = by.get(("generic", "double"))
    if d:
        c = d["crossings"]
        rel = float(np.max(c["abs"] / c["t"])) if len(c["t"]) else math.nan
        tol = REQUIREMENTS["double_generic_crossings"]
        ok = rel <= tol and c["misses"] == 0 and c["extras"] == 0 and c["direction_mismatches"] == 0
        lines.append(
            f"| double, generic, {d['periods']:g} periods: crossing times max |Δt|/t "
            f"({c['matched']} matched of {c['n_ref']}, {c['misses']} missed, {c['extras']} "
            f"extra, {c['direction_mismatches']} wrong directions) | {sci(rel)} | {tol:.0e} "
            f"| {_required(ok, d['periods'])} |"
        )
    return lines


def _required(ok: bool, periods: float) -> str:
    """A requirement stated over 100 periods is not judged on a shorter (quick) run."""
    return verdict(ok) if periods >= 100 else f"not judged ({periods:g} < 100 periods)"


def summary_rows(jobs: list[dict[str, Any]]) -> list[str]:
    """Worst case per precision, regular cases and all cases."""
    lines = [
        "| precision | group | worst rates error | worst attitude error | worst energy drift "
        "| worst |L|² drift | worst crossing |Δt|/t | judged rows | FAIL rows |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for prec in ("double", "quad", "real256"):
        for group, keep in (
            ("regular + long", lambda j: BY_NAME[j["case"]].group != "separatrix"),
            ("near separatrix", lambda j: BY_NAME[j["case"]].group == "separatrix"),
        ):
            sel = [j for j in jobs if j["precision"] == prec and keep(j)]
            if not sel:
                continue

            def top(get, sel=sel):
                vals = [(float(np.nanmax(get(j))) if len(get(j)) else -1, j["case"]) for j in sel]
                v, name = max(vals)
                return f"{sci(v)} ({name})" if v >= 0 else "–"

            rows = [r for j in sel for r in quantity_rows(j)]
            fails = sum(not r["pass"] for r in rows)
            lines.append(
                f"| {prec} | {group} | {top(lambda j: j['errors']['state'])} "
                f"| {top(lambda j: j['errors']['attitude'])} "
                f"| {top(lambda j: j['drifts']['energy'])} "
                f"| {top(lambda j: j['drifts']['momentum_squared'])} "
                f"| {top(lambda j: j['crossings']['abs'] / j['crossings']['t'])} "
                f"| {len(rows)} | {fails} |"
            )
    return lines


def case_section(name: str, jobs: list[dict[str, Any]], figure: str) -> list[str]:
    case = BY_NAME[name]
    law = jobs[0]["law"]
    lines = [
        f"### {name}: {case.title}",
        "",
        f"Inertia {case.inertia}, rates {case.rates} (binary64, exact), {case.formulation} "
        f"attitude. Period T = {law.period:.6g}; separatrix distance (realised, exact from the "
        f"inputs) δ = {law.distance:.4e}"
        + (f" (asked {case.target_distance:.0e})" if case.target_distance else "")
        + f"; law constants S_T = {law.S_T:.3g}, S_Ψ = {law.S_Psi:.3g}, g = {law.g:.3g}, "
        f"|ω|max = {law.w_max:.3g}.",
        "",
        f"![{name}](figures/{figure})",
        "",
        "| precision | periods | steps | rebasings | θ = π passages | reference error | run (s) "
        "| µs/step |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for j in jobs:
        ref = j["errors"]["reference_error"]
        fails = j["errors"]["reference_failures"]
        lines.append(
            f"| {j['precision']} | {j['periods']:g} | {j['steps']} | {j['rebasings']} "
            f"| {j['half_turns']} | {sci(ref)}"
            + (f" ({len(fails)} times failed: {fails[0]})" if fails else "")
            + f" | {j['run_seconds']:.1f} | {1e6 * j['run_seconds'] / max(j['steps'], 1):.1f} |"
        )
    lines += [
        "",
        "| precision | quantity | max error | at t | tolerance there | tolerance at t_end "
        "| max err/tol | verdict |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for j in jobs:
        for r in quantity_rows(j):
            lines.append(
                f"| {j['precision']} | {r['quantity']} | {sci(r['value'])} | {r['at']:.4g} "
                f"| {sci(r['tol'])} ({r['law']}) | {sci(r['tol_end'])} | {r['ratio']:.2g} "
                f"| {verdict(r['pass'])} |"
            )
    crossing = [
        "",
        "| precision | reference crossings | events | matched | missed | extra "
        "| beyond the law's horizon | wrong direction | max |Δt| | max |Δt|/t |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    any_crossing = False
    for j in jobs:
        c = j["crossings"]
        if not c["n_ref"]:
            continue
        any_crossing = True
        rel = float(np.max(c["abs"] / c["t"])) if len(c["t"]) else math.nan
        mx = float(np.max(c["abs"])) if len(c["abs"]) else math.nan
        crossing.append(
            f"| {j['precision']} | {c['n_ref']} | {c['n_events']} | {c['matched']} "
            f"| {c['misses']} | {c['extras']} | {c['beyond_law']} "
            f"| {c['direction_mismatches']} | {sci(mx)} | {sci(rel)} |"
        )
    if any_crossing:
        lines += crossing
    return [*lines, ""]


def exponent_table(jobs: list[dict[str, Any]]) -> list[str]:
    lines = [
        "| case | precision | periods | rates | attitude | energy | |L|² |",
        "|---|---|---|---|---|---|---|",
    ]
    for j in jobs:
        rows = fit_rows(j)
        if not rows:
            continue
        f = j["fits"]
        lines.append(
            f"| {j['case']} | {j['precision']} | {j['periods']:g} | {f['state']:.2f} "
            f"| {f['attitude']:.2f} | {f['energy']:.2f} | {f['momentum_squared']:.2f} |"
        )
    return lines


def laws_text() -> list[str]:
    return [
        "## Tolerances (fixed before the runs)",
        "",
        "ε is the precision's epsilon (2⁻⁵², 2⁻¹¹², 2⁻²⁵⁵), n(t) the steps taken up to t "
        "(recorded step by step through the progress callback), |ω₀| the norm of the initial "
        "rates. Every tolerance is evaluated at each output time; a row passes when the error "
        "is below it at every time.",
        "",
        f"* **Brouwer** (energy, |L|², space L): |drift(t)| ≤ {C_BROUWER:g} ε √n(t).",
        "* **Phase law**: round-off perturbs the rates by ~ε√n; a relative perturbation e of "
        "the rates changes the period T by S_T·e relatively (S_T = |∇_ω ln T|·|ω₀|) and the "
        "mean precession rate Ψ̄ = ΔΨ/T by S_Ψ·e (S_Ψ = |∇_ω Ψ̄|·|ω₀|), both from the closed "
        "form by central differences. Integrated over time (n ∝ t) this gives the ε·n^{3/2} "
        "law, amplified next to the separatrix by S_T ∝ 1/(δ log(1/δ)):",
        f"  * rates: |Δω|/|ω₀| ≤ {C_LAW:g} ε (1 + ⅔ S_T g t √n), g = max|ω̇|/|ω₀|;",
        f"  * attitude: min‖q ∓ q_ref‖ ≤ {C_LAW:g} ε (1 + ⅓ (S_T |ω|max + S_Ψ) t √n);",
        f"  * crossing times: |Δt| ≤ {C_LAW:g} ε (t + ⅔ S_T t √n). Reference crossings are "
        "paired with the nearest event of the same axis within a quarter of the spacing of "
        "consecutive crossings; where the law's tolerance exceeds that gate the law itself "
        "says the crossing cannot be placed, and it is counted as *beyond the law's horizon* "
        "instead of being judged.",
        f"* **Growth exponents**: slope of log(RMS error over an ensemble of runs a few ulps "
        f"apart) against log n, over t ≥ max(T, t_end/100): ≤ ½ + {FIT_SLACK} (conserved), "
        f"≤ 3/2 + {FIT_SLACK} (rates, attitude). Single runs' slopes are reported, not judged: "
        "the law is a statement about the ensemble (see the single-run table).",
        "* **Fixed requirements of the brief**: real128 within "
        f"{REQUIREMENTS['quad_generic_state']:.0e} of the reference over 100 periods (generic, "
        "quaternion); double crossing times within "
        f"{REQUIREMENTS['double_generic_crossings']:.0e} relative (|Δt|/t) over 100 periods, "
        "with no missed or extra events and the right directions.",
        "",
    ]


def ensemble_table(ensembles: dict[tuple, dict]) -> list[str]:
    """Ensemble RMS exponents, judged like the single runs."""
    lines = [
        "| case | precision | periods | runs | rates | attitude | energy | |L|² | verdict |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for (name, prec, periods), f in ensembles.items():
        sl = f["slope"]
        fails = [k for k, law in ENSEMBLE_LAW.items() if not sl[k] <= law + FIT_SLACK]
        lines.append(
            f"| {name} | {prec} | {periods:g} | {f['members']} | {sl['state']:.2f} "
            f"| {sl['attitude']:.2f} | {sl['energy']:.2f} | {sl['momentum_squared']:.2f} "
            f"| {verdict(not fails)}{' (' + ', '.join(fails) + ')' if fails else ''} |"
        )
    return lines


def diagnostic_table(diagnostic: dict[str, Any] | None) -> list[str]:
    if diagnostic is None:
        return ["(not run)"]
    lines = [
        f"The symmetric body at 256 bits over {diagnostic['periods']} periods, five ways "
        "(drifts in units of ε₂₅₆ = 2⁻²⁵⁵; the last column is Brouwer's tolerance 10 √n in the "
        "same units):",
        "",
        "| variant | steps | order | h·|ω₀| | space L drift / ε | ‖RᵀR − I‖ / ε | 10 √n |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in diagnostic["rows"]:
        lines.append(
            f"| {r['label']} | {r['steps']} | {r['order']} | {r['h_omega']:.2f} "
            f"| {r['space_L']:.3g} | {r['orthogonality']:.3g} | {r['brouwer']:.3g} |"
        )
    return lines
