"""Compiled integrators, cached by the structure of the equations: a model's right-hand
sides, events and outputs compiled once per process (:func:`compile_model`), the numbers left
in runtime parameters, and the integrators a finished run hands back kept for the next."""

from __future__ import annotations

import contextlib
import copy
import functools
import hashlib
import re
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

import heyoka as hy
import numpy as np

from .errors import SceneError
from .model import Model
from .scene import IntegratorOptions

#: Above this many bytes of serialised right-hand sides (:meth:`Model.size`), compile in compact
#: mode. Measured (validation/BENCHMARKS.md, "setup", four families): non-compact compile time
#: grows like size^1.16 and reaches ~10 s at ~140 kB, while compact mode compiles in 0.2–1.5 s
#: and its step cost falls from 1.4–2.5× (below 100 kB) to 0.9–1.4× (above 200 kB).
COMPACT_THRESHOLD = 140_000
#: The same choice for a model that counts its operations (:attr:`Model.decomposition`), whose
#: right-hand sides share subexpressions that :meth:`Model.size` counts at every use. The pooled
#: fits of that benchmark (compile time like size^1.35, and like the decomposition's length
#: n^1.63, each reaching 10 s at 93 kB and at 344 entries) put 140 kB at ≈ 480 entries.
COMPACT_DECOMPOSITION = 480


def use_compact_mode(model: Model, options: IntegratorOptions) -> bool:
    """Whether ``model`` is compiled in compact mode under ``options``.

    The scene's ``integrator.compact_mode`` decides when given; "auto" chooses compact mode
    for extended precisions (non-compact real128 code took 8–14 s to compile where compact
    took 0.7–0.9 s, at the same step cost; MPFR code is larger still), for models that ask
    for it (:attr:`Model.compact`), and above :data:`COMPACT_THRESHOLD` (or, for a model
    that counts its operations, :data:`COMPACT_DECOMPOSITION`).
    """
    if options.compact_mode is not None:
        return options.compact_mode
    if options.precision.kind != "double" or model.compact:
        return True
    if model.decomposition is not None:
        return model.decomposition > COMPACT_DECOMPOSITION
    return model.size() > COMPACT_THRESHOLD


class Spares:
    """Integrators of one compiled structure that finished runs handed back, for reuse.

    Resetting one costs microseconds where copying the template cost 0.3–1 ms, most of a short
    run. A reused integrator steps as a copy of the template does: heyoka chooses each step
    from the current Taylor coefficients alone, and carries nothing else from a propagation to
    the next but event cooldowns and the records our callbacks keep (both reset by
    :meth:`take`). Needs ``integrator`` (the template) and ``spare`` (a list).
    """

    integrator: Any
    spare: list[Any]

    def take(self) -> Any:
        """An integrator of this structure that no one else is using, its event records
        empty and its cooldowns reset; time, state and parameters are the caller's to set."""
        try:
            ta = self.spare.pop()  # atomic: threads never get the same one
        except IndexError:
            return copy.deepcopy(self.integrator)
        if ta.with_events:
            for ev in ta.nt_events:
                ev.callback.clear()
            ta.reset_cooldowns()
        return ta

    def give(self, ta: Any) -> None:
        """Hand back an integrator from :meth:`take` that its run no longer uses."""
        if len(self.spare) < _SPARE:
            self.spare.append(ta)


@dataclass
class Compiled(Spares):
    """A template integrator and the evaluator of outputs and monitors for one model structure
    (with the integrators finished runs handed back: :class:`Spares`)."""

    integrator: Any
    evaluator: Any
    compile_seconds: float
    spare: list[Any] = field(default_factory=list)
    #: Indices of the parameters the right-hand sides use (see :class:`Watch`).
    rhs_pars: list[int] = field(default_factory=list)
    #: The recorded events' expressions, compiled (:func:`event_values`; None: not needed).
    event_values: EventValues | None = None


#: Integrators kept for reuse per compiled structure (one per thread that runs it at once).
_SPARE = 8


_CACHE: dict[str, Compiled] = {}


def clear_cache() -> None:
    """Forget every compiled integrator (for measuring compile time)."""
    _CACHE.clear()
    _EVENT_VALUES.clear()


