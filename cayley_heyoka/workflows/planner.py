"""A speed–accuracy planner: which formulation and precision reach an error, and at what cost.

``cayley-heyoka plan SCENE --error 1e-12`` (and :func:`plan`) runs short pilots of the scene in
each formulation its family offers (``Family.formulations``) and in double and quad, and
extrapolates them over the scene's whole span with the laws of round-off in a Taylor
integrator (Brouwer 1937; docs/scenes.md, "Long runs"): after N steps the conserved
quantities drift like ``c₁ ε √N`` and the state (the phase along the motion) errs like
``c₂ ε N^{3/2}``, where ε is the precision's unit round-off. Each pilot measures, against its
own twin in more bits over the same stretch:

* its steps per unit time (so N over the span),
* ``c₁`` = the largest ``drift / (ε √n)`` and ``c₂`` = the largest ``error / (ε n^{3/2})``
  over its second half (n: the steps up to each output time; the error over the output
  variables, each relative to its largest magnitude, λ, μ, ν excepted: near a half-turn their
  error is their own conditioning's) — the worst seen, so that the prediction errs on the
  safe side; a motion near a separatrix, whose phase is sensitive, shows a larger ``c₂`` in
  its own pilot;
* the wall time of ``run()``: a fixed part (a run of one step) and a time per step.

The quad route uses its own steps and time and the double pilot's constants with quad's ε. A
span shorter than a pilot is run whole: the double route's errors are then the ones measured
against quad, not extrapolated.
The cheapest route whose predicted error meets the request is recommended; when none does, the
plan says what the closest one gives and how many bits (MPFR, ``integrator.precision =
{bits = N}``) the law asks for. validation/planner.py measures the predictions against whole
runs (validation/PLANNER.md).
"""

from __future__ import annotations

import copy
import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..core.errors import IntegrationError, SceneError
from ..core.families import FAMILIES
from ..core.scene import Scene

#: What a request bounds: the state along the motion, or the conserved quantities.
QUANTITIES = ("state", "invariants")
#: Steps of the first probe (the rate of steps) and of each pilot.
PROBE_STEPS, PILOT_STEPS = 200, 2000
#: Output times of a pilot.
PILOT_OUTPUTS = 65
#: Precisions a route may take (the double pilot is measured against its twin in quad).
PRECISIONS: dict[str, Any] = {"double": "double", "quad": "quad"}


@dataclass(frozen=True)
class Route:
    """One formulation in one precision, extrapolated over the scene's span.

    Attributes
    ----------
    formulation
        The value of the family's formulation key (None: the scene's own, for a family
        without alternatives).
    precision
        ``"double"`` or ``"quad"``.
    steps
        Predicted Taylor steps over the span.
    invariants, state
        Predicted relative drift of the conserved quantities and relative error of the state
        at the end of the span (NaN: not measured, e.g. no conserved quantity).
    seconds
        Predicted wall time of ``run()`` (its fixed part and its steps; compiling not
        included).
    constants
        ``c₁``, ``c₂`` as the pilot measured them, and its steps per unit time.
    """

    formulation: str | None
    precision: str
    steps: int
    invariants: float
    state: float
    seconds: float
    constants: Mapping[str, float] = field(default_factory=dict)

    def error(self, quantity: str) -> float:
        """The predicted error of ``quantity`` (``"state"`` or ``"invariants"``)."""
        return self.state if quantity == "state" else self.invariants


