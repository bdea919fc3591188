"""Many members of one model structure, integrated SIMD lanes at a time (heyoka's batch mode).

A sweep's members share compiled code and differ in their numbers (initial state, runtime
parameters). heyoka's batch integrator advances ``heyoka.recommended_simd_size()`` of them at
once, each lane with its own step size; :func:`integrate_lanes` keeps every lane busy,
handing a lane the next member when its member is done, and runs one batch integrator per
worker thread (heyoka releases the GIL while it steps).

Each member takes the steps, records the events and counts that :func:`cayley_heyoka.run` of
its scene does; its states differ from the scalar run's by a few ulps (SIMD arithmetic rounds
differently) and do not depend on the other members, their order, the lanes or the threads:

* heyoka chooses each lane's steps from that lane's Taylor coefficients alone;
* a lane's trajectory depends on where its ``propagate_grid`` calls end (a call's last point
  ends a step there), so each lane keeps the scalar engine's schedule of calls
  (:class:`cayley_heyoka.core.engine.Propagation`): one call over the whole grid, terminal events
  handled inside it. A terminal event's handler acts on a view of its lane
  (:class:`_LaneView`) and the member's own parameters, as on a scalar integrator;
* members usually run a batch at a time in that one call; a batch in which a lane stops short
  (a handler's stop, a non-finite state, its step budget) is run again lane by lane, below;
* lane by lane, a lane that stops stops the batch call; the other lanes then stand at the end
  of a whole step and resume from there with the rest of their call — the same steps as if it
  had gone on. The batch call is rectangular, so a lane with fewer points than the longest
  column gets unused points inserted in its widest gap (only a call's last point ends a step);
  a lane is given the next member as soon as its own is done;
* a lane with no member follows a copy of a busy lane (re-copied before every call, its
  results unused, its terminal events handled by copies of that lane's handlers), so that it
  never steps anywhere a member does not.

Double precision only (heyoka's batch integrators).
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

import heyoka as hy
import numpy as np

from . import compiler, outcomes, recording
from .event_parity import EventParity
from .model import Handover, Model, TerminalSpec, call_handler, own_terminal
from .precision import Precision
from .result import EventLog
from .row_pars import Rows
from .scene import IntegratorOptions
from .signals import Cancel


@dataclass
class LaneResult:
    """One member's integration: what :class:`cayley_heyoka.Result` is made of.

    ``states`` holds one row per output time reached, ``pars`` the member's whole parameter
    vector (one per row when terminal-event handlers change it); ``status`` is 0 when every
    output time was reached, -1 otherwise, with ``message`` saying why (``nonfinite``: the state
    became non-finite); ``counters`` the Taylor steps and terminal-event tallies; ``time`` the
    time reached; ``handover``: a handler asked for another variant of the model
    (:class:`~.model.Handover`), which a lane cannot compile: run the member with
    :func:`cayley_heyoka.run`.
    """

    states: np.ndarray
    pars: np.ndarray
    status: int
    message: str
    counters: dict[str, int]
    events: dict[str, EventLog]
    time: float
    nonfinite: bool
    handover: bool = False


@dataclass
class Finals:
    """What :func:`integrate_lanes` keeps with ``final_only``: each member's last state.

    ``failed`` maps a member that did not reach the last output time to its
    :class:`LaneResult` (its message, the time it reached).
    """

    states: np.ndarray
    steps: np.ndarray
    failed: dict[int, LaneResult]


class _Everything:
    """Every member's :class:`LaneResult`."""

    def __init__(self, members: int, model: Model) -> None:
        self.results: list[LaneResult | None] = [None] * members
        self.model = model

    def put(self, index: int, result: LaneResult) -> None:
        self.results[index] = result

    def block(self, block, out, res, recorded, pars, end, members) -> None:
        for j, index in enumerate(block):
            events = recorded(j)
            if members is None:
                counters, own = {"steps": outcomes.Ended.of(res[j]).steps}, pars[index]
                states = out[:, :, j].copy()
            else:  # terminal handlers: their tallies, parameters per row, rows kept
                m = members[j]
                dims = (len(self.model.system), len(self.model.pars))
                counters, (states, own) = m.counters, m.rows.joined(0, dims)
            self.results[index] = LaneResult(
                states,
                own,
                0,
                "every output time was reached",
                counters,
                recording.logs_of(self.model, events, _DOUBLE) if events else {},
                float(end),
                False,
            )

    def value(self) -> list[LaneResult]:
        return self.results  # type: ignore[return-value]


