"""The prose under each case's table: the ratios at equal error and what they are made of,
each sentence built from this run's numbers."""

from __future__ import annotations

import math

from bench_common import fmt

from .records import Case, Point


def cheapest(case: Case, method: str, level: float) -> Point | None:
    """The method's fastest sweep point at least as accurate as ``level``."""
    pts = [p for p in case.points if p.method == method and p.error <= level]
    pts = [p for p in pts if math.isfinite(p.wall)]
    return min(pts, key=lambda p: p.wall) if pts else None


def headline(case: Case, rows: dict) -> list[str]:
    """The ratios at equal error and what they are made of (steps × cost per step), worded
    from the numbers themselves."""
    parts = []
    for level, (ref, row) in rows.items():
        others = {m: r for m, r in row.items() if m != ref and math.isfinite(r)}
        if not others:
            continue
        said = ", ".join(f"{m} {_times(r)}" for m, r in sorted(others.items(), key=lambda x: x[1]))
        parts.append(f"at {level:.0e}, against {ref}: {said}")
    if not parts:
        return ["No two methods reach a common error level in this sweep."]
    out = ["Measured: " + "; ".join(parts) + "."]
    # The tightest level that at least two methods reach, taken apart into steps and the cost
    # of one step (the cheapest sweep point of each method reaching it).
    for level, (_, row) in sorted(rows.items()):
        reached = [m for m, r in row.items() if math.isfinite(r)]
        peers = [m for m in reached if not m.startswith("ours")]
        if len(reached) < 2 or (not peers and any(not m.startswith("ours") for m in row)):
            continue
        pieces = []
        for m in reached:
            p = cheapest(case, m, level)
            if p is None or not p.steps:
                continue
            pieces.append(f"{m} ({p.setting}) {p.steps} steps of {fmt(p.wall / p.steps * 1e6)} µs")
        if len(pieces) >= 2:
            out.append(f"Reaching {level:.0e}: " + "; ".join(pieces) + ".")
        break
    return [" ".join(out)]


def _at(case: Case, method: str, setting: str) -> Point | None:
    return next((p for p in case.points if p.method == method and p.setting == setting), None)


def _best(case: Case, prefix: str) -> Point | None:
    """The most accurate point of the methods whose name starts with ``prefix``."""
    pts = [p for p in case.points if p.method.startswith(prefix) and p.error > 0]
    return min(pts, key=lambda p: p.error) if pts else None


def _us(p: Point) -> float:
    return p.wall / p.steps * 1e6


def commentary(case: Case, rows: dict) -> list[str]:
    """What the ratios are made of, each sentence built from this run's numbers."""
    out = _formulation_commentary(case)
    doubles = [p for p in case.points if p.method.startswith("ours") and ", double" in p.method]
    if not doubles:
        return [" ".join(out)] if out else []
    best_double = min(doubles, key=lambda p: p.error)
    dop = _best(case, "scipy DOP853")
    if dop:
        # Our fastest double formulation where DOP853 reaches too (else at any double level).
        refs = [
            ref
            for _, (ref, row) in sorted(rows.items())
            if ", double" in ref and math.isfinite(row.get("scipy DOP853", math.nan))
        ]
        refs += [ref for _, (ref, _) in rows.items() if ", double" in ref]
        ref_method = refs[0] if refs else best_double.method
        mine = _at(case, ref_method, "1e-16") or best_double
        call = f", each {case.rhs_call * 1e6:.1f} µs from Python" if case.rhs_call else ""
        out.append(
            f"DOP853's steps cost {fmt(_us(dop))} µs (about 12 right-hand-side calls per step"
            f"{call}; the compiled right-hand side is the code our integrator steps with) "
            f"against {fmt(_us(mine))} µs for our order-{mine.order} Taylor step "
            f"({mine.method}, tolerance {mine.setting}); scipy raises any rtol below 100ε to "
            f"100ε, and its best error here is {dop.error:.1e} against our double's "
            f"{best_double.error:.1e}."
        )
    radau, dop6 = _at(case, "scipy Radau", "rtol 1e-06"), _at(case, "scipy DOP853", "rtol 1e-06")
    if radau and dop6:
        out.append(
            "Radau (implicit, the Jacobian compiled as well) takes "
            f"{radau.steps / dop6.steps:.0f}× DOP853's steps at rtol 1e-6 and more time per "
            "step: the case is not stiff (Radau is run on this case only; the others are "
            "conservative too, with no fast decaying modes)."
        )
    out += _ias15_commentary(case, rows, best_double)
    ha = [p for p in doubles if p.method.endswith("high accuracy")]
    if ha:
        plain = min((p for p in doubles if p not in ha), key=lambda p: p.error)
        top = min(ha, key=lambda p: p.error)
        out.append(
            f"heyoka's high-accuracy mode (compensated evaluation of the Taylor polynomials) "
            f"gives {top.error:.1e} at tolerance {top.setting} against {plain.error:.1e} for our "
            f"best plain double run; single runs, so a factor of a few either way is the "
            "round-off's own scatter."
        )
    quad = min(
        (p for p in case.points if "real128" in p.method and p.error < best_double.error),
        key=lambda p: p.wall,
        default=None,
    )
    if quad:
        best_peer = min(
            (p for p in case.points if p.error > 0 and _double_peer(p.method)),
            key=lambda p: p.error,
            default=None,
        )
        beyond = f" (no peer goes below {best_peer.error:.1e})" if best_peer else ""
        out.append(
            f"Double stops at {best_double.error:.1e}{beyond}; the cheapest real128 point below "
            f"it ({quad.method}, {quad.setting}: {quad.error:.1e}) costs "
            f"{quad.wall / best_double.wall:.0f}× that double run — real128 arithmetic is in "
            f"software, {_us(quad) / _us(best_double):.0f}× the time per step here."
        )
    out += _extended_commentary(case)
    return [" ".join(out)] if out else []