def cache_size() -> int:
    """Number of compiled model structures held in memory."""
    return len(_CACHE)


#: heyoka's name of the time in an expression's text (no state variable is named t).
_TIME = re.compile(r"\bt\b")


def compile_model(model: Model, options: IntegratorOptions) -> tuple[Compiled, bool]:
    """The compiled integrator for ``model``, from the cache when possible.

    Returns the compiled object and whether it came from the cache.
    """
    key = cache_key(model, options)
    hit = _CACHE.get(key)
    if hit is not None:
        return hit, True
    # (Only before compiling: a cached structure has passed it.)
    for e in model.events:
        if not hy.get_variables(e.expression) and not _TIME.search(str(e.expression)):
            # heyoka refuses such an event function ("cannot be constants or parameters").
            raise SceneError(
                f"events.{e.name}.expression",
                f"is constant ({e.expression}): an event needs the state or t to cross zero",
            )
    with quiet_heyoka():
        compiled = _compile(model, options)
    _CACHE[key] = compiled
    return compiled, False


@contextlib.contextmanager
def quiet_heyoka() -> Iterator[None]:
    """heyoka's ``[warning]`` log lines off (their cases are reported as errors of ours)."""
    hy.set_logger_level_error()
    try:
        yield
    finally:
        hy.set_logger_level_warning()  # heyoka's default


def _compile(model: Model, options: IntegratorOptions) -> Compiled:
    t0 = time.perf_counter()
    prec = options.precision
    compact = use_compact_mode(model, options)
    kw = prec.heyoka_kwargs
    ev_kw = {"fp_type": kw["fp_type"]} if kw else {}
    # Every crossing, whatever the event's direction: the parity of a run's crossings
    # (:mod:`.event_parity`) counts them all; the logs keep the event's own direction.
    nt_events = [
        hy.nt_event(e.expression, _Recorder(), direction=hy.event_direction.any, **ev_kw)
        for e in model.events
    ]
    t_events = [
        hy.t_event(
            e.expression, direction=_direction(e.direction), callback=TerminalCallback(i), **ev_kw
        )
        for i, e in enumerate(model.terminal)
    ]
    extra = {}
    if options.tolerance is not None:
        extra["tol"] = prec.number(options.tolerance)
    ta = hy.taylor_adaptive(
        model.system,
        prec.array(model.initial_state),
        pars=prec.array(model.pars.values[: model.integrator_parameters()]),
        compact_mode=compact,
        high_accuracy=options.high_accuracy,
        nt_events=nt_events,
        t_events=t_events,
        **extra,
        **kw,
    )
    outputs = flat_outputs(model)
    evaluator = hy.cfunc(
        [e for _, e in outputs], [v for v, _ in model.system], compact_mode=compact, **kw
    )
    rhs_pars = sorted(int(str(p)[1:]) for p in hy.get_params([rhs for _, rhs in model.system]))
    values = event_values(model, options)
    return Compiled(ta, evaluator, time.perf_counter() - t0, rhs_pars=rhs_pars, event_values=values)


class EventValues:
    """A model's recorded events at one state: the sign of each event's expression and of its
    rate of change along the motion (compiled once per structure), what
    :class:`.event_parity.EventParity` compares.

    Parameters
    ----------
    function
        ``heyoka.cfunc`` of the expressions, then of their time derivatives, over the state
        variables.
    """

    def __init__(self, function: Any) -> None:
        self._function = function
        self._held = function.nparams

    def at(self, states: Any, pars: Any, times: Any) -> tuple[np.ndarray, np.ndarray]:
        """The signs (0: zero or NaN) of each expression and of its time derivative at each
        of ``states`` (shape (n, variables), the run's precision), with its whole parameter
        vector (``pars``, shape (n, parameters)) and its time (``times``, shape (n,)): two
        integer arrays of shape (n, events). One call for many states: a call costs ~10 µs
        of heyoka's Python binding, whatever it evaluates."""
        kwargs: dict[str, Any] = {"time": times}
        if self._held:
            kwargs["pars"] = np.ascontiguousarray(pars[:, : self._held].T)
        values = self._function(np.ascontiguousarray(states.T), **kwargs)
        signs = (values > 0).astype(np.int8) - (values < 0).astype(np.int8)
        n = len(signs) // 2
        return signs[:n].T, signs[n:].T


