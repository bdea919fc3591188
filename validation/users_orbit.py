"""The orbit rows of the user-path benchmarks (issue 16): Kepler + J2, Cayley 1860, Encke.

Run:  python validation/users_orbit.py [--quick]     (prints the table)

Rows (each ours ÷ its floor, timed interleaved in one process, median and spread of repeats):

1. Cartesian Kepler + J2 (case R1 of the 1860 reference values, double, tolerance ε) against a
   hand-written heyoka system with the closed-form gradient, μ and 3μJ₂R²/2 as runtime
   parameters as ours has them, r² computed once (``engine_figures._hand_written_cartesian_j2``):
   (a) the compiled step — our model's integrator and the hand-written one each take exactly
   the same number of steps (``max_steps``) from the same state; (b) a whole ``run()`` over 1000
   orbits with 101 outputs (integrator compiled and cached) against resetting the hand-written
   integrator and ``propagate_grid`` over the same outputs.
2. Cayley's 1860 formulation (r, ṙ, ρ, h, Θ, Σ, Φ, with its ρ-revolution and equatorial-stop
   terminal events) per step against our Cartesian formulation, both through ``run()`` on the
   same scene: (wall ÷ steps) ÷ (wall ÷ steps). The note gives the same ratio for the equations
   alone (each model's system as a plain heyoka integrator, no events, the same steps): what
   ρ's revolutions and the equatorial stop add is the difference.
3. Encke's formulation against REBOUND's IAS15 with REBOUNDx's J2 (``bench_ias15``'s case: e = 0.5,
   J2 = 10⁻³, 10⁴ orbits; 100 in quick mode), wall time of a whole ``run()`` against IAS15's
   ``integrate`` over the same output grid; the note gives both final position errors against
   the cached real128 reference, so that "at IAS15's error" can be judged: at tolerance ε Encke
   is the more accurate, and loosening the tolerance saves little (the steps hardly change, the
   error grows fast: see the note of row 3c). The same for our Cartesian formulation (3b), and
   Encke at tolerance 1e-14 (3c).
"""

from __future__ import annotations

import copy
import statistics
import sys
import time
from typing import Any

import bench_ias15
import engine_figures
import heyoka as hy
import numpy as np
import users_common
from bench_common import available
from users_common import Row, interleaved

import cayley_heyoka as ch
from cayley_heyoka.core.compiler import compile_model
from cayley_heyoka.core.families import FAMILIES

PERIOD = 4.97  # of case R1's orbit, roughly: spans are given in orbits


def _scene(formulation: str, orbits: int, outputs: int = 2) -> ch.Scene:
    data = engine_figures._orbit_scene(formulation).to_dict()
    data["output"]["times"] = {"start": "0", "stop": str(orbits * PERIOD), "count": outputs}
    return ch.Scene.from_dict(data)


def _decomposition(ta: Any) -> int:
    return len(ta.decomposition)


# ---------------------------------------------------------------------- 1. Cartesian + J2
def cartesian_step(quick: bool) -> Row:
    """Row 1a: the compiled step, the same number of steps on both sides."""
    scene = _scene("cartesian", 1)
    model = FAMILIES["orbit"].build(scene)
    compiled, _ = compile_model(model, scene.integrator)
    ours = copy.deepcopy(compiled.integrator)
    ours.pars[:] = np.array([float(v) for v in model.pars.values])[: len(ours.pars)]
    init = np.array([float(v) for v in model.initial_state])
    raw = engine_figures._hand_written_cartesian_j2(init.copy(), parameters=True)
    steps = 5_000 if quick else 40_000

    def stepping(ta: Any) -> Any:
        def go() -> None:
            ta.time = 0.0
            ta.state[:] = init
            res = ta.propagate_until(1e12, max_steps=steps)
            assert res[3] == steps, res

        return go

    ratios, t_ours, t_raw = interleaved(stepping(ours), stepping(raw), 5 if quick else 9)
    return Row(
        "Cartesian Kepler + J2, compiled step",
        ratios,
        1.15,
        "hand-written heyoka system (closed-form ∇Ω, μ and 3μJ₂R²/2 parameters, r² once)",
        f"{steps} steps each; {t_ours / steps * 1e9:.0f} vs {t_raw / steps * 1e9:.0f} ns/step; "
        f"heyoka decomposition {_decomposition(ours)} vs {_decomposition(raw)} entries",
    )


