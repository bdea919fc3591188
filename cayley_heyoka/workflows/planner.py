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

Every pilot is the user's scene: the family translates it to each formulation
(:meth:`~cayley_heyoka.core.families.Family.in_formulation`, which keeps every option the target
takes), :func:`~cayley_heyoka.core.closed_form.with_precision` sets the route's precision and
tolerance, and only the output times (a stretch from the scene's first time, resolved in double)
and the step budget are the pilot's own. A route is a complete recommendation — formulation,
precision and tolerance: the laws are those of round-off, so a route keeps the scene's tolerance
where it is at most its precision's ε and takes ``"auto"`` (the precision's own) otherwise, and
says so. A route whose steps exceed the scene's ``integrator.max_steps`` (or that the engine's
estimate from the first steps would refuse) is marked and not recommended.

The cheapest runnable route whose predicted error meets the request is recommended; when none
does, the plan says what the closest one gives and how many bits (MPFR, ``integrator.precision =
{bits = N}``) the law asks for. validation/planner.py measures the predictions against whole
runs (validation/PLANNER.md).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from decimal import Decimal
from fractions import Fraction
from typing import Any

import numpy as np

from ..core.closed_form import with_precision
from ..core.errors import IntegrationError, SceneError
from ..core.families import FAMILIES, Family
from ..core.precision import MAX_BITS, Number, Precision, exact_fraction, number_argument, shown
from ..core.scene import TOLERANCE_FLOOR, Scene, require_scene

#: What a request bounds: the state along the motion, or the conserved quantities.
QUANTITIES = ("state", "invariants")
#: Steps of the first probe (the rate of steps) and of each pilot.
PROBE_STEPS, PILOT_STEPS = 200, 2000
#: Output times of a pilot.
PILOT_OUTPUTS = 65
#: Precisions a route may take (the double pilot is measured against its twin in quad).
PRECISIONS: dict[str, Any] = {"double": "double", "quad": "quad"}


class RequestError(ValueError):
    """A bad request to :func:`plan` (not the scene's fault), naming the argument.

    Attributes
    ----------
    parameter
        ``"error"``, ``"quantity"`` or ``"formulations"``.
    rule
        What it must be, and what it was.
    """

    def __init__(self, parameter: str, rule: str) -> None:
        self.parameter, self.rule = parameter, rule
        super().__init__(f"{parameter}: {rule}")