@dataclass
class Plan:
    """What :func:`plan` found: every route, the recommended one, and why.

    Attributes
    ----------
    error, quantity
        The request.
    span
        The scene's time span.
    routes
        Every route piloted, cheapest first.
    recommended
        The cheapest route predicted to meet the request, or None.
    refused
        Formulations that could not be piloted, with the reason.
    message
        The recommendation, or what it would take.
    """

    error: float
    quantity: str
    span: float
    routes: list[Route]
    recommended: Route | None
    refused: dict[str, str]
    message: str

    def for_error(self, error: float, quantity: str | None = None) -> Plan:
        """The same routes (no new pilots) recommended for another request.

        Parameters
        ----------
        error
            The largest relative error wanted at the end of the span (> 0).
        quantity
            ``"state"`` or ``"invariants"`` (default: this plan's).

        Returns
        -------
        Plan

        Raises
        ------
        ValueError
            A bad ``error`` or ``quantity``.
        """
        quantity = self.quantity if quantity is None else quantity
        _check_request(error, quantity)
        meeting = [r for r in self.routes if r.error(quantity) <= error]
        best = meeting[0] if meeting else None
        return Plan(
            error,
            quantity,
            self.span,
            self.routes,
            best,
            self.refused,
            _advice(self.routes, best, error, quantity),
        )

    def text(self) -> str:
        """A table of the routes and the recommendation, for the terminal."""
        lines = [
            f"plan for error {self.error:g} of the {self.quantity} over t = {self.span:g}",
            "",
            f"{'formulation':<14} {'precision':<9} {'steps':>12} {'state':>10} "
            f"{'invariants':>10} {'time':>10}",
        ]
        for r in self.routes:
            mark = "  <-" if r is self.recommended else ""
            lines.append(
                f"{r.formulation or '(scene)':<14} {r.precision:<9} {r.steps:>12,} "
                f"{r.state:>10.1e} {r.invariants:>10.1e} {_seconds(r.seconds):>10}{mark}"
            )
        for name, why in self.refused.items():
            lines.append(f"{name:<14} not piloted: {why}")
        return "\n".join([*lines, "", self.message])


def plan(
    scene: Scene,
    error: float,
    quantity: str = "state",
    formulations: Sequence[str] | None = None,
    progress: Callable[[str], None] | None = None,
) -> Plan:
    """Pilot the scene's formulations in double and quad and recommend the cheapest that
    reaches ``error``.

    Parameters
    ----------
    scene
        A validated scene; its span is the one planned for.
    error
        The largest relative error wanted at the end of the span (> 0).
    quantity
        ``"state"`` (the motion itself: its phase error grows fastest) or ``"invariants"``
        (the drift of the conserved quantities).
    formulations
        The formulations to try (default: every one the family offers that the scene allows).
    progress
        Called with a line of text as each pilot starts.

    Returns
    -------
    Plan

    Raises
    ------
    ValueError
        A bad ``error`` or ``quantity``, or a scene no route could pilot.
    """
    _check_request(error, quantity)
    base = scene.to_dict()
    grid = scene.output.time_grid(scene.integrator.precision)
    t0, t1 = float(grid[0]), float(grid[-1])
    span = t1 - t0
    if not span > 0:
        raise ValueError("the scene's output times span no time: there is nothing to plan")
    family = FAMILIES[scene.family]
    key, offered = family.formulations or (None, (None,))
    if formulations is not None:
        unknown = [f for f in formulations if f not in offered]
        if unknown:
            raise ValueError(f"formulations {unknown} are not among {list(offered)}")
        offered = tuple(formulations)
    routes: list[Route] = []
    refused: dict[str, str] = {}
    for formulation in offered:
        name = formulation or "(scene)"
        if progress is not None:
            progress(f"piloting {name}")
        try:
            routes += _pilot(base, key, formulation, t0, span)
        except (SceneError, IntegrationError, _Unfit) as exc:
            refused[name] = str(exc).splitlines()[0]
    if not routes:
        raise ValueError(f"no formulation could be piloted: {refused}")
    routes.sort(key=lambda r: r.seconds)
    return Plan(error, quantity, span, routes, None, refused, "").for_error(error, quantity)


def _check_request(error: float, quantity: str) -> None:
    if isinstance(error, bool) or not isinstance(error, int | float) or not error > 0:
        raise ValueError(f"error must be a number > 0, got {error!r}")
    if not math.isfinite(error):
        raise ValueError(f"error must be finite, got {error!r}")
    if quantity not in QUANTITIES:
        raise ValueError(f"quantity must be one of {QUANTITIES}, got {quantity!r}")


class _Unfit(Exception):
    """A pilot that cannot be extrapolated (it stopped, or recorded too little)."""


