"""Our side of the sweeps: ``cayley_heyoka.run`` at each tolerance, its stepping timed.

Our side: ``cayley_heyoka.run`` on the scene, one compiled integrator per (formulation,
precision, tolerance) — the tolerance is a compile-time option, so each sweep point compiles
once; that compile is timed and reported apart. The wall time of a point is the stepping of
that compiled integrator over the span, with ``run``'s calls and event handling
(:class:`Stepper`); ``run``'s fixed cost on top (building the model, the cache lookup,
the copy of the integrator, the outputs) is reported in its own table: it is milliseconds,
while a double-precision sweep point steps in tens of microseconds to a few milliseconds.
"""

from __future__ import annotations

import copy
import math
import time
from collections.abc import Callable, Sequence
from typing import Any

import heyoka as hy

import cayley_heyoka as ch
from cayley_heyoka.core.engine import compile_model
from cayley_heyoka.core.families import FAMILIES
from cayley_heyoka.core.model import own_terminal

from . import timing
from .cases import LABEL, REFERENCE_TOL, TINY, with_integrator
from .records import Case, Point
from .timing import least_time, log


class Stepper:
    """``run``'s compiled integrator, stepped over the scene's span without ``run``'s fixed cost.

    The same template integrator ``run`` copies (``compiler.compile_model``), the same call
    (one ``propagate_grid`` over the output times, terminal events handled inside it) and the
    same event handling (the family's handlers: chart re-basings, revolutions of ρ); left out
    is what ``run`` does around them — building the model, the cache lookup, the copy of the
    integrator, the output evaluation — which is measured apart. The step count is checked
    against ``run``'s, or this would time something else.
    """

    def __init__(self, scene: ch.Scene, steps: int) -> None:
        self.model = FAMILIES[scene.family].build(scene)
        compiled, _ = compile_model(self.model, scene.integrator)
        self.prec = scene.integrator.precision
        self.grid = scene.output.time_grid(self.prec)
        self.ta = copy.deepcopy(compiled.integrator)
        self.steps = steps

    def __call__(self) -> float:
        """Seconds of one pass over the span."""
        model, ta, prec, grid = self.model, self.ta, self.prec, self.grid
        pars = prec.array(model.pars.values)  # handlers change them (a chart's base)
        held = len(ta.pars)
        ta.time = grid[0]
        ta.state[:] = prec.array(model.initial_state)
        ta.pars[:] = pars[:held]
        if model.terminal:
            ta.reset_cooldowns()  # the previous pass's last event must not mute the first
            handlers = own_terminal(model.terminal)

            def handle(index: int, ta: Any) -> bool:
                if handlers[index].handle(ta, pars) is not None:
                    raise RuntimeError("a terminal event stopped the timed run")
                ta.pars[:] = pars[:held]
                ta.reset_cooldowns()
                return True

            for ev in ta.t_events:
                ev.callback.target = handle
        s = time.perf_counter()
        res = ta.propagate_grid(grid)
        elapsed = time.perf_counter() - s
        if res[0] != hy.taylor_outcome.time_limit:
            raise RuntimeError(f"stepping ended with outcome {res[0]}")
        if res[3] != self.steps:
            raise RuntimeError(f"stepped {res[3]} steps where run() took {self.steps}")
        return elapsed


def ours(
    case: Case,
    formulation: str,
    data: dict,
    precision: str,
    tolerances: Sequence[str],
    t_end: Any,
    error: Callable[[ch.Result], float],
    label: str = "",
) -> dict[str, ch.Result]:
    """Sweep one formulation at one precision; adds points to ``case``, returns the results."""
    method = f"ours {formulation}, {LABEL[precision]}{label}"
    results = {}
    for tol in tolerances:
        scene = with_integrator(data, precision, tol, [0.0, t_end])
        first = ch.run(scene)  # compiles (or finds the code in heyoka's disk cache)
        compile_s = first.metadata["compile_seconds"]
        stepper = Stepper(scene, first.counters["steps"])
        run_wall = wall = math.inf
        for _ in range(timing.REPEAT):
            # Interleaved, so that a change of load on the shared machine hits both alike.
            s = time.perf_counter()
            result = ch.run(scene)
            run_wall = min(run_wall, time.perf_counter() - s)
            wall = min(wall, stepper())
            if run_wall > timing.BUDGET:
                break
        # run() does this stepping and more: a stepping time above it is the load's doing.
        wall = min(wall, run_wall)
        # run()'s own cost, from a span of one step: the same at every tolerance, so the least
        # over the sweep is the least disturbed measurement.
        tiny = with_integrator(data, precision, tol, [0.0, TINY])
        fixed = least_time(lambda tiny=tiny: ch.run(tiny), 2 * timing.REPEAT)[0]
        case.fixed_cost[method] = min(case.fixed_cost.get(method, math.inf), fixed)
        steps = result.counters["steps"]
        err = error(result)
        rebasings = result.counters.get("rebasings")
        case.points.append(
            Point(
                method,
                tol,
                steps,
                wall,
                err,
                run_wall,
                compile_s,
                f"{rebasings} re-basings" if rebasings is not None else "",
                result.metadata["order"],
            )
        )
        results[tol] = result
        log(
            f"{case.name}: {method} tol {tol}: {steps} steps, {wall * 1e3:.2f} ms "
            f"(run {run_wall * 1e3:.2f}, compile {compile_s:.2f} s), error {err:.2e}"
        )
    return results


def high_accuracy(case: Case, data: dict, formulation: str, t_end: Any, error: Callable) -> None:
    """The tightest double tolerances again with heyoka's compensated evaluation of the Taylor
    polynomials (``integrator.high_accuracy``): does our round-off floor move?"""
    d = {**data, "integrator": {"high_accuracy": True}}
    ours(case, formulation, d, "double", ("1e-14", "1e-16"), t_end, error, ", high accuracy")


def reference_check(
    case: Case, formulation: str, data: dict, t_end: Any, error: Callable, unit: str = ""
) -> None:
    """The reference's own error: another formulation (other variables, other equations) in
    real128 at the reference's tolerance, run once, untimed."""
    other = ch.run(with_integrator(data, "quad", REFERENCE_TOL, [0.0, t_end]))
    case.notes.append(
        f"The reference's own error: the {formulation} formulation in real128 at "
        f"{REFERENCE_TOL} (other variables and equations) differs from it by "
        f"{error(other):.1e}{unit}."
    )


def reference_run(data: dict, t_end: Any) -> ch.Result:
    """The real128 reference at tolerance 1e-32."""
    return ch.run(with_integrator(data, "quad", REFERENCE_TOL, [0.0, t_end]))
