"""Build → compile (cached) → propagate → record: the one path every model family takes.

Compiled integrators are cached in memory by the *structure* of the equations (the numbers
live in runtime parameters), so running a scene again, or a scene differing only in its
numbers, costs a copy of a template integrator instead of an LLVM compilation.
"""

from __future__ import annotations

import copy
import hashlib
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import heyoka as hy
import numpy as np

from .errors import IntegrationError
from .families import FAMILIES
from .model import Model
from .precision import Precision
from .result import EventLog, Result, versions
from .scene import IntegratorOptions, Scene

Progress = Callable[[float], None]

#: Above this many bytes of serialised right-hand sides (:meth:`Model.size`), compile in compact
#: mode. Measured (validation/BENCHMARKS.md, "setup", four families): non-compact compile time
#: grows like size^1.16 and reaches ~10 s at ~140 kB, while compact mode compiles in 0.2–1.5 s
#: and its step cost falls from 1.4–2.5× (below 100 kB) to 0.9–1.4× (above 200 kB).
COMPACT_THRESHOLD = 140_000


def use_compact_mode(model: Model, options: IntegratorOptions) -> bool:
    """Whether ``model`` is compiled in compact mode under ``options``.

    The scene's ``integrator.compact_mode`` decides when given; "auto" chooses compact mode
    for extended precisions (non-compact real128 code took 8–14 s to compile where compact
    took 0.7–0.9 s, at the same step cost; MPFR code is larger still), for models that ask
    for it (:attr:`Model.compact`), and above :data:`COMPACT_THRESHOLD`.
    """
    if options.compact_mode is not None:
        return options.compact_mode
    return options.precision.kind != "double" or model.compact or model.size() > COMPACT_THRESHOLD


@dataclass
class Compiled:
    """A template integrator and the evaluator of outputs and monitors for one model structure."""

    integrator: Any
    evaluator: Any
    compile_seconds: float


_CACHE: dict[str, Compiled] = {}


def clear_cache() -> None:
    """Forget every compiled integrator (for measuring compile time)."""
    _CACHE.clear()


def cache_size() -> int:
    """Number of compiled model structures held in memory."""
    return len(_CACHE)


