"""Work–precision: error against wall time over a tolerance sweep, ours and the peers side by side.

Run:  python validation/bench_work_precision.py [--quick] [--out PATH]
      (or through the driver: python validation/benchmarks.py --only work_precision)

Cases (spans kept modest; the e = 0.5, 10⁴-orbit IAS15 accuracy study is another section's):

* ``free_regular``, ``free_separatrix`` — torque-free bodies of validation/rotation_cases.py (the
  generic body and the one 1e-6 from the separatrix), 20 periods, against the closed form
  ``cayley_heyoka.reference.FreeRigidBody``;
* ``heavy_top`` — the bundled examples/heavy_top.toml over t = 50, against a real128 run;
* ``orbit_j2`` — a J2 orbit at e = 0.1 over 100 orbits, against a real128 Cartesian run;
* ``planets`` — the predominant-mass system of examples/planets.toml over 100 inner orbits,
  against a real128 canonical run;
* ``free_extended`` — the generic body over a short span in extended precision: real128,
  MPFR at 113 and 256 bits, mpmath's ``odefun``.

Our side: ``cayley_heyoka.run`` on the scene, one compiled integrator per (formulation,
precision, tolerance) — the tolerance is a compile-time option, so each sweep point compiles
once; that compile is timed and reported apart. The wall time of a point is the stepping of
that compiled integrator over the span, with ``run``'s calls and event handling
(:class:`Stepper`); ``run``'s fixed cost on top (building the model, the cache lookup,
the copy of the integrator, the outputs) is reported in its own table: it is milliseconds,
while a double-precision sweep point steps in tens of microseconds to a few milliseconds.

Peers, in the same process: scipy's ``solve_ivp`` (DOP853; Radau once, to check stiffness) on
the same equations, their right-hand side compiled by heyoka into a ``cfunc`` (so scipy pays
only its own per-call Python overhead, not a slow numpy right-hand side); mpmath's ``odefun``
(``free_extended``); REBOUND's IAS15 with REBOUNDx's ``gravitational_harmonics`` for J2 and plain
N-body gravity for the planets. A peer that is not installed is reported as such.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections.abc import Sequence
from pathlib import Path

HERE = Path(__file__).resolve().parent
if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))

from bench_common import Curve, fmt, ratios_at_equal_error  # noqa: E402
from work_precision_bench import timing  # noqa: E402
from work_precision_bench.cases import (  # noqa: E402
    LABEL,
)
from work_precision_bench.orbit_runs import orbit_j2, planets  # noqa: E402
from work_precision_bench.records import Case, Point  # noqa: E402
from work_precision_bench.rotation_runs import free_body, free_extended, heavy_top  # noqa: E402
from work_precision_bench.timing import log  # noqa: E402


# ---------------------------------------------------------------------------- rendering
def curves(case: Case) -> list[Curve]:
    """Each method's (wall time, error) points: what a user waits for — our whole ``run()``
    (model build, output evaluation), a peer's whole call."""
    by: dict[str, Curve] = {}
    for p in case.points:
        c = by.setdefault(p.method, Curve(p.method, [], [], []))
        c.times.append(p.run_wall if p.run_wall is not None else p.wall)
        c.errors.append(p.error)
        c.settings.append(p.setting)
    return list(by.values())


def ratio_rows(case: Case, cs: list[Curve]) -> dict[float, tuple[str, dict]]:
    """Per level: the reference method — our fastest double formulation there, else our
    fastest real128 one, else real 256 — and every method's time over its time."""
    out = {}
    for level in case.levels:
        ref = None
        for precision in ("double", "quad", "real256"):
            mine = [
                (c.time_at(level), c)
                for c in cs
                if c.method.startswith("ours") and f", {LABEL[precision]}" in c.method
            ]
            mine = [(t, c) for t, c in mine if math.isfinite(t)]
            if mine:
                ref = min(mine, key=lambda x: x[0])[1]
                break
        if ref is None:
            continue
        row = ratios_at_equal_error(cs, ref.method, [level])[0]
        row.pop("error")
        out[level] = (ref.method, row)
    return out


def cheapest(case: Case, method: str, level: float) -> Point | None:
    """The method's fastest sweep point at least as accurate as ``level``."""
    pts = [p for p in case.points if p.method == method and p.error <= level]
    pts = [p for p in pts if math.isfinite(p.wall)]
    return min(pts, key=lambda p: p.wall) if pts else None


