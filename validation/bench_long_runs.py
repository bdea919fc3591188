"""Long runs at tolerance 1e-18: the cases whose drift keeps a shared part at the default.

Run:  python validation/benchmarks.py --only long_runs [--quick]

At the default tolerance (ε) the conservation section (:mod:`bench_conservation`) finds a
small shared part where the steps repeat: a periodic orbit, a steady rotation, a long run of one
body, a chaotic top whose truncation error does not average to zero over its motion. heyoka's
truncation error there is about 10⁻⁴ ε per step and of one sign, so it grows like n and
overtakes the walk's ε√n somewhere between 10⁶ and 10⁹ steps. A tolerance below ε raises the
Taylor order (20 → 22 at 1e-18) with the same steps, as heyoka's own outer Solar System
tutorial does for Brouwer's law. This section measures those cases again at 1e-18, with the
same ensembles, columns and floors as the conservation section, and their cost against the
default side by side.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
from bench_conservation import (
    FLAG,
    SHARED_QUANTILE,
    Case,
    estimator_scatter,
    fit,
    measure,
    step_rate,
    table_rows,
)

TIGHT = (("tolerance", "1e-18"),)


def cases(quick: bool) -> list[Case]:
    """The conservation section's cases with a shared part at the default tolerance."""
    if quick:
        return [Case("free body", "quaternion", "generic", 8, 2e4, TIGHT)]
    top = "examples/heavy_top.toml"
    return [
        Case("free body", "quaternion", "generic", 8, 1e9, TIGHT),
        Case("Kepler", "cartesian", "e = 0.5", 16, 1e8, TIGHT),
        *(Case("heavy top", f, top, 16, 1e7, TIGHT) for f in ("quaternion", "rodrigues")),
    ]


def cost(quick: bool) -> list[str]:
    """Wall time of one run at the default and at 1e-18, interleaved, least of 5."""
    import cayley_heyoka as ch

    lines = [
        "| case | steps | default (s) | 1e-18 (s) | ratio |",
        "|---|---|---|---|---|",
    ]
    steps = 2e4 if quick else 1e6
    for case in cases(quick):
        loose = Case(case.system, case.formulation, case.body, 1, steps)
        tight = Case(case.system, case.formulation, case.body, 1, steps, TIGHT)
        rate = step_rate(loose)
        scenes = [ch.Scene.from_dict(c.scene([0.0, steps / rate])) for c in (loose, tight)]
        best = [float("inf"), float("inf")]
        n = [0, 0]
        for scene in scenes:
            ch.run(scene)  # compile (or load from heyoka's cache) outside the timing
        for _ in range(5):
            for i, scene in enumerate(scenes):
                t0 = time.perf_counter()
                result = ch.run(scene)
                best[i] = min(best[i], time.perf_counter() - t0)
                n[i] = result.counters["steps"]
        lines.append(
            f"| {loose.label} | {n[0]:.3g} / {n[1]:.3g} | {best[0]:.3f} | {best[1]:.3f} | "
            f"{best[1] / best[0]:.2f} |"
        )
    return lines


def run(quick: bool, figures: Path) -> str:
    """Measure; return the Markdown of the section (no figures)."""
    wall0 = time.perf_counter()
    data = measure(cases(quick))
    fits = {c: {label: fit(e, label) for label, _ in c.quantities} for c, e in data.items()}
    floors = {m: estimator_scatter(m, 200 if quick else 1000) for m in {c.members for c in data}}
    floor_text = "; ".join(
        f"{m} members: shared (median) ≤ {f['shared'][0]:.2f}, windows shared ≤ "
        f"{f['windows_shared'][0]:.2f}"
        for m, f in sorted(floors.items())
    )
    lines = [
        "## Long runs at tolerance 1e-18",
        "",
        "The cases of the conservation section that keep a shared part at the default tolerance, "
        "run again at `tolerance = 1e-18` (Taylor order 22 instead of 20, the same steps): "
        "ensembles, columns and marks as there (⚠: exponents above "
        f"{FLAG['ensemble']} / {FLAG['windows']}, shared fractions above the "
        f"{SHARED_QUANTILE:.0%} quantile of independent walks: {floor_text}).",
        "",
        *table_rows(data, fits, floors),
        "",
        "What the tighter tolerance costs: one `run()` at each setting over the same span, "
        "timed interleaved (least of 5).",
        "",
        *cost(quick),
        "",
        f"Ensemble thread seconds: {sum(e.seconds for e in data.values()):.0f}; "
        f"steps per member: {', '.join(f'{np.mean(e.steps):.3g}' for e in data.values())}; "
        f"wall {time.perf_counter() - wall0:.0f} s.",
    ]
    return "\n".join(lines)