def compile_model(model: Model, options: IntegratorOptions) -> tuple[Compiled, bool]:
    """The compiled integrator for ``model``, from the cache when possible.

    Returns the compiled object and whether it came from the cache.
    """
    key = _cache_key(model, options)
    hit = _CACHE.get(key)
    if hit is not None:
        return hit, True
    t0 = time.perf_counter()
    prec = options.precision
    compact = use_compact_mode(model, options)
    kw = prec.heyoka_kwargs
    ev_kw = {"fp_type": kw["fp_type"]} if kw else {}
    nt_events = [
        hy.nt_event(e.expression, _Recorder(), direction=_direction(e.direction), **ev_kw)
        for e in model.events
    ]
    t_events = [
        hy.t_event(e.expression, direction=_direction(e.direction), **ev_kw) for e in model.terminal
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
    outputs = _flat_outputs(model)
    evaluator = hy.cfunc(
        [e for _, e in outputs], [v for v, _ in model.system], compact_mode=compact, **kw
    )
    compiled = Compiled(ta, evaluator, time.perf_counter() - t0)
    _CACHE[key] = compiled
    return compiled, False


def run(scene: Scene, progress: Progress | None = None) -> Result:
    """Integrate a scene and record its outputs, events and monitors.

    Parameters
    ----------
    scene
        A validated :class:`~cayley_heyoka.scene.Scene`.
    progress
        Called with the current time after each step (slows stepping; for progress bars).

    Returns
    -------
    Result
        Every output time, or, if the run stops early, an :class:`IntegrationError` is raised
        whose ``result`` holds what was computed up to the failure.
    """
    wall0 = time.perf_counter()
    model = FAMILIES[scene.family].build(scene)
    prec = scene.integrator.precision
    compiled, cached = compile_model(model, scene.integrator)
    ta = copy.deepcopy(compiled.integrator)
    grid = scene.output.time_grid(prec)
    ta.time = grid[0]
    ta.state[:] = prec.array(model.initial_state)
    # The whole parameter vector (outputs may use parameters the equations do not); the
    # integrator holds its leading part, copied back whenever a handler changes it.
    pars = prec.array(model.pars.values)
    held = len(ta.pars)
    ta.pars[:] = pars[:held]

    callback = _ProgressCallback(progress) if progress else None
    # Runtime only: a step cap changes no compiled code, so it shares the cached integrator.
    limit = {}
    if scene.integrator.max_step is not None:
        limit["max_delta_t"] = prec.number(scene.integrator.max_step)
    states, pars_rows = [], []
    counters = {"steps": 0, **{spec.counter: 0 for spec in model.terminal}}
    status, message = 0, "every output time was reached"
    stopped_at = None
    # Outputs come from heyoka's dense output: only the last point of a propagate_grid call
    # ends a step there. So after a terminal event the grid is resumed from the current time;
    # propagate_until to the next output would end a step at each output reached after an
    # event — a rounding kick each, and a trajectory that depends on the output grid. A call
    # costs O(its points): one after an event covers twice the outputs of the last stretch
    # between events (the next event usually comes first), doubling while none interrupts it.
    span, since_event = len(grid), 0
    i = 0
    while i < len(grid):
        resume = ta.time != grid[i]
        points = grid[i : i + span]
        if resume:
            points = _starting_at(prec, ta.time, points)
        res = ta.propagate_grid(points, callback=callback, **limit)
        outcome, out = res[0], res[-1]
        if resume:
            out = out[1:]  # the current time: not an output time, or recorded already
        counters["steps"] += res[3]
        states.append(out)
        # Copies row by row: np.repeat aliases the limbs of heyoka's multiprecision dtype.
        pars_rows += [pars.copy() for _ in range(len(out))]
        i += len(out)
        since_event += len(out)
        code = int(outcome)
        if outcome == hy.taylor_outcome.time_limit:
            span = min(2 * span, len(grid))
            continue
        span, since_event = 2 * since_event + _RESUME_SPAN, 0
        if -len(model.terminal) <= code <= -1:
            spec = model.terminal[-code - 1]
            stop = spec.handle(ta, pars)
            ta.pars[:] = pars[:held]
            counters[spec.counter] += 1
            if stop is not None:
                status, message = -1, stop
                if spec.records is not None:
                    stopped_at = (spec.records, ta.time, spec.direction)
                break
            ta.reset_cooldowns()
            continue
        status = -1
        if outcome == hy.taylor_outcome.err_nf_state:
            message = f"the state became non-finite after t = {ta.time}; results kept up to there"
        elif outcome == hy.taylor_outcome.cb_stop:
            message = f"stopped by the progress callback at t = {ta.time}"
        else:
            message = f"stopped at t = {ta.time} with outcome {outcome}"
        break

    state = np.concatenate(states) if states else np.empty((0, len(model.system)))
    pars = np.array(pars_rows) if pars_rows else np.empty((0, len(model.pars)))
    times = grid[: len(state)]
    values = evaluate_outputs(compiled, model, state, pars, times, prec)
    result = Result(
        t=times,
        variables={k: values[k] for k in model.outputs},
        monitors={k: values[k] for k in model.monitors},
        conserved=model.conserved,
        events=_event_logs(model, ta, prec, stopped_at),
        precision=prec,
        status=status,
        message=message,
        counters=counters,
        scene=scene.to_dict(),
        metadata={
            **versions(),
            "wall_seconds": time.perf_counter() - wall0,
            "compile_seconds": 0.0 if cached else compiled.compile_seconds,
            "compiled_from_cache": cached,
            "order": int(ta.order),
            "tolerance": str(ta.tol),
        },
    )
    if status != 0:
        raise IntegrationError(message, result)
    return result


# ---------------------------------------------------------------------- internals
#: Output times added to a propagate_grid call after a terminal event (see ``run``).
_RESUME_SPAN = 8


def _starting_at(prec: Precision, t: Any, points: np.ndarray) -> np.ndarray:
    """``points`` preceded by the current time ``t`` (heyoka's grids start there)."""
    if prec.kind == "double":
        return np.concatenate(([t], points))
    # Through Python objects: numpy's copies of heyoka's multiprecision dtype alias limbs.
    return prec.array([t, *points])


class _Recorder:
    """Non-terminal event callback: remembers each occurrence's time and direction."""

    def __init__(self) -> None:
        self.times: list[Any] = []
        self.directions: list[int] = []

    def __call__(self, ta: Any, t: Any, d_sgn: int) -> None:
        self.times.append(t)
        self.directions.append(int(d_sgn))


class _ProgressCallback:
    def __init__(self, progress: Progress) -> None:
        self.progress = progress

    def __call__(self, ta: Any) -> bool:
        self.progress(float(ta.time))
        return True


def _direction(d: int) -> Any:
    return {
        0: hy.event_direction.any,
        1: hy.event_direction.positive,
        -1: hy.event_direction.negative,
    }[d]


def _cache_key(model: Model, options: IntegratorOptions) -> str:
    text = "\n".join(
        [
            model.structure_key(),
            model.output_key(),
            options.precision.name,
            str(options.tolerance),
            str(options.compact_mode),
            str(options.high_accuracy),
        ]
    )
    return hashlib.sha256(text.encode()).hexdigest()


def _flat_outputs(model: Model) -> list[tuple[str, Any]]:
    flat = [(k, v) for k, v in model.outputs.items()]
    for k, v in model.monitors.items():
        if isinstance(v, list):
            flat += [(f"{k}[{i}]", e) for i, e in enumerate(v)]
        else:
            flat.append((k, v))
    return flat


def evaluate_outputs(
    compiled: Compiled,
    model: Model,
    state: np.ndarray,
    pars: np.ndarray,
    times: np.ndarray,
    prec: Precision,
) -> dict[str, np.ndarray]:
    """The model's outputs and monitors from states recorded by ``compiled``'s integrator.

    Parameters
    ----------
    compiled
        What :func:`compile_model` returned for ``model``.
    state
        States, shape ``(n, len(model.system))``, one row per time.
    pars
        The whole parameter vector at each time, shape ``(n, len(model.pars))``.
    times
        The ``n`` times.
    prec
        The precision of the arrays.

    Returns
    -------
    dict
        Each output and monitor by name: shape ``(n,)``, or ``(n, k)`` for a k-vector monitor.
    """
    evaluator = compiled.evaluator
    n = len(state)
    if n == 0:
        rows = np.empty((len(_flat_outputs(model)), 0))
    else:
        kwargs: dict[str, Any] = {"time": np.ascontiguousarray(times)}
        if evaluator.nparams:
            kwargs["pars"] = np.ascontiguousarray(pars[:, : evaluator.nparams].T)
        rows = evaluator(np.ascontiguousarray(state.T), **kwargs)
    out: dict[str, np.ndarray] = {}
    k = 0
    for name, value in list(model.outputs.items()) + list(model.monitors.items()):
        width = len(value) if isinstance(value, list) else 1
        block = rows[k : k + width]
        out[name] = block.T.copy() if isinstance(value, list) else block[0].copy()
        k += width
    return out


def _event_logs(
    model: Model, ta: Any, prec: Precision, stopped_at: tuple | None
) -> dict[str, EventLog]:
    gathered: dict[str, list[tuple[Any, int, str]]] = {}
    recorded = ta.nt_events if model.events else []
    for spec, ev in zip(model.events, recorded, strict=True):
        rec = ev.callback
        gathered.setdefault(spec.name, [])
        gathered[spec.name] += [
            (t, d, spec.label_for(d)) for t, d in zip(rec.times, rec.directions, strict=True)
        ]
    if stopped_at is not None:
        spec, t, d = stopped_at
        gathered.setdefault(spec.name, []).append((t, d, spec.label_for(d)))
    logs = {}
    for name, items in gathered.items():
        items.sort(key=lambda x: x[0])
        logs[name] = EventLog(
            time=prec.array([x[0] for x in items]) if items else prec.array([]),
            direction=np.array([x[1] for x in items], dtype=int),
            label=np.array([x[2] for x in items], dtype=str),
        )
    return logs
