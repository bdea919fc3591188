"""The report writer: a case's Markdown (its ratio table, sweep points, figure link), the table
of run()'s fixed cost, and the section around them."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

from bench_common import Curve, fmt, ratios_at_equal_error

from .cases import LABEL
from .commentary import commentary, headline
from .plots import plot
from .records import Case

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


def fixed_cost_table(cases: Sequence[Case]) -> list[str]:
    lines = [
        "| case | method | run() over one step (ms) |",
        "|---|---|---|",
    ]
    for case in cases:
        for method, cost in case.fixed_cost.items():
            lines.append(f"| {case.name} | {method} | {fmt(cost * 1e3)} |")
    return lines


def section(cases: Sequence[Case], figures: Path) -> str:
    """The Markdown body of the work–precision section from the cases run; plots into
    ``figures``."""
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
    return "\n".join(body)