def cartesian_run(quick: bool) -> Row:
    """Row 1b: a whole run() against the hand-written integrator reset and propagated over the
    same output grid."""
    orbits = 100 if quick else 1000
    scene = _scene("cartesian", orbits, 101)
    model = FAMILIES["orbit"].build(scene)
    init = np.array([float(v) for v in model.initial_state])
    raw = engine_figures._hand_written_cartesian_j2(init.copy(), parameters=True)
    grid = np.linspace(0.0, orbits * PERIOD, 101)
    steps: dict[str, int] = {}

    def ours() -> None:
        steps["ours"] = ch.run(scene).counters["steps"]

    def floor() -> None:
        raw.time = 0.0
        raw.state[:] = init
        steps["raw"] = raw.propagate_grid(grid)[3]

    ratios, t_ours, t_raw = interleaved(ours, floor, 5 if quick else 9)
    return Row(
        f"Cartesian Kepler + J2, whole `run()`, {orbits} orbits, 101 outputs",
        ratios,
        1.15,
        "hand-written integrator: reset + `propagate_grid`",
        f"{t_ours * 1e3:.1f} vs {t_raw * 1e3:.1f} ms; steps {steps['ours']} vs {steps['raw']}",
    )


# ---------------------------------------------------------------------- 2. Cayley 1860
def cayley_per_step(quick: bool) -> Row:
    """Row 2: Cayley's formulation per step ÷ our Cartesian per step, both through run()."""
    orbits = 200 if quick else 5000
    cayley, cartesian = _scene("cayley", orbits), _scene("cartesian", orbits)
    counters: dict[str, dict] = {}

    def runner(scene: ch.Scene, key: str) -> Any:
        def go() -> None:
            counters[key] = ch.run(scene).counters

        return go

    ratios, t_cay, t_car = interleaved(
        runner(cayley, "cayley"), runner(cartesian, "cartesian"), 5 if quick else 7
    )
    n_cay, n_car = counters["cayley"]["steps"], counters["cartesian"]["steps"]
    per_step = [r * n_car / n_cay for r in ratios]
    entries = []
    for scene in (cayley, cartesian):
        compiled, _ = compile_model(FAMILIES["orbit"].build(scene), scene.integrator)
        entries.append(_decomposition(compiled.integrator))
    bare = _bare_step_ratio(cayley, cartesian, 5_000 if quick else 20_000, 5 if quick else 9)
    return Row(
        f"Cayley 1860 orbit (J2), per step through `run()`, {orbits} orbits",
        per_step,
        2.0,  # issue 33
        "our Cartesian formulation per step, through `run()`",
        f"{t_cay / n_cay * 1e6:.2f} vs {t_car / n_car * 1e6:.2f} µs/step; steps {n_cay} vs "
        f"{n_car} ({counters['cayley']['revolutions']} revolutions of ρ); whole runs "
        f"{statistics.median(ratios):.2f}×; heyoka decomposition {entries[0]} vs "
        f"{entries[1]} entries (Cayley's with its two terminal events); the equations alone "
        f"(bare integrators, no events) {statistics.median(bare):.2f}× "
        f"({min(bare):.2f}–{max(bare):.2f}) per step",
    )


def _bare_step_ratio(cayley: ch.Scene, cartesian: ch.Scene, steps: int, repeats: int) -> list:
    """Cayley's equations per step ÷ the Cartesian ones, each a plain heyoka integrator of the
    model's system (no terminal events, so no revolutions of ρ: the same number of steps from
    the initial state)."""
    stepping = []
    for scene in (cayley, cartesian):
        model = FAMILIES["orbit"].build(scene)
        # heyoka wants the parameters up to the last the equations use (the events' left out).
        used = [int(str(p)[1:]) for _, rhs in model.system for p in hy.get_params(rhs)]
        pars = [float(v) for v in model.pars.values[: 1 + max(used, default=-1)]]
        init = np.array([float(v) for v in model.initial_state])
        ta = hy.taylor_adaptive(model.system, init, pars=pars)

        def go(ta: Any = ta, init: np.ndarray = init) -> None:
            ta.time = 0.0
            ta.state[:] = init
            res = ta.propagate_until(1e12, max_steps=steps)
            assert res[3] == steps, res

        stepping.append(go)
    return interleaved(*stepping, repeats)[0]


