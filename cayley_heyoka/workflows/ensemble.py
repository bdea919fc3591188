"""Propagate many initial states of one scene: compile once, integrate every member.

A scene describes one body; an ensemble is the same equations and numbers from many initial
states (a cloud of debris, a spread of attitudes, a Monte Carlo over initial conditions).
:func:`propagate_ensemble` builds the scene's model once, compiles it once and integrates each
member to one end time, returning the final states in the model's state variables::

    import numpy as np
    import cayley_heyoka as ch
    from cayley_heyoka.workflows.ensemble import ensemble_state, propagate_ensemble

    scene = ch.Scene.from_dict({"body": {"inertia": [1.0, 1.5, 2.5]},
                                "initial": {"rates": [0.3, 1.0, 0.5]},
                                "attitude": {"formulation": "quaternion"},
                                "output": {"times": [0.0, 10.0]}})
    names, x0 = ensemble_state(scene)            # the scene's own state: perturb it
    members = np.repeat(x0[None, :], 10_000, axis=0)
    members[:, :3] *= 1 + 0.1 * np.random.default_rng(1).standard_normal((10_000, 3))
    out = propagate_ensemble(scene, members, t_end=10.0, mode="batch")
    out.states                                   # (10_000, 7) at t = 10

The guide, with measured throughput: docs/ensembles.md.

Modes (measured in validation/BENCHMARKS.md, section "Set-up cost and ensembles"):

``"batch"``
    heyoka's batch integrator: ``heyoka.recommended_simd_size()`` members per SIMD lane set,
    each lane with its own step size; one batch integrator per worker thread, a lane handed the
    next member as soon as its own is done (:mod:`cayley_heyoka.core.lanes`, the path sweeps
    take too). Each member takes the serial mode's steps; its state differs by a few ulps
    (SIMD rounding). Double precision only.
``"threads"``
    the scalar integrator, one copy per worker thread, each sweeping its share of members.
``"serial"``
    the scalar integrator in the calling thread: the reference the others must equal.

Only the final state is returned: no output grid, monitors or events. Scenes with terminal
events are refused: their handlers keep part of the motion in runtime parameters (the
Rodrigues chart's base, ρ's whole revolutions, Encke's reference ellipse), so the final
integrated state alone does not give it. Use ``attitude.formulation = "quaternion"`` or
``orbit.formulation = "cartesian"``, or :func:`cayley_heyoka.run_sweep`, which runs such
members in the same batch lanes (handlers included) and records their outputs.

Members share the scene's numbers (runtime parameters); scenes differing only in numbers share
the compiled code, so one ensemble per set of numbers costs no recompilation.
"""

from __future__ import annotations

import copy
import os
import time
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from queue import SimpleQueue
from typing import Any

import heyoka as hy
import numpy as np

from ..core import compiler, lanes
from ..core.errors import OptionError, SceneError
from ..core.model import Model
from ..core.precision import Number, Precision, number_argument
from ..core.scene import IntegratorOptions, Scene, require_scene
from ..core.structures import model_for

MODES = ("batch", "threads", "serial")

# What each terminal event is for, and the formulation that has none (for the refusal).
_TERMINAL_HINTS = {
    "rebasings": "the Rodrigues chart's re-basing; use attitude.formulation = 'quaternion'",
    "revolutions": "the count of ρ's revolutions; use orbit.formulation = 'cartesian'",
    "equatorial_handovers": (
        "the hand-over of Cayley's angles near the reference plane; use orbit.formulation = "
        "'cartesian'"
    ),
    "rectifications": "Encke's rectification; use orbit.formulation = 'cartesian'",
}
# Members per task handed to a worker: large enough that the task overhead (a queue
# round trip, a few µs) stays below a member's cost, small enough to balance two workers
# when members differ in cost.
_CHUNK = 64


@dataclass(frozen=True)
class EnsembleResult:
    """Final states of an ensemble.

    Attributes
    ----------
    names
        The state variables, in column order (the model's integrated state).
    states
        ``(members, len(names))`` final states at ``t_end``, in the scene's precision.
    steps
        Taylor steps taken by each member (a batch lane counts its own steps).
    t_start, t_end
        The scene's start time (its first output time) and the end time, in its precision.
    mode, workers
        How the ensemble was run.
    compile_seconds
        Seconds spent compiling (0 when the compiled integrator came from a cache).
    wall_seconds
        Seconds of the propagation alone (after compiling).
    """

    names: tuple[str, ...]
    states: np.ndarray
    steps: np.ndarray
    t_start: Any
    t_end: Any
    mode: str
    workers: int
    compile_seconds: float
    wall_seconds: float


class EnsembleError(RuntimeError):
    """A member's integration failed (a non-finite state, or a stop before ``t_end``).

    ``member`` is its index in the initial states; ``time`` how far it got.
    """

    def __init__(self, member: int, time: Any, message: str) -> None:
        self.member = member
        self.time = time
        super().__init__(message)