def _formulation_commentary(case: Case) -> list[str]:
    out = []
    pairs = {
        "ours rodrigues, double": (
            "ours quaternion, double",
            "the Rodrigues chart takes {s}× the quaternion's steps (the pole of tan(θ/2) at "
            "θ = π bounds its Taylor step; {extra}) at {c}× the time per step",
        ),
        "ours cayley, double": (
            "ours cartesian, double",
            "Cayley's variables take {s}× the Cartesian steps at {c}× the time per step (Ω's "
            "gradient composed with the frame tables)",
        ),
        "ours quaternion, double": (
            "ours cartesian, double",
            "the orbit-frame quaternion takes {s}× the Cartesian steps at {c}× the time per step",
        ),
        "ours elements, double": (
            "ours canonical, double",
            "Hamilton's elements take {s}× the canonical steps at {c}× the time per step "
            "(Kepler's equation and the gradient of H₂ through it, compact mode)",
        ),
    }
    for method, (base, text) in pairs.items():
        a, b = _at(case, method, "1e-16"), _at(case, base, "1e-16")
        if a and b:
            s, c = a.steps / b.steps, _us(a) / _us(b)
            extra = a.extra or "no re-basing"
            out.append(
                f"At tolerance 1e-16, {text.format(s=f'{s:.2g}', c=f'{c:.2g}', extra=extra)}."
            )
    loose_e = _at(case, "ours elements, double", "1e-6")
    loose_c = _at(case, "ours canonical, double", "1e-6")
    if loose_e and loose_c and loose_e.error < loose_c.error:
        out.append(
            f"At tolerance 1e-6 the elements are the more accurate ({loose_e.error:.1e} against "
            f"{loose_c.error:.1e}): they move by O(m/M), so the same local tolerance is a smaller "
            "error in the positions."
        )
    return out


def _ias15_commentary(case: Case, rows: dict, best_double: Point) -> list[str]:
    ias = [p for p in case.points if p.method == "REBOUND IAS15"]
    if not ias:
        return []
    out = []
    common = [
        (level, ref)
        for level, (ref, row) in sorted(rows.items())
        if math.isfinite(row.get("REBOUND IAS15", math.nan))
    ]
    if common:
        level, ref = common[0]
        mine, theirs = cheapest(case, ref, level), cheapest(case, "REBOUND IAS15", level)
        if mine and theirs:
            fewer = "fewer" if theirs.steps < mine.steps else "more"
            dearer = "dearer" if _us(theirs) > _us(mine) else "cheaper"
            out.append(
                f"At {level:.0e}, IAS15's cheapest point ({theirs.setting}) takes {theirs.steps} "
                f"steps of {fmt(_us(theirs))} µs against {mine.steps} of {fmt(_us(mine))} µs for "
                f"{mine.method} ({mine.setting}): {fewer}, {dearer} steps — an IAS15 step "
                "evaluates the forces at 7 substeps per predictor–corrector iteration, two or more "
                "iterations a step."
            )
    best = min(ias, key=lambda p: p.error)
    floors: dict[str, float] = {}
    for p in case.points:
        if p.method.startswith("ours") and ", double" in p.method:
            floors[p.method] = min(floors.get(p.method, math.inf), p.error)
    below = [m for m, e in floors.items() if e < best.error]
    out.append(
        f"Most accurate points: IAS15 {best.error:.1e} ({best.setting}); "
        + ", ".join(f"{m.removeprefix('ours ')} {e:.1e}" for m, e in floors.items())
        + ". These are round-off floors, and one run is one sample of a random walk: only "
        "factors well beyond a few mean something. "
        + (
            "IAS15's is below all of ours in double: it keeps its round-off small by "
            "compensated summation (Rein & Spiegel 2015)."
            if not below
            else f"{len(below)} of our {len(floors)} double variants "
            f"{'goes' if len(below) == 1 else 'go'} below IAS15's."
        )
    )
    tight = [p for p in ias if _eps(p) <= 1e-6]
    if len(tight) >= 2 and any(b.error > a.error for a, b in zip(tight, tight[1:], strict=False)):
        out.append(
            "Below ε = 1e-6 its error no longer falls with ε ("
            + ", ".join(f"{p.error:.0e} at {p.setting.removeprefix('ε ')}" for p in tight)
            + "): round-off, not truncation."
        )
    return out


def _double_peer(method: str) -> bool:
    return method.startswith(("scipy", "REBOUND"))


def _eps(p: Point) -> float:
    return float(p.setting.split()[1])


def _extended_commentary(case: Case) -> list[str]:
    out = []
    q, r113 = (
        _at(case, "ours quaternion, real128", "1e-32"),
        _at(case, "ours quaternion, real 113", "1e-32"),
    )
    if q and r113:
        out.append(
            f"At tolerance 1e-32, MPFR at 113 bits steps in {r113.wall / q.wall:.2g}× the time "
            "of real128 (libquadmath), with the same errors."
        )
    mp = [p for p in case.points if p.method.startswith("mpmath")]
    if mp:
        out.append(
            "mpmath's `odefun` builds each Taylor series from finite differences of Euler steps "
            "carried at (degree + 1)× the working precision, in pure Python "
            "(mpmath/calculus/odes.py): "
            + "; ".join(f"{p.setting}: {p.wall:.2f} s for {p.error:.1e}" for p in mp)
            + "."
        )
    return out


def _times(r: float) -> str:
    x = r if r >= 1 else 1 / r
    text = f"{x:.0f}×" if x >= 10 else f"{x:.2g}×"
    return f"{text} the time" if r >= 1 else f"{text} faster"