def _pilot(
    base: dict, key: str | None, formulation: str | None, t0: float, span: float
) -> list[Route]:
    """The double and quad routes of one formulation."""
    d = copy.deepcopy(base)
    if key is not None:
        _set(d, key, formulation)
    d.pop("events", None)
    d["integrator"] = {**base.get("integrator", {}), "precision": "double"}
    rate = _rate(d, t0, span)
    stretch = min(span, PILOT_STEPS / rate)
    # A budget far above the pilot's steps: the engine then takes no longer probe of its own
    # (a run whose first steps are not well inside its budget probes, then starts again).
    d["integrator"]["max_steps"] = 1000 * PILOT_STEPS
    d["output"] = {"times": {"start": t0, "stop": t0 + stretch, "count": PILOT_OUTPUTS}}
    # A span shorter than a pilot is run whole: its errors are measured, not extrapolated.
    whole = stretch >= span
    # The quad run is the double pilot's twin and quad's own pilot: run once.
    quad_run = _recorded(_with(d, "quad"))
    double = _measure(_with(d, "double"), _recorded(_with(d, "double")), quad_run[0], whole)
    # Quad's own steps and time; its constants are double's (its twin would need MPFR).
    quad = _measure(_with(d, "quad"), quad_run, None, whole)
    routes = []
    for precision, m in (("double", double), ("quad", quad)):
        eps = m["eps"]
        steps = m["steps"] if whole else max(1, round(m["rate"] * span))
        c1, c2 = double["c1"], double["c2"]
        invariants = max(c1 * eps * math.sqrt(steps), eps) if not math.isnan(c1) else math.nan
        state = max(c2 * eps * steps**1.5, eps)
        if whole and precision == "double":
            state = max(m["state"], eps)
            invariants = max(m["drift"], eps) if not math.isnan(m["drift"]) else math.nan
        routes.append(
            Route(
                formulation,
                precision,
                steps,
                invariants,
                state,
                m["fixed"] + m["per_step"] * steps,
                {"c1": c1, "c2": c2, "steps_per_time": m["rate"]},
            )
        )
    return routes


def _rate(d: dict, t0: float, span: float) -> float:
    """Steps per unit time over the first :data:`PROBE_STEPS` steps: stretches growing
    eightfold from span/2²⁰ until one needs more steps (the engine refuses a stretch whose
    first steps show it needs more than ten times its budget)."""
    probe = copy.deepcopy(d)
    probe["integrator"]["max_steps"] = PROBE_STEPS
    stretch = span / 2**20
    while True:
        probe["output"] = {"times": {"start": t0, "stop": t0 + stretch, "count": 2}}
        times: list[float] = []
        result = _run(probe, progress=times.append)
        if result.status != 0 or stretch >= span:
            reached = (times[-1] if times else t0) - t0
            if not reached > 0:
                raise _Unfit("the probe did not advance")
            return len(times) / reached
        stretch = min(span, 8 * stretch)


def _with(d: dict, precision: str) -> dict:
    out = copy.deepcopy(d)
    out["integrator"]["precision"] = PRECISIONS[precision]
    return out


def _recorded(d: dict) -> tuple[Any, list[float]]:
    """A run of ``d`` and the time after each of its steps."""
    times: list[float] = []
    return _run(d, progress=times.append), times


def _measure(
    mine: dict, recorded: tuple[Any, list[float]], truth: Any | None, whole: bool
) -> dict[str, float]:
    """One pilot (``recorded``: its run of ``mine``): its rate of steps and wall per step, and
    with a ``truth`` in more bits the constants of the two laws and, for a ``whole`` span, the
    largest errors themselves."""
    result, times = recorded
    scene = Scene.from_dict(mine)
    eps = float(scene.integrator.precision.epsilon)
    steps = result.counters["steps"]
    t = np.asarray(result.t, dtype=float)
    if steps < 1 or (not whole and (steps < 16 or len(t) < 8)):
        raise _Unfit(f"the pilot took {steps} steps only")
    # n(t): the progress callback reports the time after each step.
    n = np.interp(t, np.asarray(times, dtype=float), np.arange(1, len(times) + 1), left=1)
    late = n >= n[-1] / 2
    # A run costs a fixed part (building, the cache lookup, the copy of the integrator, the
    # outputs) and its steps: timed apart, the least of a few, so that neither is charged to
    # the other when the span is extrapolated.
    t0 = float(t[0])
    first = copy.deepcopy(mine)
    first["output"] = {"times": {"start": t0, "stop": t0 + (t[1] - t[0]) / 64, "count": 2}}
    fixed, wall = _least(Scene.from_dict(first)), _least(scene)
    out = {
        "eps": eps,
        "steps": steps,
        "rate": steps / (t[-1] - t[0]),
        "fixed": fixed,
        "per_step": max(wall - fixed, 0.0) / steps,
    }
    if truth is None:
        return out
    skip = FAMILIES[scene.family].build(scene).unbounded
    error = _state_error(result, truth, skip)
    out["state"] = float(np.max(error))
    out["c2"] = float(np.max(error[late] / (eps * n[late] ** 1.5)))
    drifts = [
        np.max(np.abs(np.asarray(result.drift(k), dtype=float)).reshape(len(t), -1), axis=1)
        for k in result.conserved
    ]
    out["c1"] = out["drift"] = math.nan
    if drifts:
        worst = np.max(np.array(drifts), axis=0)
        out["c1"] = float(np.max(worst[late] / (eps * np.sqrt(n[late]))))
        out["drift"] = float(np.max(worst))
    return out


