"""What a run records: outputs and monitors evaluated on the recorded states in the run's
precision, event logs, and the checks that a run's records fit in memory and start finite."""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Container, Mapping, Sequence
from typing import Any

import mpmath
import numpy as np

from .compiler import Compiled, flat_outputs
from .errors import SceneError
from .model import Model
from .precision import Precision, approx, exact_fraction, shown
from .result import EventLog
from .scene import Scene

#: Largest estimated memory of a run's recorded rows (output times × (state + parameters +
#: outputs + monitors) numbers); the results, their evaluation and the saved file need a few
#: times this again, so a run above it would exhaust an ordinary machine.
MAX_RECORD_BYTES = 2**30


def check_fits(scene: Scene, model: Model) -> None:
    """Refuse a run whose recorded rows would exceed :data:`MAX_RECORD_BYTES`, or whose
    ``max_step`` needs more steps than ``integrator.max_steps`` to cover its span."""
    options, output = scene.integrator, scene.output
    prec = options.precision
    width = 1 + len(model.system) + len(model.pars) + len(flat_outputs(model))
    # heyoka's MPFR numbers hold their limbs outside the array.
    size = {"double": 8, "quad": 16}.get(prec.kind) or 32 + 8 * math.ceil(prec.bits / 64)
    need = output.count * width * size
    if need > MAX_RECORD_BYTES:
        raise SceneError(
            "output.times",
            f"{output.count} output times of {width} numbers ({prec.name}, {size} bytes each) "
            f"need ~{need / 2**30:.3g} GiB, more than {MAX_RECORD_BYTES / 2**30:.3g} GiB; "
            "record fewer times",
        )
    if options.max_step is not None:
        start, stop = output.span()
        steps = (exact_fraction(stop) - exact_fraction(start)) / exact_fraction(options.max_step)
        if steps > options.max_steps:
            raise SceneError(
                "integrator.max_step",
                f"{shown(options.max_step)} needs at least {approx(steps)} steps from "
                f"t = {start} to {stop}, more than the step budget integrator.max_steps = "
                f"{options.max_steps}",
            )


def start_values(model: Model, precision: Precision) -> tuple[np.ndarray, np.ndarray]:
    """The initial state and the whole parameter vector of ``model`` in ``precision``, each
    finite, or the refusal naming the scene field a number comes from.

    The scene's own numbers were checked in the run's precision when it was loaded; one that
    is not finite here (or that the precision cannot hold) is derived from them (μ Jₙ Rⁿ, a
    state converted from elements) and overflows it.

    Copies: a model's numbers do not change, so they are converted once per precision.
    """
    held = model.__dict__.setdefault("_start_values", {})
    if precision.name not in held:
        # Overflows in the conversion are not reported by numpy: the refusals name them.
        with np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            held[precision.name] = _start_values(model, precision)
    state, values = held[precision.name]
    return state.copy(), values.copy()


def _start_values(model: Model, precision: Precision) -> tuple[np.ndarray, np.ndarray]:
    names = model.state_names
    state = _finite_array(
        precision,
        model.initial_state,
        lambda i: model.initial_field(names[i]),
        lambda i: f"the initial value of {names[i]}",
    )
    pars = model.pars
    values = _finite_array(
        precision,
        pars.values,
        lambda i: pars.fields[i] or f"parameters.{pars.names[i]}",
        lambda i: f"the number {pars.names[i]}" if pars.fields[i] is not None else "the parameter",
    )
    return state, values


def _finite_array(
    precision: Precision,
    values: Sequence[Any],
    field: Callable[[int], str],
    what: Callable[[int], str],
) -> np.ndarray:
    """``values`` in ``precision``, or the refusal of the first that is not finite there,
    naming ``field(i)`` and saying ``what(i)`` it is (worded only when refused)."""
    try:
        out = precision.array(values)
    except SceneError:
        for i, value in enumerate(values):
            try:
                precision.number(value)
            except SceneError:
                source = "them" if ", " in field(i) else "it"
                raise SceneError(
                    field(i),
                    f"{what(i)} derived from {source} is {_short(value)}, which "
                    f"{precision.name} cannot hold; scale the units (or choose a wider "
                    "precision)",
                ) from None
        raise
    bad = np.flatnonzero(~np.isfinite(out))
    if len(bad):
        i = int(bad[0])
        raise SceneError(
            field(i), f"{what(i)} is {out[i]} at the start: it must be finite to integrate"
        )
    return out