_EVENT_VALUES: dict[str, EventValues] = {}


def event_values(model: Model, options: IntegratorOptions) -> EventValues | None:
    """The compiled signs of ``model``'s recorded events and of their rates (shared by the
    single run and the batch lanes of one structure), or None for a model without both
    recorded and terminal events: only a terminal event can hide a crossing
    (:mod:`.event_parity`), and no other model pays the compilation."""
    if not (model.events and model.terminal):
        return None
    key = cache_key(model, options)
    hit = _EVENT_VALUES.get(key)
    if hit is not None:
        return hit
    expressions = [e.expression for e in model.events]
    function = hy.cfunc(
        expressions + [along_motion(model, e) for e in expressions],
        [v for v, _ in model.system],
        compact_mode=use_compact_mode(model, options),
        **options.precision.heyoka_kwargs,
    )
    values = _EVENT_VALUES[key] = EventValues(function)
    return values


def along_motion(model: Model, expression: Any) -> Any:
    """The time derivative of ``expression`` along the motion of ``model``'s system: its
    gradient along the right-hand sides, and its explicit dependence on the time."""
    # heyoka differentiates by variables only: one stands in for the time meanwhile.
    tau = hy.make_vars("time__")
    held = hy.subs(expression, {hy.time: tau})
    terms = [hy.diff(held, tau)] + [hy.diff(held, v) * rhs for v, rhs in model.system]
    return hy.subs(hy.sum(terms), {tau: hy.time})


def cache_key(model: Model, options: IntegratorOptions) -> str:
    """The key of ``model``'s compiled code: equal keys share one compiled integrator."""
    return _digest(
        model.code_key,
        options.precision.name,
        str(options.tolerance),
        str(options.compact_mode),
        str(options.high_accuracy),
    )


@functools.lru_cache(maxsize=256)
def _digest(*parts: str) -> str:
    # Each run asks for its key: a model's code_key is one string object, its hash kept.
    return hashlib.sha256("\n".join(parts).encode()).hexdigest()


def event_direction(spec: Any) -> Any:
    """heyoka's direction of an :class:`EventSpec` or :class:`TerminalSpec`."""
    return _direction(spec.direction)


def _direction(d: int) -> Any:
    return {
        0: hy.event_direction.any,
        1: hy.event_direction.positive,
        -1: hy.event_direction.negative,
    }[d]


class _Recorder:
    """Non-terminal event callback: remembers each occurrence's time and direction."""

    def __init__(self) -> None:
        self.times: list[Any] = []
        self.directions: list[int] = []

    def __call__(self, ta: Any, t: Any, d_sgn: int) -> None:
        self.times.append(t)
        self.directions.append(int(d_sgn))

    def clear(self) -> None:
        self.times.clear()
        self.directions.clear()


class TerminalCallback:
    """The callback of a terminal event: hands the event to ``target(index, integrator)``
    (a batch integrator's: ``target(index, integrator, lane)``), which returns whether the
    integration (the lane) goes on.

    The engine points ``target`` at the run using the integrator
    (:meth:`Propagation._on_terminal`; the lanes at :mod:`.lanes`'s). heyoka copies an
    integrator's callbacks with it; a copy starts without a target (it serves another run).
    """

    def __init__(self, index: int) -> None:
        self.index = index
        self.target: Callable[..., bool] | None = None

    def __deepcopy__(self, memo: dict) -> TerminalCallback:
        return TerminalCallback(self.index)

    def __call__(self, ta: Any, d_sgn: Any, *lane: int) -> bool:
        if self.target is None:
            raise RuntimeError("a terminal event reached with no run to handle it")
        return self.target(self.index, ta, *lane)


def flat_outputs(model: Model) -> list[tuple[str, Any]]:
    flat = [(k, v) for k, v in model.outputs.items()]
    for k, v in model.monitors.items():
        if isinstance(v, list):
            flat += [(f"{k}[{i}]", e) for i, e in enumerate(v)]
        else:
            flat.append((k, v))
    return flat