def ensemble_state(scene: Scene) -> tuple[tuple[str, ...], np.ndarray]:
    """The state variables of the scene's model and its initial state, in its precision.

    The starting point of an ensemble: perturb the state, stack the members as rows and pass
    them to :func:`propagate_ensemble`.

    Parameters
    ----------
    scene
        A validated scene.

    Returns
    -------
    names, state
        The integrated variables (e.g. ``p, q, r, qw, qx, qy, qz`` for a rigid body with a
        quaternion attitude; ``x, y, z, vx, vy, vz`` for a Cartesian orbit) and their values
        at the start time.
    """
    model = model_for(scene)
    prec = scene.integrator.precision
    return tuple(model.state_names), prec.array(model.initial_state)


def propagate_ensemble(
    scene: Scene,
    initial_states: Any,
    t_end: Number,
    *,
    mode: str = "batch",
    workers: int | None = None,
) -> EnsembleResult:
    """Integrate every row of ``initial_states`` from the scene's start time to ``t_end``.

    Parameters
    ----------
    scene
        A validated scene without terminal events and without ``output.events``; its numbers
        (moments, μ, force strengths, …), tolerance and precision apply to every member. Its
        first output time is the start time; the rest of ``output.times`` is not used.
    initial_states
        ``(members, n)`` array: one initial state per row, in the order of
        :func:`ensemble_state`'s names. Finite numbers; converted to the scene's precision
        (pass decimal text for exact quad or multiprecision values).
    t_end
        The common end time: any number :func:`~cayley_heyoka.core.precision.as_number`
        takes (decimal text for exactness beyond double), held by the scene's precision.
    mode
        ``"batch"`` (SIMD batch integrators, double only), ``"threads"`` (scalar integrators
        on worker threads) or ``"serial"`` (the calling thread).
    workers
        Worker threads for ``"batch"`` and ``"threads"`` (default: ``os.cpu_count()``);
        ``"serial"`` uses one.

    Returns
    -------
    EnsembleResult
        The final states (rows in the order given), steps, timings.

    Raises
    ------
    TypeError
        ``scene`` is not a Scene, or ``t_end`` is not a number.
    ValueError
        A scene the ensemble cannot run (terminal events, recorded events, batch mode beyond
        double precision), a bad mode or worker count, initial states of the wrong shape or
        not finite, a non-finite ``t_end``.
    EnsembleError
        A member's state became non-finite (or it stopped before ``t_end``): the first such
        member is named.
    """
    scene = require_scene(scene)
    if mode not in MODES:
        raise ValueError(f"mode must be one of {MODES}, got {mode!r}")
    if workers is not None and (
        isinstance(workers, bool) or not isinstance(workers, int) or workers < 1
    ):
        raise ValueError(f"workers must be a positive integer or None, got {workers!r}")
    options = scene.integrator
    prec = options.precision
    if mode == "batch" and prec.kind != "double":
        raise ValueError(
            f"mode 'batch' runs in double precision only (heyoka's batch integrators), but the "
            f"scene's precision is {prec.name!r}: use mode='threads'"
        )
    if scene.output.events:
        raise ValueError(
            f"an ensemble records no events, but the scene lists output.events = "
            f"{list(scene.output.events)}: remove them (run() a member to record its events)"
        )
    model = model_for(scene)
    if model.terminal:
        why = "; ".join(
            _TERMINAL_HINTS.get(t.counter, f"the terminal event {t.counter!r}")
            for t in model.terminal
        )
        raise ValueError(
            "this scene has terminal events, whose handlers keep part of the motion in "
            "parameters, so a final state alone does not give it (no mode returns them; "
            f"run_sweep runs such members in batch lanes and records their outputs): {why}"
        )
    names = tuple(model.state_names)
    states = _initial_states(initial_states, names, prec)
    try:
        end = prec.hold(number_argument(t_end, "t_end"), "t_end")
    except SceneError as exc:
        raise OptionError("t_end", exc.constraint) from None
    start = scene.time_grid[0]
    workers = 1 if mode == "serial" else (workers or os.cpu_count() or 1)

    if mode == "batch":
        return _lanes(model, options, states, start, end, workers)
    compiled, cached = compiler.compile_model(model, options)
    template, compile_seconds = compiled.integrator, 0.0 if cached else compiled.compile_seconds
    pars = prec.array(model.pars.values[: model.integrator_parameters()])
    limit: dict[str, Any] = {"max_steps": options.max_steps}  # the step budget, per member
    if options.max_step is not None:
        limit["max_delta_t"] = prec.number(options.max_step)

    members = len(states)
    out = np.empty_like(states)
    steps = np.zeros(members, dtype=np.int64)
    job = _ScalarSweep(states, out, steps, start, end, pars, limit)
    tasks = [range(i, min(i + _CHUNK, members)) for i in range(0, members, _CHUNK)]
    workers = min(workers, len(tasks))

    t0 = time.perf_counter()
    if workers == 1:
        ta = copy.deepcopy(template)
        failures = [job(ta, r) for r in tasks]
    else:
        pool: SimpleQueue = SimpleQueue()
        for _ in range(workers):
            pool.put(copy.deepcopy(template))

        def task(members: range) -> EnsembleError | None:
            ta = pool.get()
            try:
                return job(ta, members)
            finally:
                pool.put(ta)

        with ThreadPoolExecutor(max_workers=workers) as executor:
            failures = list(executor.map(task, tasks))
    wall = time.perf_counter() - t0
    failed = [f for f in failures if f is not None]
    if failed:
        raise min(failed, key=lambda f: f.member)
    return EnsembleResult(names, out, steps, start, end, mode, workers, compile_seconds, wall)