# ---------------------------------------------------------------------- 3. Encke vs IAS15
def against_ias15(quick: bool) -> list[Row]:
    """Rows 3a–c: our formulations against IAS15 over the same grid (``bench_ias15``)."""
    if not (available("rebound") and available("reboundx")):
        why = 'the IAS15 rows: REBOUND and REBOUNDx are not installed (pip install -e ".[bench]")'
        users_common.SKIPPED.append(why)
        print(f"not measured: {why}", file=sys.stderr)
        return []
    n = bench_ias15.N_QUICK if quick else bench_ias15.N_FULL
    times = bench_ias15.grid(n)
    ref = bench_ias15.reference(times, check=False)
    final: dict[str, float] = {}

    def error(x: np.ndarray) -> float:
        d = np.asarray(x, dtype=bench_ias15.LD)[:, -1] - ref.x[:, len(times) - 1]
        return float(np.sqrt((d * d).sum()))

    def ias15() -> None:
        out, _ = bench_ias15.ias15(times)
        final["ias15"] = error(out[:3])

    def ours(key: str, formulation: str, **integrator: Any) -> Any:
        scene = bench_ias15.scene(formulation, times, **integrator)

        def go() -> None:
            r = ch.run(scene)
            final[key] = error(np.array([np.asarray(r[k], dtype=float) for k in "xyz"]))
            final[key + " steps"] = r.counters["steps"]

        return go

    rows = []
    cases = [
        ("Encke (tolerance ε)", "encke", "encke", {}),
        ("Cartesian (tolerance ε)", "cartesian", "cartesian", {}),
        ("Encke (tolerance 1e-14)", "encke 1e-14", "encke", {"tolerance": "1e-14"}),
    ]
    for what, key, formulation, integrator in cases:
        ratios, t_ours, t_ias = interleaved(
            ours(key, formulation, **integrator), ias15, 3 if quick else 5
        )
        extra = ""
        if formulation == "encke":
            # One more run with the rectification handler timed: its share of the wall time.
            with bench_ias15.encke_variant(bench_ias15.TimedEncke):
                timed = bench_ias15.scene(formulation, times, **integrator)
                ch.run(timed)  # warm: the timed handler's model, compiled or cached
                bench_ias15.TimedEncke.seconds = 0.0
                t0 = time.perf_counter()
                r = ch.run(timed)
                wall = time.perf_counter() - t0
            handler = bench_ias15.TimedEncke.seconds
            each = handler / max(r.counters["rectifications"], 1)
            extra = (
                f"; rectification handler {handler / wall:.0%} of the wall time "
                f"({each * 1e6:.0f} µs each)"
            )
        rows.append(
            Row(
                f"{what} vs IAS15, e = 0.5 + J2, {n} orbits",
                ratios,
                0.15,
                "REBOUND IAS15 + REBOUNDx J2 (ε = 1e-9, its default)",
                f"final |Δx|/a {final[key]:.2e} vs IAS15 {final['ias15']:.2e} "
                f"({final[key] / final['ias15']:.2g}× IAS15's); {t_ours:.2f} vs {t_ias:.2f} s; "
                f"{final[key + ' steps']} steps{extra}",
            )
        )
    return rows


def rows(quick: bool) -> list[Row]:
    """The orbit rows of the issue's table (``quick``: a smoke run in well under 30 s)."""
    out = [cartesian_step(quick), cartesian_run(quick), cayley_per_step(quick)]
    return out + against_ias15(quick)


def main(argv: list[str] | None = None) -> int:
    return users_common.main(rows, __doc__.splitlines()[0], "a smoke run (< 30 s)", argv)


if __name__ == "__main__":
    sys.exit(main())