class _Finals:
    """Only each member's last state and steps (ensembles: one vectorised copy a batch)."""

    def __init__(self, members: int, dim: int) -> None:
        self.finals = Finals(np.full((members, dim), np.nan), np.zeros(members, np.int64), {})

    def put(self, index: int, result: LaneResult) -> None:
        self.finals.steps[index] = result.counters["steps"]
        if result.status == 0:
            self.finals.states[index] = result.states[-1]
        else:
            self.finals.failed[index] = result

    def block(self, block, out, res, recorded, pars, end, members) -> None:
        n = len(block)
        self.finals.states[block[0] : block[0] + n] = out[-1, :, :n].T
        self.finals.steps[block[0] : block[0] + n] = [outcomes.Ended.of(r).steps for r in res[:n]]

    def value(self) -> Finals:
        return self.finals


@dataclass
class CompiledBatch(compiler.Spares):
    """A batch integrator template for one model structure, and spares to reuse."""

    integrator: Any
    width: int
    compile_seconds: float
    spare: list[Any] = field(default_factory=list)
    #: The recorded events' signs (:func:`.compiler.event_values`; None: not needed).
    event_values: compiler.EventValues | None = None


_CACHE: dict[str, CompiledBatch] = {}
_DOUBLE = Precision()
_COMPILING = threading.Lock()


def compile_batch(model: Model, options: IntegratorOptions) -> tuple[CompiledBatch, bool]:
    """The batch integrator of ``model``'s structure (double precision), from the cache when
    possible; returns it and whether it came from the cache."""
    if options.precision.kind != "double":
        raise ValueError("heyoka's batch integrators run in double precision only")
    width = hy.recommended_simd_size()
    key = f"{compiler.cache_key(model, options)}/{width}"
    hit = _CACHE.get(key)
    if hit is not None:
        return hit, True
    with _COMPILING:
        hit = _CACHE.get(key)
        if hit is not None:
            return hit, True
        t0 = time.perf_counter()
        compact = compiler.use_compact_mode(model, options)
        held = model.integrator_parameters()
        # Every crossing, as in the single run's integrator (:mod:`.event_parity`).
        nt = [
            hy.nt_event_batch(e.expression, _LaneRecorder(), direction=hy.event_direction.any)
            for e in model.events
        ]
        te = [
            hy.t_event_batch(
                e.expression,
                direction=compiler.event_direction(e),
                callback=compiler.TerminalCallback(i),
            )
            for i, e in enumerate(model.terminal)
        ]
        extra = {} if options.tolerance is None else {"tol": _DOUBLE.number(options.tolerance)}
        state = np.repeat(np.asarray(model.initial_state, dtype=float)[:, None], width, axis=1)
        pars = np.asarray(model.pars.values[:held], dtype=float)
        ta = hy.taylor_adaptive_batch(
            model.system,
            state,
            pars=np.repeat(pars[:, None], width, axis=1),
            compact_mode=compact,
            high_accuracy=options.high_accuracy,
            nt_events=nt,
            t_events=te,
            **extra,
        )
        values = compiler.event_values(model, options)
        compiled = CompiledBatch(ta, width, time.perf_counter() - t0, event_values=values)
        _CACHE[key] = compiled
        return compiled, False


def clear_cache() -> None:
    """Forget the compiled batch integrators."""
    _CACHE.clear()