def _short(value: Any) -> str:
    """A number (or its decimal text) to 6 significant digits."""
    with mpmath.workdps(20):
        return mpmath.nstr(mpmath.mpf(str(value)), 6)


def all_finite(values: Mapping[str, np.ndarray], skip: Container[str] = ()) -> bool:
    """Whether every value of ``values`` (outputs and monitors by name) but those named in
    ``skip`` is finite: in double, one test of them all (a test per output costs ~5 µs, and a
    model may have dozens)."""
    arrays = [v for k, v in values.items() if k not in skip]
    if not arrays:
        return True
    if arrays[0].dtype == np.float64:  # a run's outputs share its precision
        return bool(np.isfinite(np.concatenate(arrays, axis=None)).all())
    return all(np.all(np.isfinite(a)) for a in arrays)


def first_nonfinite(
    model: Model, values: dict[str, np.ndarray], times: np.ndarray
) -> tuple[int, str] | None:
    """The first row at which an output or monitor of ``values`` is not finite, and the
    message of the stop there; None if every value is finite."""
    if all_finite(values, model.unbounded):
        return None
    first = None
    # Infinite (or 0/0) at a half-turn, rightly, are the unbounded outputs; a state gone NaN
    # shows in the others.
    suspects = [
        name
        for name, value in values.items()
        if name not in model.unbounded and not np.isfinite(value).all()
    ]
    for name in suspects:
        value = values[name]
        rows = np.asarray(value).reshape(len(value), -1)
        bad = np.flatnonzero(~np.all(np.isfinite(rows), axis=1))
        if len(bad) and (first is None or bad[0] < first[0]):
            first = (int(bad[0]), name)
    if first is None:
        return None
    k, name = first
    kind = "monitor" if name in model.monitors else "output"
    return k, f"the {kind} {name} became non-finite at t = {times[k]}; results kept up to there"