def clear_cache() -> None:
    """Forget the compiled batch integrators (scalar ones live in :mod:`.engine`'s cache)."""
    lanes.clear_cache()


# ---------------------------------------------------------------------- internals
def _initial_states(values: Any, names: Sequence[str], prec: Precision) -> np.ndarray:
    """The members as a ``(members, n)`` array in the scene's precision, or a clear refusal."""
    n = len(names)
    try:
        raw = np.asarray(values)
        if raw.dtype.kind not in "fiu" or prec.kind != "double":
            raw = np.array(values, dtype=object)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"initial_states must be an array of numbers: {exc}") from None
    if raw.dtype.kind in "fiu":
        array = raw.astype(float)  # a numeric array in double: as it is, at numpy's speed
    elif raw.ndim != 2:
        array = raw
    else:
        # Any other input, number by number through the one entry of numbers (10**400, a
        # real128, a Fraction), in the scene's precision.
        array = np.array(
            [
                prec.hold(
                    number_argument(v, f"initial_states[{i}, {j}]"), f"initial_states[{i}, {j}]"
                )
                for i, row in enumerate(raw)
                for j, v in enumerate(row)
            ],
            dtype=float if prec.kind == "double" else prec.fp_type,
        ).reshape(raw.shape)
    if array.ndim != 2 or array.shape[1] != n or array.shape[0] == 0:
        raise ValueError(
            f"initial_states must have shape (members, {n}), one row per member with the "
            f"state variables {list(names)}; got shape {array.shape}"
        )
    finite = np.isfinite(array)
    if not finite.all():
        member, column = (int(i) for i in np.argwhere(~finite)[0])
        raise ValueError(
            f"initial_states[{member}] is not finite: {names[column]} = {array[member, column]}"
        )
    return array


def _lanes(
    model: Model, options: IntegratorOptions, states: np.ndarray, start: Any, end: Any, workers: int
) -> EnsembleResult:
    """Batch mode: the members in SIMD lanes (:mod:`cayley_heyoka.core.lanes`, the sweeps' path)."""
    batch, cached = lanes.compile_batch(model, options)
    pars = np.asarray(model.pars.values, dtype=float)
    grid = np.array([start, end], dtype=float)
    t0 = time.perf_counter()
    with compiler.quiet_heyoka():
        finals = lanes.integrate_lanes(
            model,
            options,
            grid,
            states,
            np.repeat(pars[None, :], len(states), axis=0),
            workers,
            final_only=True,
        )
    wall = time.perf_counter() - t0
    if finals.failed:
        i = min(finals.failed)
        run = finals.failed[i]
        why = hy.taylor_outcome.err_nf_state if run.nonfinite else run.message
        raise _failure(i, run.time, why)
    out, steps = finals.states, finals.steps
    used = max(1, min(workers, -(-len(states) // batch.width)))
    seconds = 0.0 if cached else batch.compile_seconds
    return EnsembleResult(
        tuple(model.state_names), out, steps, start, end, "batch", used, seconds, wall
    )


class _ScalarSweep:
    """Integrates members one after the other on a scalar integrator."""

    width = 1

    def __init__(self, states, out, steps, start, end, pars, limit) -> None:
        self.states, self.out, self.steps = states, out, steps
        self.start, self.end, self.pars, self.limit = start, end, pars, limit

    def __call__(self, ta: Any, members: range) -> EnsembleError | None:
        ta.pars[:] = self.pars
        for i in members:
            ta.time = self.start
            ta.state[:] = self.states[i]
            outcome, _, _, nsteps, *_ = ta.propagate_until(self.end, **self.limit)
            self.steps[i] = nsteps
            if outcome != hy.taylor_outcome.time_limit or ta.time != self.end:
                return _failure(i, ta.time, outcome)
            self.out[i] = ta.state
        return None


def _failure(member: int, reached: Any, outcome: Any) -> EnsembleError:
    if outcome == hy.taylor_outcome.err_nf_state:
        why = "its state became non-finite"
    elif isinstance(outcome, str):
        why = f"it stopped ({outcome})"
    else:
        why = f"it stopped with outcome {outcome}"
    return EnsembleError(
        member, reached, f"ensemble member {member}: {why} at t = {reached}; no states returned"
    )