def integrate_lanes(
    model: Model,
    options: IntegratorOptions,
    grid: np.ndarray,
    initial: np.ndarray,
    pars: np.ndarray,
    threads: int = 1,
    cancel: threading.Event | None = None,
    terminal: Sequence[Sequence[TerminalSpec]] | None = None,
    final_only: bool = False,
) -> list[LaneResult] | Finals:
    """Integrate members of ``model``'s structure over ``grid``, lanes at a time.

    Parameters
    ----------
    model
        The structure (any member's model).
    options
        The members' integrator options (double precision; a ``max_step`` applies to all).
    grid
        The output times (doubles, strictly increasing).
    initial
        ``(members, len(model.system))``: each member's initial state.
    pars
        ``(members, len(model.pars))``: each member's whole parameter vector.
    threads
        Batch integrators run at once, each on its share of the members.
    cancel
        Once set, the lanes stop (a :class:`Cancel` within a step, another after their current
        call); members not finished are None.
    terminal
        Each member's terminal events (its own model's, whose handlers may keep state of their
        own; each member runs copies of them); default: ``model``'s for every member.
    final_only
        Keep only each member's last state (:class:`Finals`).

    Returns
    -------
    list of LaneResult, or Finals
        In the order of the members.
    """
    compiled, _ = compile_batch(model, options)
    members = len(initial)
    handlers: Sequence[Sequence[TerminalSpec]] | _Shared = (
        _Shared(model.terminal) if terminal is None else terminal
    )
    results = _Finals(members, len(model.system)) if final_only else _Everything(members, model)
    starts = iter(range(0, members, compiled.width))
    lock = threading.Lock()

    def next_block() -> list[int]:
        """The next members for a batch (none when all are taken)."""
        with lock:
            lo = next(starts, members)
        return list(range(lo, min(lo + compiled.width, members)))

    def work() -> None:
        ta = compiled.take()
        poison = _Poison(ta)
        if isinstance(cancel, Cancel):
            cancel.watch(poison)
        try:
            lanes = _Lanes(ta, compiled, model, options, grid, next_block, results, cancel)
            lanes.run(initial, pars, handlers)
        finally:
            if isinstance(cancel, Cancel):
                cancel.unwatch(poison)
            for ev in ta.t_events if model.terminal else ():
                ev.callback.target = None  # no reference from a spare integrator to the lanes
            compiled.give(ta)

    workers = max(1, min(threads, -(-members // compiled.width)))
    if workers == 1:
        work()
    else:
        errors: list[BaseException] = []

        def guarded(fn=work) -> None:
            try:
                fn()
            except BaseException as exc:  # re-raised in the calling thread
                errors.append(exc)

        pool = [threading.Thread(target=guarded) for _ in range(workers)]
        for t in pool:
            t.start()
        for t in pool:
            t.join()
        if errors:
            raise errors[0]
    return results.value()


# ---------------------------------------------------------------------- internals
class _LaneRecorder:
    """Non-terminal event callback of a batch integrator: each lane's occurrences."""

    def __init__(self) -> None:
        self.times: dict[int, list[float]] = {}
        self.directions: dict[int, list[int]] = {}

    def __call__(self, ta: Any, t: float, d_sgn: Any, lane: int) -> None:
        self.times.setdefault(lane, []).append(t)
        self.directions.setdefault(lane, []).append(int(d_sgn))

    def clear(self, lane: int | None = None) -> None:
        if lane is None:
            self.times.clear()
            self.directions.clear()
        else:
            self.times.pop(lane, None)
            self.directions.pop(lane, None)

    def take(self, lane: int) -> tuple[list[float], list[int]]:
        return self.times.pop(lane, []), self.directions.pop(lane, [])


class _Poison:
    """Makes a batch integrator's parameters and state NaN (a :class:`Cancel` hook): its
    next step is not finite, and heyoka returns."""

    def __init__(self, ta: Any) -> None:
        self.ta = ta

    def __call__(self) -> None:
        self.ta.pars[:] = np.nan
        self.ta.state[:] = np.nan


class _Shared:
    """The model's terminal events for every member (each takes its own copies of them:
    :meth:`_Lanes._member`)."""

    def __init__(self, specs: Sequence[TerminalSpec]) -> None:
        self.specs = specs

    def __getitem__(self, index: int) -> Sequence[TerminalSpec]:
        return self.specs


class _LaneView:
    """One lane of a batch integrator, as a terminal-event handler sees an integrator.

    ``state`` is a view of the lane's column of the integrator's state (assignments reach the
    integrator), made once: heyoka's arrays stay where they are for the integrator's life,
    and building a view costs more than a handler's arithmetic."""

    def __init__(self, ta: Any, lane: int) -> None:
        self._times, self._lane = ta.time, lane  # heyoka's times: a view, as the state
        self.state: np.ndarray = ta.state[:, lane]
        #: The lane's column of the integrator's parameters (a view).
        self.pars: np.ndarray = ta.pars[:, lane]

    @property
    def time(self) -> float:
        return float(self._times[self._lane])


@dataclass
class _Member:
    """A lane's member and where it stands in the engine's schedule of calls.

    ``rows`` are the rows it has kept, with the parameters each was computed with where its
    handlers change them, and its current call's schedule (:class:`~.row_pars.Rows`, the
    scalar engine's record).
    """

    index: int
    pars: np.ndarray
    terminal: list[TerminalSpec] = field(default_factory=list)
    stopped_at: tuple | None = None
    steps: int = 0
    rows: Rows = field(default_factory=Rows)
    counters: dict[str, int] = field(default_factory=dict)
    status: int = 0
    message: str = "every output time was reached"
    event_times: list[list[float]] = field(default_factory=list)
    event_directions: list[list[int]] = field(default_factory=list)
    time: float = 0.0
    nonfinite: bool = False
    handover: bool = False
    #: The accounting of its recorded events' crossings (:mod:`.event_parity`); None for a
    #: twin (:meth:`_Lanes._twin`) and for a model without terminal and recorded events.
    parity: EventParity | None = None

    def crossings(self) -> list[tuple[list, list]]:
        return list(zip(self.event_times, self.event_directions, strict=True))


class _Lanes:
    def __init__(self, ta, compiled, model, options, grid, next_block, results, cancel) -> None:
        self.cancel = cancel
        self.ta, self.width, self.model, self.grid = ta, compiled.width, model, grid
        self.event_values = compiled.event_values
        self.next_block, self.results = next_block, results
        self.budget = options.max_steps
        self.limit = {} if options.max_step is None else {"max_delta_t": float(options.max_step)}
        self.held = ta.pars.shape[0]
        self.recorders = [ev.callback for ev in ta.nt_events] if model.events else []
        self.table: np.ndarray | None = None
        # Each lane's member, and the copy an idle lane follows (:meth:`_twin`).
        self.lanes: list[_Member | None] = [None] * self.width
        self.twins: list[_Member | None] = [None] * self.width
        for ev in ta.t_events if model.terminal else ():
            ev.callback.target = self._on_terminal
        self.views = [_LaneView(ta, j) for j in range(self.width)]
        self.hi, self.lo = ta.dtime  # views, as the views' states

    def run(self, initial: np.ndarray, pars: np.ndarray, terminal: Any) -> None:
        """Members a batch at a time: one call over the whole grid, the usual case; a batch in
        which a lane stops short (a handler's stop, a non-finite state, the step budget) is run
        again lane by lane (:meth:`_lane_by_lane`), with the same bits up to its stop."""
        self.initial, self.pars, self.terminal = initial, pars, terminal
        while not (self.cancel is not None and self.cancel.is_set()):
            block = self.next_block()
            if not block:
                return
            if not self._at_once(block):
                self._lane_by_lane(iter(block))

    def _cancelled(self) -> bool:
        return self.cancel is not None and self.cancel.is_set()

    def _member(self, index: int) -> _Member:
        """Member ``index`` at its start: its parameters, its own terminal handlers."""
        specs = own_terminal(self.terminal[index])
        m = _Member(index, np.array(self.pars[index], dtype=float), specs)
        m.rows = Rows(with_pars=bool(specs))  # handlers change the parameters row by row
        m.counters = {"steps": 0, **{spec.counter: 0 for spec in specs}}
        m.event_times = [[] for _ in self.model.events]
        m.event_directions = [[] for _ in self.model.events]
        if self.event_values is not None:
            m.parity = EventParity(self.event_values)
            m.parity.start(self.initial[index], m.pars, self.grid[0], m.crossings())
        return m

    @staticmethod
    def _twin(m: _Member) -> _Member:
        """A stand-in that an idle lane following ``m``'s lane hands its terminal events to:
        copies of ``m``'s parameters and handlers, its results unused."""
        twin = _Member(-1, m.pars.copy(), own_terminal(m.terminal))
        twin.counters = dict(m.counters)
        return twin

    def _at_once(self, block: list[int]) -> bool:
        """Integrate ``block`` in one call over the grid; False if a lane did not reach its
        end (nothing is recorded then)."""
        ta, width, grid = self.ta, self.width, self.grid
        lanes = block + [block[-1]] * (width - len(block))  # spare lanes copy the last member
        members: list[_Member] | None = None
        if self.model.terminal:
            members = [self._member(i) for i in block]
            for m in members:
                m.rows.begin(grid)
            self.lanes = [*members, *[None] * (width - len(block))]
            self.twins = [None] * len(block) + [
                self._twin(members[-1]) for _ in range(width - len(block))
            ]
        ta.set_dtime(np.full(width, grid[0]), np.zeros(width))
        ta.state[:] = self.initial[lanes].T
        ta.pars[:] = self.pars[lanes, : self.held].T
        for rec in self.recorders:
            rec.clear()
        if ta.with_events:
            ta.reset_cooldowns()
        if self._cancelled():
            return True  # nothing recorded: the block's members stay unfinished
        if len(grid) == 2:
            # Two points: the start and where propagate_until ends (an ensemble's case; the
            # same steps as a grid's, and its last output is the state it ends at).
            first = ta.state.copy()
            ta.propagate_until(grid[-1], max_steps=self.budget, **self.limit)
            out = np.stack([first, ta.state])
            res = ta.propagate_res
        elif len(grid) > 2:
            if self.table is None:
                self.table = np.repeat(grid[:, None], width, axis=1)
            out = outcomes.batch_states(
                ta.propagate_grid(self.table, max_steps=self.budget, **self.limit)
            )
            res = ta.propagate_res
        else:
            out = ta.state.copy()[None, :, :]
            res = [(hy.taylor_outcome.time_limit, 0, 0, 0)] * width
        self.lanes, self.twins = [None] * width, [None] * width
        if self._cancelled():
            return True  # a cancel may have poisoned the call: nothing of it is recorded
        end, times = grid[-1], ta.time
        done = hy.taylor_outcome.time_limit
        ended = [outcomes.Ended.of(r) for r in res[: len(block)]]
        if any(e.outcome != done or times[j] != end for j, e in enumerate(ended)):
            return False
        if members is not None:
            for j, m in enumerate(members):
                m.counters["steps"] = ended[j].steps
                m.rows.keep(out[:, :, j].copy(), m.pars)
                self._gather(j, m)
                if m.parity is not None:
                    m.parity.finish(m.crossings())
        self.results.block(block, out, res, self._recorded(members), self.pars, end, members)
        return True

    def _recorded(self, members: list[_Member] | None) -> Callable[[int], list]:
        """Lane ``j``'s crossings of each event at the end of a batch call: its member's
        (gathered from the recorders), or the recorders' (no terminal events)."""
        if members is not None:
            return lambda j: members[j].crossings()
        recorders = self.recorders
        return lambda j: [rec.take(j) for rec in recorders]

    def _lane_by_lane(self, members: Iterator[int]) -> None:
        """Integrate ``members`` lane by lane on the engine's schedule of calls (see the module
        docstring), each lane given the next of them when its own is done."""
        self._next = lambda: next(members, None)
        for rec in self.recorders:
            rec.clear()
        for j in range(self.width):
            self._assign(j)
        while any(m is not None for m in self.lanes):
            if self._cancelled():
                return
            self._step()
        self.twins = [None] * self.width

    def _assign(self, j: int) -> None:
        """Give lane ``j`` the next member, or nothing (then it follows a busy lane)."""
        index = self._next()
        if index is None:
            self.lanes[j] = None
            return
        self.lanes[j] = m = self._member(index)
        self.twins[j] = None
        ta = self.ta
        hi, lo = _finite_dtime(ta)
        hi[j], lo[j] = self.grid[0], 0.0
        ta.set_dtime(hi, lo)
        ta.state[:, j] = self.initial[index]
        ta.pars[:, j] = m.pars[: self.held]
        for rec in self.recorders:
            rec.clear(j)
        if ta.with_events:
            ta.reset_cooldowns(j)
        self._record_trivial(j)

    def _record_trivial(self, j: int) -> None:
        """A call of one point at the lane's current time takes no step: recorded here."""
        last = len(self.grid) - 1
        while (m := self.lanes[j]) is not None:
            if m.status != 0 or m.rows.done > last:
                self._finish(j, m)
                continue
            if m.rows.done == last and self.ta.time[j] == self.grid[last]:
                m.rows.keep(self.ta.state[:, j].copy()[None, :], m.pars)
                continue
            return

    def _column(self, j: int, m: _Member) -> tuple[np.ndarray, int]:
        """Lane ``j``'s points for this call, and how many lead the outputs (the current
        time, if it is not the first output)."""
        points = self.grid[m.rows.done :]
        t = self.ta.time[j]
        if t != points[0]:
            return np.concatenate(([t], points)), 1
        return points, 0

    def _step(self) -> None:
        ta, width = self.ta, self.width
        members = {j: m for j in range(width) if (m := self.lanes[j]) is not None}
        busy = list(members)
        columns = {j: self._column(j, m) for j, m in members.items()}
        for j, m in members.items():
            points, lead = columns[j]
            m.rows.begin(points[lead:])
        length = max(len(c) for c, _ in columns.values())
        # Idle lanes follow a busy one (a copy of its time, state, parameters and handlers).
        source = busy[0]
        hi, lo = _finite_dtime(ta)
        for j in range(width):
            if self.lanes[j] is None:
                hi[j], lo[j] = hi[source], lo[source]
                ta.state[:, j] = ta.state[:, source]
                ta.pars[:, j] = ta.pars[:, source]
                if ta.with_events:
                    ta.reset_cooldowns(j)
                if self.model.terminal:
                    self.twins[j] = self._twin(members[source])
                columns[j] = columns[source]
        ta.set_dtime(hi, lo)
        table = np.empty((length, width))
        for j in range(width):
            table[:, j] = _padded(columns[j][0], length)
        left = min(self.budget - m.steps for m in members.values())
        if self._cancelled():
            return
        out = outcomes.batch_states(ta.propagate_grid(table, max_steps=left, **self.limit))
        results = ta.propagate_res
        if self._cancelled():
            return  # a cancel may have poisoned the call: its members stay unfinished
        for rec in self.recorders:
            for j in range(width):
                if self.lanes[j] is None:
                    rec.clear(j)
        for j in busy:
            self._collect(j, columns[j], length, out[:, :, j], outcomes.Ended.of(results[j]))

    def _collect(
        self, j: int, column: tuple[np.ndarray, int], length: int, out, ended: outcomes.Ended
    ) -> None:
        """Record lane ``j``'s rows of the call and act on its outcome, as
        :meth:`cayley_heyoka.core.engine.Propagation._propagate` does on a scalar integrator."""
        ta, m = self.ta, self.lanes[j]
        if m is None:
            raise RuntimeError(f"lane {j} has no member to collect")
        points, lead = column
        outcome, steps = ended.outcome, ended.steps
        t = ta.time[j]
        # Rows of the table holding this lane's output times (after any inserted points).
        extra = length - len(points)
        gap = int(np.argmax(np.diff(points))) if extra else 0  # where _padded inserted them
        positions = np.arange(lead, len(points))
        rows = positions + np.where(positions > gap, extra, 0)
        # heyoka writes the outputs a lane passes; a call stopped by a lane going non-finite
        # in its first step writes none (those rows stay NaN, the lanes' times unchanged).
        reached = int(np.count_nonzero(points[lead:] <= t))
        finite = np.all(np.isfinite(out[rows[:reached]]), axis=1)
        if not finite.all():
            reached = int(np.argmin(finite))
        m.steps += steps
        m.counters["steps"] += steps
        m.time = t
        if reached:
            m.rows.keep(out[rows[:reached]].copy(), m.pars)
        self._gather(j, m)
        code = int(outcome)
        if m.status != 0 or (t == points[-1] and m.rows.done == len(self.grid)):
            pass  # stopped by its handler (status set), or every output reached
        elif ended.zero_step:
            m.status, m.message = -1, outcomes.zero_step_message(self.model, t)
        elif m.steps >= self.budget:
            self._out_of_steps(m, t)
        elif outcome == hy.taylor_outcome.err_nf_state:
            m.status, m.nonfinite = -1, True
            when = t if np.isfinite(t) else self.grid[max(m.rows.done - 1, 0)]
            m.message = outcomes.nonfinite(when)
        elif outcome in (hy.taylor_outcome.success, hy.taylor_outcome.step_limit) or code >= 0:
            pass  # another lane stopped the call, this one at the end of a whole step
        elif code < 0 and -code - 1 < len(self.model.terminal):
            pass  # its twin's handler stopped (the lane stands where its own would have)
        elif outcome != hy.taylor_outcome.time_limit:
            m.status = -1
            m.message = outcomes.other(outcome, t)
        self._record_trivial(j)

    def _gather(self, j: int, m: _Member) -> None:
        """Move the crossings lane ``j``'s recorders hold into its member ``m``'s."""
        for rec, times, directions in zip(
            self.recorders, m.event_times, m.event_directions, strict=True
        ):
            got_t, got_d = rec.take(j)
            times += got_t
            directions += got_d

    def _on_terminal(self, index: int, ta: Any, lane: int) -> bool:
        """Terminal event ``index`` of lane ``lane``, within heyoka's call: its member's
        handler on a view of the lane (:class:`_LaneView`); whether the lane goes on."""
        cancel = self.cancel
        if cancel is not None and cancel.is_set():
            return False  # its parameters may hold a Cancel's poison: stop the lane
        m = self.lanes[lane] or self.twins[lane]
        if m is None:
            raise RuntimeError(f"lane {lane} reached a terminal event with no member")
        t = self.hi[lane]  # heyoka's time is the high part of its double-length time
        m.rows.passing((t, self.lo[lane]), m.pars)
        spec, view = m.terminal[index], self.views[lane]
        stop = call_handler(spec, view, m.pars, t)
        view.pars[:] = m.pars[: self.held] if self.held < len(m.pars) else m.pars
        m.counters[spec.counter] += 1
        if stop is not None:
            if isinstance(stop, Handover):
                # The variant's code is another batch integrator: the member goes to run().
                m.status, m.handover = -1, True
                m.message = f"handed over to the model's variant {stop.variant!r} at t = {t}"
                return False
            m.status, m.message = -1, stop
            if spec.records is not None:
                m.stopped_at = (spec.records, t, spec.direction)
            return False
        if m.parity is not None:
            self._gather(lane, m)
            m.parity.note(np.ascontiguousarray(view.state), m.pars, t, m.crossings())
        if cancel is not None and cancel.is_set():
            view.pars[:] = np.nan  # a Cancel's poison was overwritten just above
        return True

    def _out_of_steps(self, m: _Member, t: float) -> None:
        m.status, m.message = -1, outcomes.out_of_steps(self.budget, t)

    def _finish(self, j: int, m: _Member) -> None:
        """Hand lane ``j``'s member ``m`` to the results; the lane takes the next one."""
        self.results.put(m.index, self._result(m))
        self._assign(j)

    def _result(self, m: _Member) -> LaneResult:
        if m.terminal:  # handlers change parameters (a chart's base): one vector per row
            states, pars = m.rows.joined(0, (self.ta.dim, len(m.pars)))
        else:
            states, pars = m.rows.joined_states(self.ta.dim), m.pars
        if m.parity is not None:
            m.parity.finish(m.crossings())
        recorded = m.crossings()
        logged = [m.stopped_at] if m.stopped_at is not None else []
        events = recording.logs_of(self.model, recorded, _DOUBLE, logged)
        return LaneResult(
            states, pars, m.status, m.message, m.counters, events, m.time, m.nonfinite, m.handover
        )


def _finite_dtime(ta: Any) -> tuple[np.ndarray, np.ndarray]:
    """Copies of the lanes' double-length times, a lane gone non-finite (about to be given a
    member or a copy of a busy lane) at 0: heyoka refuses to set a non-finite time."""
    hi, lo = (np.where(np.isfinite(a), a, 0.0) for a in ta.dtime)
    return hi, lo


def _padded(points: np.ndarray, length: int) -> np.ndarray:
    """``points`` with ``length - len(points)`` unused times inserted in their widest gap
    (strictly increasing, so heyoka accepts the grid; only the last point ends a step)."""
    extra = length - len(points)
    if extra == 0:
        return points
    k = int(np.argmax(np.diff(points)))
    a, b = points[k], points[k + 1]
    fill = np.unique(a + (b - a) * (np.arange(1, extra + 1) / (extra + 1)))
    fill = fill[(fill > a) & (fill < b)]
    if len(fill) < extra:
        raise ValueError(
            f"output.times: no gap between output times holds {extra} distinct doubles "
            f"(widest {float(a)!r} … {float(b)!r}); such a grid cannot be batched — run the "
            "members with cayley_heyoka.run"
        )
    return np.concatenate((points[: k + 1], fill, points[k + 1 :]))