def evaluate_outputs(
    compiled: Compiled,
    model: Model,
    state: np.ndarray,
    pars: np.ndarray,
    times: np.ndarray,
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
        The ``n`` times (the arrays in the run's precision).

    Returns
    -------
    dict
        Each output and monitor by name: shape ``(n,)``, or ``(n, k)`` for a k-vector monitor.
    """
    stacked = evaluate_members(
        compiled, model, np.asarray(state)[None], np.asarray(pars)[None], times
    )
    return {name: value[0] for name, value in stacked.items()}


def evaluate_members(
    compiled: Compiled,
    model: Model,
    states: np.ndarray,
    pars: np.ndarray,
    times: np.ndarray,
) -> dict[str, np.ndarray]:
    """:func:`evaluate_outputs` of several runs recorded at the same ``n`` times (the members
    of a sweep), in one call of the compiled evaluator.

    ``states`` is ``(runs, n, len(model.system))``, ``pars`` each run's whole parameter
    vector, ``(runs, len(model.pars))``, or one per time, ``(runs, n, len(model.pars))``;
    each output is returned as ``(runs, n)`` or ``(runs, n, k)``.

    The evaluator works SIMD lanes at a time, and some functions iterate until every lane of a
    batch has converged (Kepler's equation): a row's bits depend on the rows beside it. Each
    run is therefore cut into whole batches of its own rows (the last padded with copies of
    its last row), so that a run's outputs are the same bits alone or beside others.
    """
    evaluator = compiled.evaluator
    width = max(1, int(getattr(evaluator, "batch_size", 1)))
    runs, n = states.shape[:2]
    to = -(-n // width) * width
    if runs == 0 or n == 0:
        rows = np.empty((len(flat_outputs(model)), runs, n))
    elif states.dtype == np.float64 and pars.dtype == np.float64:
        rows = _evaluate_doubles(evaluator, states, pars, times, to)
    else:
        # In the precision's own arrays (a concatenation keeps heyoka's dtypes).
        if to != n:
            states = np.concatenate([states, np.repeat(states[:, -1:], to - n, axis=1)], axis=1)
        flat = states.reshape(runs * to, states.shape[2])
        kwargs: dict[str, Any] = {
            "time": np.ascontiguousarray(np.tile(_padded(np.asarray(times), to), runs))
        }
        if evaluator.nparams:
            used = pars[..., : evaluator.nparams]
            if used.ndim == 2:
                used = np.repeat(used[:, None, :], to, axis=1)
            elif to != n:
                used = np.concatenate([used, np.repeat(used[:, -1:], to - n, axis=1)], axis=1)
            kwargs["pars"] = np.ascontiguousarray(used.reshape(runs * to, -1).T)
        rows = evaluator(np.ascontiguousarray(flat.T), **kwargs)
        rows = rows.reshape(rows.shape[0], runs, to)
    rows = rows[:, :, :n]
    return {
        name: rows[a:b].transpose(1, 2, 0).copy() if vector else rows[a].copy()
        for name, a, b, vector in _output_layout(model)
    }


def _evaluate_doubles(evaluator: Any, states, pars, times, to: int) -> np.ndarray:
    """The evaluator's rows ``(outputs, runs, to)`` of double arrays, its inputs written in place
    (runs padded to ``to`` rows with their last row)."""
    runs, n, d = states.shape
    x = np.empty((d, runs, to))
    x[:, :, :n] = states.transpose(2, 0, 1)
    t = np.empty((runs, to))
    t[:, :n] = times
    if to != n:
        x[:, :, n:] = states[:, -1:].transpose(2, 0, 1)
        t[:, n:] = times[-1]
    kwargs: dict[str, Any] = {"time": t.reshape(-1)}
    held = evaluator.nparams
    if held:
        used = pars[..., :held]
        p = np.empty((held, runs, to))
        if used.ndim == 2:
            p[:] = used.T[:, :, None]
        else:
            p[:, :, :n] = used.transpose(2, 0, 1)
            if to != n:
                p[:, :, n:] = used[:, -1:].transpose(2, 0, 1)
        kwargs["pars"] = p.reshape(held, runs * to)
    rows = evaluator(x.reshape(d, runs * to), **kwargs)
    return rows.reshape(rows.shape[0], runs, to)


def _output_layout(model: Model) -> list[tuple[str, int, int, bool]]:
    """Each output and monitor's rows in the evaluator's result: (name, first, end, vector)."""
    held = model.__dict__.get("_output_layout")
    if held is None:
        held, k = [], 0
        for name, value in list(model.outputs.items()) + list(model.monitors.items()):
            width = len(value) if isinstance(value, list) else 1
            held.append((name, k, k + width, isinstance(value, list)))
            k += width
        model.__dict__["_output_layout"] = held
    return held


def _padded(times: np.ndarray, to: int) -> np.ndarray:
    n = len(times)
    return times if to == n else np.concatenate([times, np.repeat(times[-1:], to - n)])


def event_logs(
    model: Model, ta: Any, prec: Precision, logged: Sequence[tuple] = ()
) -> dict[str, EventLog]:
    """The occurrences recorded by ``ta``'s event callbacks (and terminal events that stand
    for one: ``logged``), by name."""
    recorded = ta.nt_events if model.events else []
    return logs_of(
        model, [(ev.callback.times, ev.callback.directions) for ev in recorded], prec, logged
    )


def logs_of(
    model: Model, recorded: list[tuple[list, list]], prec: Precision, logged: Sequence[tuple] = ()
) -> dict[str, EventLog]:
    """The event logs of ``model`` from each event's recorded (times, directions), and the
    occurrences ``(spec, time, direction)`` logged by terminal events (a stop, a hand-over).

    Every crossing is recorded, whatever the event's direction (:mod:`.event_parity` counts
    them all): an event's log keeps those of its own direction."""
    gathered: dict[str, list[tuple[Any, int, str]]] = {}
    for spec, (times, directions) in zip(model.events, recorded, strict=True):
        gathered.setdefault(spec.name, [])
        want = spec.direction
        gathered[spec.name] += [
            (t, d, spec.label_for(d))
            for t, d in zip(times, directions, strict=True)
            if not want or d == want
        ]
    for spec, t, d in logged:
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