@dataclass(frozen=True)
class Route:
    """One formulation in one precision and tolerance, extrapolated over the scene's span.

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
    tolerance
        The route's ``integrator.tolerance`` as it is to be written: ``"auto"`` (the
        precision's ε) or the scene's own (kept where it is at most the precision's ε).
    over_budget
        Why ``run`` would not carry the route through with the scene's
        ``integrator.max_steps`` ('' when it would); such a route is never recommended.
    """

    formulation: str | None
    precision: str
    steps: int
    invariants: float
    state: float
    seconds: float
    constants: Mapping[str, float] = field(default_factory=dict)
    tolerance: str = "auto"
    over_budget: str = ""

    def error(self, quantity: str) -> float:
        """The predicted error of ``quantity`` (``"state"`` or ``"invariants"``)."""
        return self.state if quantity == "state" else self.invariants

    @property
    def runnable(self) -> bool:
        """Whether ``run`` carries the route through within the scene's step budget."""
        return not self.over_budget


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
        The cheapest runnable route predicted to meet the request, or None.
    refused
        Formulations that could not be piloted, with the reason.
    message
        The recommendation, or what it would take.
    conserved
        The scene's conserved quantities (none: ``"invariants"`` cannot be asked for).
    scene
        The scene planned for (:meth:`scene_for` builds a route's run of it).
    """

    error: float
    quantity: str
    span: float
    routes: list[Route]
    recommended: Route | None
    refused: dict[str, str]
    message: str
    conserved: tuple[str, ...] = ()
    scene: Scene | None = None

    def for_error(self, error: Any, quantity: str | None = None) -> Plan:
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
        RequestError
            A bad ``error`` or ``quantity`` (a ValueError).
        """
        quantity = self.quantity if quantity is None else quantity
        wanted = _request(error, quantity, self.conserved)
        meeting = [r for r in self.routes if r.runnable and r.error(quantity) <= wanted]
        best = meeting[0] if meeting else None
        return Plan(
            wanted,
            quantity,
            self.span,
            self.routes,
            best,
            self.refused,
            _advice(self.routes, best, wanted, quantity, self.scene),
            self.conserved,
            self.scene,
        )

    def scene_for(self, route: Route) -> Scene:
        """The scene planned for, as ``route`` runs it: in its formulation, precision and
        tolerance, every other option as the scene has it."""
        if self.scene is None:
            raise ValueError("this plan does not hold its scene")
        return _variant(self.scene, FAMILIES[self.scene.family], route.formulation, route.precision)

    def text(self) -> str:
        """A table of the routes and the recommendation, for the terminal."""
        lines = [
            f"plan for error {self.error:g} of the {self.quantity} over t = {self.span:g}",
            "",
            f"{'formulation':<14} {'precision':<9} {'tolerance':<10} {'steps':>14} "
            f"{'state':>10} {'invariants':>10} {'time':>10}",
        ]
        for r in self.routes:
            mark = "  <-" if r is self.recommended else ""
            if not r.runnable:
                mark = "  over integrator.max_steps"
            lines.append(
                f"{r.formulation or '(scene)':<14} {r.precision:<9} {r.tolerance:<10} "
                f"{r.steps:>14,} {r.state:>10.1e} {r.invariants:>10.1e} "
                f"{_seconds(r.seconds):>10}{mark}"
            )
        for name, why in self.refused.items():
            lines.append(f"{name:<14} not piloted: {why}")
        return "\n".join([*lines, "", self.message])


def plan(
    scene: Scene,
    error: Any,
    quantity: str = "state",
    formulations: Sequence[str] | None = None,
    progress: Callable[[str], None] | None = None,
) -> Plan:
    """Pilot the scene's formulations in double and quad and recommend the cheapest that
    reaches ``error``.

    Parameters
    ----------
    scene
        A validated scene; its span is the one planned for, and every pilot is this scene in
        a route's formulation, precision and tolerance.
    error
        The largest relative error wanted at the end of the span: a number > 0 that a double
        holds (an int, float, :class:`~fractions.Fraction`, :class:`~decimal.Decimal`, numpy
        scalar or decimal text).
    quantity
        ``"state"`` (the motion itself: its phase error grows fastest) or ``"invariants"``
        (the drift of the conserved quantities; refused for a scene that conserves none).
    formulations
        The formulations to try (default: the scene's own and every other the family offers).
    progress
        Called with a line of text as each pilot starts.

    Returns
    -------
    Plan

    Raises
    ------
    RequestError
        A bad ``error``, ``quantity`` or ``formulations`` (a ValueError naming it).
    ValueError
        A scene no route could pilot (:class:`SceneError` for the scene's own fields).
    TypeError
        ``scene`` is not a :class:`Scene`.
    """
    from ..core.engine import model_of

    scene = require_scene(scene)
    family = FAMILIES[scene.family]
    own = family.formulation_of(scene)
    _, offered = family.formulations or (None, (None,))
    if own not in offered:
        offered = (own, *offered)
    offered = _chosen(formulations, offered)
    conserved = tuple(model_of(scene).conserved)
    wanted = _request(error, quantity, conserved)
    grid = scene.time_grid
    # The span in the run's precision: in double 1e15 + 1e3 - 1e15 is exact.
    span = float(grid[-1] - grid[0])
    if not span > 0:
        raise SceneError("output.times", "span no time: there is nothing to plan")
    if not math.isfinite(span):
        raise SceneError("output.times", "span more time than a double holds: too long to plan")
    routes: list[Route] = []
    refused: dict[str, str] = {}
    for formulation in offered:
        name = formulation or "(scene)"
        if progress is not None:
            progress(f"piloting {name}")
        try:
            routes += _pilot(scene, family, formulation, span)
        except (SceneError, IntegrationError, _Unfit) as exc:
            refused[name] = str(exc).splitlines()[0]
    if not routes:
        why = "; ".join(f"{name}: {reason}" for name, reason in refused.items())
        raise ValueError(f"no formulation could be piloted: {why}")
    routes.sort(key=lambda r: r.seconds)
    draft = Plan(wanted, quantity, span, routes, None, refused, "", conserved, scene)
    return draft.for_error(wanted, quantity)


def _chosen(formulations: Sequence[str] | None, offered: tuple) -> tuple:
    """The formulations asked for, each once, in the order given."""
    if formulations is None:
        return offered
    if isinstance(formulations, str) or not isinstance(formulations, Sequence):
        raise RequestError(
            "formulations",
            f"must be a list of names, got {formulations!r} (a list: [{formulations!r}])",
        )
    names = list(dict.fromkeys(formulations))
    if not names:
        raise RequestError("formulations", f"names none; choose among {list(offered)}")
    unknown = [f for f in names if f not in offered]
    if unknown:
        raise RequestError("formulations", f"{unknown} are not among {list(offered)}")
    return tuple(names)


def _request(error: Any, quantity: str, conserved: tuple[str, ...]) -> float:
    """The request checked: ``error`` as a double (a number > 0 in a double's range, read
    exactly first), ``quantity`` one that the scene has."""
    if not isinstance(quantity, str) or quantity not in QUANTITIES:
        raise RequestError("quantity", f"must be one of {QUANTITIES}, got {quantity!r}")
    if quantity == "invariants" and not conserved:
        raise RequestError(
            "quantity",
            "'invariants' bounds the drift of the conserved quantities, and this scene "
            "conserves none (no energy, momentum or conserved monitor): ask for the state",
        )
    try:
        value = exact_fraction(number_argument(error, "error", positive=True))
    except (TypeError, ValueError) as exc:  # one message for every bad request number
        raise RequestError("error", str(exc).removeprefix("error ")) from None
    try:
        wanted = float(value)
    except OverflowError:
        wanted = math.inf
    if not 0 < wanted < math.inf:
        raise RequestError(
            "error",
            f"must be a relative error a double holds (5e-324 … 1.8e308), got {shown(error)}",
        )
    return wanted


class _Unfit(Exception):
    """A pilot that cannot be extrapolated (it stopped, or recorded too little)."""


def _route_tolerance(scene: Scene, prec: Precision) -> Number | None:
    """The tolerance a route in ``prec`` runs with: the scene's where it is at most ``prec``'s ε
    (and above its floor), else None ("auto"): the laws extrapolated are round-off's."""
    tolerance = scene.integrator.tolerance
    if tolerance is None:
        return None
    eps = Fraction(2) ** (1 - prec.bits)
    value = exact_fraction(tolerance)
    return tolerance if eps * TOLERANCE_FLOOR <= value <= eps else None


def _variant(scene: Scene, family: Family, formulation: str | None, precision: str) -> Scene:
    """The user's scene as a route runs it: in ``formulation``, ``precision`` and the route's
    tolerance, every other option kept."""
    base = scene
    if formulation is not None and formulation != family.formulation_of(scene):
        base = Scene.from_dict(family.in_formulation(scene, formulation))
    prec = Precision.from_spec(PRECISIONS[precision])
    return with_precision(base, prec, _route_tolerance(scene, prec))


def _window(
    scene: Scene,
    start: Number,
    length: float,
    count: int,
    max_steps: int,
    stop: Number | None = None,
) -> Scene:
    """``scene`` over ``count`` output times from ``start`` (as the scene writes it) over
    ``length``, or to ``stop`` as written, with the step budget ``max_steps``: the pilot's own
    part, everything else the scene's.

    The times between are doubles (the coarsest precision piloted) written exactly, so that a
    pilot and its twin in more bits are compared at the same times; they are at least two
    units in the last place apart, so that they are distinct in every precision (a stretch of
    1e-3 from t = 1e15 is not, in double)."""
    first = float(exact_fraction(start))
    last = float(exact_fraction(stop)) if stop is not None else first + length
    step = max((last - first) / (count - 1), 2 * math.ulp(max(abs(first), abs(last))))
    if stop is None:
        last = first + step * (count - 1)
    between = [str(Decimal(first + k * step)) for k in range(1, count - 1)]
    times = [start, *between, stop if stop is not None else str(Decimal(last))]
    return _over(scene, times, max_steps)


def _over(scene: Scene, times: list[Number], max_steps: int) -> Scene:
    return scene.derive({"output.times": times, "integrator.max_steps": max_steps})


def _pilot(scene: Scene, family: Family, formulation: str | None, span: float) -> list[Route]:
    """The double and quad routes of one formulation."""
    from ..core.engine import preflight
    from ..core.span_probe import ESTIMATE_MARGIN

    variants = {p: _variant(scene, family, formulation, p) for p in PRECISIONS}
    for variant in variants.values():
        preflight(variant)  # the refusals of a run of the route, before any pilot
    start, stop = scene.output.span()
    early = _rate(variants["double"], start, span)
    stretch = min(span, PILOT_STEPS / early)
    # A span shorter than a pilot is run whole: its errors are measured, not extrapolated.
    whole = stretch >= span
    # A budget far above the pilot's steps: the engine then takes no longer probe of its own
    # (a run whose first steps are not well inside its budget probes, then starts again).
    budget = 1000 * PILOT_STEPS
    pilots = {
        p: _window(v, start, stretch, PILOT_OUTPUTS, budget, stop if whole else None)
        for p, v in variants.items()
    }
    # The quad run is the double pilot's twin and quad's own pilot: run once.
    quad_run = _recorded(pilots["quad"])
    double = _measure(pilots["double"], _recorded(pilots["double"]), quad_run[0], whole)
    # Quad's own steps and time; its constants are double's (its twin would need MPFR).
    quad = _measure(pilots["quad"], quad_run, None, whole)
    max_steps = scene.integrator.max_steps
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
        # The engine refuses a span whose first steps, extrapolated, need more than
        # ESTIMATE_MARGIN times the budget; the probe's rate is such a first-steps rate.
        first_steps = early * span * m["rate"] / double["rate"]
        over = ""
        if steps > max_steps:
            over = f"about {steps:,} steps, more than integrator.max_steps = {max_steps:,}"
        elif first_steps > ESTIMATE_MARGIN * max_steps:
            over = (
                f"its first steps extrapolate to about {first_steps:.3g} steps, more than "
                f"{ESTIMATE_MARGIN} times integrator.max_steps = {max_steps:,}: run refuses it"
            )
        tolerance = variants[precision].integrator.tolerance
        routes.append(
            Route(
                formulation,
                precision,
                steps,
                invariants,
                state,
                m["fixed"] + m["per_step"] * steps,
                {"c1": c1, "c2": c2, "steps_per_time": m["rate"]},
                "auto" if tolerance is None else str(tolerance),
                over,
            )
        )
    return routes


def _rate(scene: Scene, start: Number, span: float) -> float:
    """Steps per unit time over the first :data:`PROBE_STEPS` steps: stretches growing
    eightfold from span/2²⁰ until one needs more steps (the engine refuses a stretch whose
    first steps show it needs more than ten times its budget), or until the stretch that
    the scene's ``integrator.max_step`` lets a probe's budget cover (the engine refuses a
    longer one)."""
    step = scene.integrator.max_step
    cap = span if step is None else min(span, PROBE_STEPS / 2 * float(exact_fraction(step)))
    stretch = min(span / 2**20, cap)
    while True:
        whole = stretch >= span
        probe = _window(
            scene, start, stretch, 2, PROBE_STEPS, scene.output.span()[1] if whole else None
        )
        times: list[float] = []
        try:
            result = _run(probe, progress=times.append)
        except SceneError as exc:
            if exc.field != "output.times":
                raise
            raise _Unfit(
                f"the first {stretch:.3g} time units of the span need more than "
                f"{10 * PROBE_STEPS} steps: {10 * PROBE_STEPS * span / stretch:.2g} or more over "
                "the span"
            ) from None
        if result.status != 0 or stretch >= cap:
            t0 = float(probe.time_grid[0])
            reached = (times[-1] if times else t0) - t0
            if not reached > 0:
                raise _Unfit("the probe did not advance")
            return len(times) / reached
        stretch = min(cap, 8 * stretch)


def _recorded(scene: Scene) -> tuple[Any, list[float]]:
    """A run of ``scene`` and the time after each of its steps."""
    times: list[float] = []
    return _run(scene, progress=times.append), times


def _measure(
    mine: Scene, recorded: tuple[Any, list[float]], truth: Any | None, whole: bool
) -> dict[str, float]:
    """One pilot (``recorded``: its run of ``mine``): its rate of steps and wall per step, and
    with a ``truth`` in more bits the constants of the two laws and, for a ``whole`` span, the
    largest errors themselves."""
    result, times = recorded
    eps = float(mine.integrator.precision.epsilon)
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
    start, _ = mine.output.span()
    first = _window(mine, start, (t[1] - t[0]) / 64, 2, mine.integrator.max_steps)
    fixed, wall = _least(first), _least(mine)
    out = {
        "eps": eps,
        "steps": steps,
        "rate": steps / (t[-1] - t[0]),
        "fixed": fixed,
        "per_step": max(wall - fixed, 0.0) / steps,
    }
    if truth is None:
        return out
    from ..core.engine import model_of

    skip = model_of(mine).unbounded
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


def _run(scene: Scene, progress: Callable[[Any], None] | None = None) -> Any:
    from ..core.engine import run

    result = run(scene, progress, raise_on_failure=False)
    if result.status != 0 and "max_steps" not in result.message:
        raise _Unfit(f"the pilot stopped: {result.message}")
    return result


def _advice(
    routes: list[Route], best: Route | None, error: float, quantity: str, scene: Scene | None
) -> str:
    if best is not None:
        return (
            f"recommended: {_name(best, scene)} (predicted {quantity} error "
            f"{best.error(quantity):.1e}, about {_seconds(best.seconds)})"
            f"{_tolerance_note(best, scene)}"
        )
    meeting = [r for r in routes if r.error(quantity) <= error]
    if meeting:
        r = meeting[0]
        return (
            f"no route within the step budget reaches {error:g}: {_name(r, scene)} would "
            f"(predicted {quantity} error {r.error(quantity):.1e}, about {_seconds(r.seconds)}) "
            f"but takes {r.over_budget}: raise integrator.max_steps to run it"
            f"{_tolerance_note(r, scene)}"
        )
    closest = min(routes, key=lambda r: r.error(quantity))
    text = (
        f"no route reaches {error:g}: the closest, {_name(closest, scene)}, predicts "
        f"{closest.error(quantity):.1e} in about {_seconds(closest.seconds)}"
    )
    c = closest.constants["c2" if quantity == "state" else "c1"]
    if math.isfinite(c) and c > 0:
        power = 1.5 if quantity == "state" else 0.5
        needed = error / (c * closest.steps**power)
        bits = math.ceil(-math.log2(needed)) + 4
        if bits <= MAX_BITS:
            text += (
                f"; the law asks for about {bits} bits (integrator.precision = {{bits = {bits}}}, "
                "MPFR, slower per step and not timed here)"
            )
        else:
            text += (
                f"; the law asks for about {bits} bits, more than the {MAX_BITS} that "
                "integrator.precision = {bits = N} takes: shorten the span or ask for less"
            )
    return text + _tolerance_note(closest, scene)


def _name(route: Route, scene: Scene | None) -> str:
    """The route as a recommendation: formulation, precision and, where it is not the
    scene's, the tolerance to write."""
    text = f"{route.formulation or 'the scene as written'} in {route.precision}"
    if _tolerance_changed(route, scene):
        text += f" with integrator.tolerance = {route.tolerance!r}"
    return text


def _tolerance_changed(route: Route, scene: Scene | None) -> bool:
    if scene is None:
        return False
    own = scene.integrator.tolerance
    return route.tolerance != ("auto" if own is None else str(own))


def _tolerance_note(route: Route, scene: Scene | None) -> str:
    """Why a route's tolerance is not the scene's."""
    if scene is None or not _tolerance_changed(route, scene):
        return ""
    own = scene.integrator.tolerance
    assert own is not None  # an "auto" scene's routes are all "auto"
    prec = Precision.from_spec(PRECISIONS[route.precision])
    if exact_fraction(own) > Fraction(2) ** (1 - prec.bits):
        why = f"looser than {route.precision}'s round-off: the laws predicted are round-off's"
    else:
        why = f"below the least {route.precision} takes (1e-6 ε)"
    return f" — not the scene's tolerance {own}, which is {why}"


def _seconds(s: float) -> str:
    if s < 0.01:
        return f"{1e3 * s:.2g} ms"
    if s < 1:
        return f"{1e3 * s:.0f} ms"
    if s < 3600:
        return f"{s:.1f} s"
    return f"{s / 3600:.1f} h"