def render(case: Case, figures: Path) -> str:
    cs = curves(case)
    figure = f"bench_wp_{case.name}.png"
    plot(case, cs, figures / figure)
    lines = [
        f"### {case.name}",
        "",
        f"{case.title}. Error: {case.error_measure}, against {case.reference}.",
        "",
        f"![work–precision, {case.name}](figures/{figure})",
        "",
    ]
    methods = [c.method for c in cs]
    rows = ratio_rows(case, cs)
    if rows:
        shown = [
            m for m in methods if any(math.isfinite(r[1].get(m, math.nan)) for r in rows.values())
        ]
        lines += [
            "Wall time of a whole run at equal error (ours: `run()` with its model build and "
            "output evaluation; a peer: its whole call) over the reference method's (– : the "
            "method's sweep does not reach that error):",
            "",
            "| error | relative to | " + " | ".join(shown) + " |",
            "|---|---|" + "---|" * len(shown),
        ]
        for level, (ref, row) in rows.items():
            lines.append(
                f"| {level:.0e} | {ref} | "
                + " | ".join(fmt(row.get(m, math.nan)) for m in shown)
                + " |"
            )
        lines.append("")
    lines += headline(case, rows)
    lines += ["", *commentary(case, rows)]
    lines += [""] + [f"* {n}" for n in case.notes + case.missing]
    lines += [
        "",
        "<details><summary>sweep points</summary>",
        "",
        "| method | setting | steps | order | wall (ms) | error | whole run() (ms) | compile (s) "
        "| notes |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for p in case.points:
        lines.append(
            f"| {p.method} | {p.setting} | {p.steps if p.steps is not None else '–'} | "
            f"{p.order or '–'} | {fmt(p.wall * 1e3)} | {p.error:.2e} | "
            f"{fmt(p.run_wall * 1e3) if p.run_wall is not None else '–'} | "
            f"{f'{p.compile:.2f}' if p.compile is not None else '–'} | {p.extra} |"
        )
    lines += ["", "</details>", ""]
    return "\n".join(lines)


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


def plot(case: Case, cs: list[Curve], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.6))
    for c in cs:
        # In sweep order (tolerance tightening): where round-off takes over, the error turns
        # back, and the line shows it.
        pts = [(e, t) for e, t in zip(c.errors, c.times, strict=True) if e > 0 and math.isfinite(t)]
        if not pts:
            continue
        style = "-o" if c.method.startswith("ours") else "--s"
        ax.loglog([p[0] for p in pts], [p[1] * 1e3 for p in pts], style, ms=4, label=c.method)
    ax.set_xlabel("error at the final time")
    ax.set_ylabel("wall time (ms)")
    ax.set_title(f"work–precision: {case.name}")
    ax.invert_xaxis()
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="best")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def fixed_cost_table(cases: Sequence[Case]) -> list[str]:
    lines = [
        "| case | method | run() over one step (ms) |",
        "|---|---|---|",
    ]
    for case in cases:
        for method, cost in case.fixed_cost.items():
            lines.append(f"| {case.name} | {method} | {fmt(cost * 1e3)} |")
    return lines


# ---------------------------------------------------------------------------- driver
def run(quick: bool, figures: Path) -> str:
    """The Markdown body of the work–precision section; plots into ``figures``."""
    figures.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    timing.REPEAT = 2 if quick else 5  # the smoke run must stay within seconds
    periods = 2 if quick else 20
    cases = [
        free_body("free_regular", "generic", periods, quick),
        free_body("free_separatrix", "separatrix_p6", periods, quick),
        heavy_top(quick),
        orbit_j2(quick),
        planets(quick),
        free_extended(quick),
    ]
    body = [
        "## Work–precision",
        "",
        INTRO,
        "",
        *[render(c, figures) for c in cases],
        "### Fixed cost of a run",
        "",
        "What one `cayley_heyoka.run` call costs besides stepping (building the model, the "
        "cache lookup, the copy of the compiled integrator, evaluating the outputs), measured "
        "as a run over a span of 1e-6 (one step). It is not in the wall times above; a short "
        "run pays it in full.",
        "",
        *fixed_cost_table(cases),
    ]
    log(f"total {time.perf_counter() - t0:.0f} s")
    return "\n".join(body)


INTRO = (
    "Error at the final time against wall time over a sweep of each method's tolerance, every "
    "method in one process on the same machine state. **Ours**: `cayley_heyoka.run` with "
    "`integrator.tolerance` swept, output at the start and end only. The tolerance is compiled "
    "in, so each point compiles once; that compile is timed apart (the `compile` column, small "
    "when heyoka's disk cache already had the code) and excluded. A point's wall time is the "
    "stepping: the compiled integrator `run` uses, stepped over the span with `run`'s calls and "
    "event handling (chart re-basings, revolutions of ρ), the least of up to 5 repeats, its "
    "step count checked equal to `run`'s. What `run` costs besides — building the model, the "
    "cache lookup, the copy of the integrator, the outputs — is the *whole run()* column, and "
    "the table at the end. Errors come from `run`'s results. **scipy** `solve_ivp` integrates "
    "the same equations, the right-hand side (and for Radau the Jacobian) compiled by heyoka "
    "into a `cfunc` — fair to scipy: it pays its own Python loop, not a slow numpy right-hand "
    "side; `atol = rtol × |v|` for each vector v of the state at t = 0 (rates, quaternion, "
    "position, velocity, momentum). **REBOUND IAS15**: `epsilon` 1e-2 … 1e-8 and its default, "
    "`adaptive_mode` at its default; only `integrate` is timed. **mpmath** `odefun` (its "
    "Taylor method, pure Python) on `free_extended`. The ratio tables divide each method's time "
    "at equal error (log–log interpolation between sweep points; – where its sweep does not "
    "reach the level) by that of our fastest double formulation, or our fastest real128 one "
    "where double does not reach the level. Wall times come from a 2-core machine shared with "
    "other jobs: read the ratios, measured side by side, not the absolute times."
)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--out", type=Path, default=HERE / "BENCHMARKS.md")
    args = parser.parse_args(argv)
    import benchmarks

    return benchmarks.main(
        ["--only", "work_precision", "--out", str(args.out)] + (["--quick"] if args.quick else [])
    )


if __name__ == "__main__":
    sys.exit(main())