def _least(scene: Scene, repeats: int = 3, enough: float = 0.5) -> float:
    """The least wall time of ``run()`` of a built scene (compiled: the stepping and the
    outputs, as a user's run pays them; not parsing the scene, which a user's run of the same
    scene object does not repeat), over up to ``repeats`` runs: fewer once they have taken
    ``enough`` seconds, where a run is long against the machine's jitter."""
    from ..core.engine import run

    best, spent = math.inf, 0.0
    for _ in range(repeats):
        started = time.perf_counter()
        run(scene, raise_on_failure=False)
        took = time.perf_counter() - started
        best, spent = min(best, took), spent + took
        if spent >= enough:
            break
    return best


def _state_error(result: Any, reference: Any, skip: Sequence[str] = ()) -> np.ndarray:
    """The largest relative difference over the output variables both runs report finite,
    each scaled by its largest magnitude (at least 1); not those in ``skip``, a model's
    unbounded ones (λ, μ, ν near a half-turn: their error there is their conditioning's)."""
    worst = np.zeros(len(result.t))
    for name, values in result.variables.items():
        if name not in reference.variables or name in skip:
            continue
        shape = (len(result.t), -1)
        a = np.asarray(values).reshape(shape)
        b = np.asarray(reference.variables[name]).ravel()
        if reference.precision != result.precision:
            # The difference in the run's own type: in double it would round to 0.
            b = result.precision.from_text(reference.precision.to_text(b))
        b = b.reshape(shape)
        diff = np.abs(a - b).astype(float)
        if not (np.all(np.isfinite(diff)) and np.all(np.isfinite(b.astype(float)))):
            continue
        scale = max(1.0, float(np.max(np.abs(b.astype(float)))))
        worst = np.maximum(worst, np.max(diff, axis=1) / scale)
    return worst


def _run(d: Mapping[str, Any], progress: Callable[[Any], None] | None = None) -> Any:
    from ..core.engine import run

    result = run(Scene.from_dict(d), progress, raise_on_failure=False)
    if result.status != 0 and "max_steps" not in result.message:
        raise _Unfit(result.message)
    return result


def _set(d: dict, key: str, value: Any) -> None:
    table, name = key.split(".")
    d.setdefault(table, {})[name] = value


def _advice(routes: list[Route], best: Route | None, error: float, quantity: str) -> str:
    if best is not None:
        return (
            f"recommended: {best.formulation or 'the scene as written'} in {best.precision} "
            f"(predicted {quantity} error {best.error(quantity):.1e}, about "
            f"{_seconds(best.seconds)})"
        )
    closest = min(routes, key=lambda r: r.error(quantity))
    text = (
        f"no route reaches {error:g}: the closest, {closest.formulation or 'the scene'} in "
        f"{closest.precision}, predicts {closest.error(quantity):.1e} in about "
        f"{_seconds(closest.seconds)}"
    )
    c = closest.constants["c2" if quantity == "state" else "c1"]
    if math.isfinite(c) and c > 0:
        power = 1.5 if quantity == "state" else 0.5
        needed = error / (c * closest.steps**power)
        bits = math.ceil(-math.log2(needed)) + 4
        text += (
            f"; the law asks for about {bits} bits (integrator.precision = {{bits = {bits}}}, "
            "MPFR, slower per step and not timed here)"
        )
    return text


def _seconds(s: float) -> str:
    if s < 0.01:
        return f"{1e3 * s:.2g} ms"
    if s < 1:
        return f"{1e3 * s:.0f} ms"
    if s < 3600:
        return f"{s:.1f} s"
    return f"{s / 3600:.1f} h"
