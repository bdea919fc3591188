"""Build → compile (cached) → propagate → record: the one path every model family takes.

Compiled integrators are cached in memory by the *structure* of the equations (the numbers
live in runtime parameters), so running a scene again, or a scene differing only in its
numbers, costs a reset of an integrator a finished run handed back (or a copy of the template)
instead of an LLVM compilation; the model of a scene run again is kept too.

Before anything is compiled a run is refused (:class:`SceneError`) if it cannot fit or cannot
mean anything: recorded rows beyond :data:`MAX_RECORD_BYTES`, a ``max_step`` that needs more
steps than the step budget, a non-finite initial state or parameter, and — once compiled — an
output, monitor or expression of the scene's text that is not finite at the first output
time, or a first step that is not; the refusal names the scene field of the cause
(:mod:`.causes`). A run spends at most
``integrator.max_steps`` steps, then stops with its results. In the main thread, Ctrl-C (or a
SIGTERM the caller turns into one) is noted and acted on after the current step: the run ends
there with everything recorded so far (:class:`Interrupted`), the same bits as an
uninterrupted run up to there.
"""

from __future__ import annotations

import math
import time
import warnings
import weakref
from collections.abc import Callable
from typing import Any

import heyoka as hy
import numpy as np

from . import outcomes
from .causes import check_sources, explain_start, start_failure
from .compiler import compile_model, quiet_heyoka
from .errors import IntegrationError, Interrupted, SceneError
from .event_parity import EventParity
from .model import Handover, Model, call_handler, own_terminal
from .precision import Precision
from .recording import (
    all_finite,
    check_fits,
    evaluate_outputs,
    event_logs,
    first_nonfinite,
    start_values,
)
from .result import Result, versions
from .row_pars import Rows
from .scene import Scene, check_units, require_scene
from .signals import WORKER, DeferredSignals, held_signals
from .span_probe import SpanProbe
from .step_callbacks import HeldProgress, Progress, ProgressCallback, SignalCallback, ZeroSteps
from .structures import model_for

__all__ = ["Progress", "Propagation", "model_of", "preflight", "run"]


def run(scene: Scene, progress: Progress | None = None, *, raise_on_failure: bool = True) -> Result:
    """Integrate a scene and record its outputs, events and monitors.

    Parameters
    ----------
    scene
        A validated :class:`~cayley_heyoka.core.scene.Scene`.
    progress
        Called with the current time after each step, in the run's precision (a float, a
        heyoka ``real128`` or ``real``: a quad time beyond 1e308, or one step of 1e-20 at
        t = 1e15, has no float); it slows stepping (for progress bars).
    raise_on_failure
        If True (the default), a run that stops before the last output time raises
        :class:`IntegrationError`. If False it returns its result, as
        :func:`scipy.integrate.solve_ivp` does: ``success`` False, ``status`` −1 and
        ``message`` saying why, with every output time reached before the stop (for a sweep
        or a study that tallies failures instead of catching them).

    Returns
    -------
    Result
        Every output time (or, with ``raise_on_failure=False``, those reached).

    Raises
    ------
    TypeError
        If ``scene`` is not a :class:`~cayley_heyoka.core.scene.Scene` (a dictionary is
        built into one with :meth:`~cayley_heyoka.core.scene.Scene.from_dict`).
    SceneError
        If the scene cannot be run (see the module docstring).
    IntegrationError
        If the run stops early (a non-finite state, a terminal event, the step budget) and
        ``raise_on_failure`` is True; its ``result`` holds what was computed up to there.
    Interrupted
        On Ctrl-C (or another signal raising KeyboardInterrupt) during the propagation; its
        ``result`` holds what was computed, marked interrupted.
    """
    propagation = Propagation(require_scene(scene), progress)
    try:
        try:
            propagation.advance()
        except KeyboardInterrupt:
            if propagation.status != INTERRUPTED:
                raise
            # The run is ending by a signal: another one (Ctrl-C twice) must not lose the
            # rows while they are gathered.
            with held_signals():
                raise Interrupted(propagation.message, propagation.result()) from None
        result = propagation.result()
    finally:
        propagation.release()
    if result.status != 0 and raise_on_failure:
        raise IntegrationError(result.message, result)
    return result


#: :attr:`Result.status` of a run ended by a signal (other early stops are -1).
INTERRUPTED = -2


def model_of(scene: Scene) -> Model:
    """``scene``'s model, built once per scene object while it lives.

    Running one scene again (a benchmark, a notebook cell) then costs no build. (Each run
    takes its own copies of terminal-event handlers that keep state: :func:`own_terminal`.)
    """
    return _held(scene).model


class _Held:
    """What a run of a scene needs that does not change from run to run: its model, whether
    the refusals that depend on the scene alone were checked (they passed), and whether its
    span was probed and found to fit (:mod:`.span_probe`: a run's first steps, the same at
    every run of the scene)."""

    __slots__ = ("model", "ref", "checked", "probed")

    def __init__(self, scene: Scene, model: Model) -> None:
        self.ref = weakref.ref(scene)
        self.model = model
        self.checked = False
        self.probed = False


def _held(scene: Scene) -> _Held:
    key = id(scene)
    held = _MODELS.get(key)
    if held is not None and held.ref() is scene:
        return held
    # Overflows while building are not reported by numpy: the run's checks name them.
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        held = _Held(scene, model_for(scene))
    if len(_MODELS) >= _MODELS_HELD:
        _MODELS.pop(next(iter(_MODELS)))
    _MODELS[key] = held
    return held


#: Models of the scenes run last (by object: a scene is immutable once validated).
_MODELS: dict[int, _Held] = {}
_MODELS_HELD = 64


def preflight(scene: Scene) -> None:
    """Raise the :class:`SceneError` that :func:`run` would raise before integrating, if any.

    For computations that integrate a scene their own way (consistency checks, variational
    equations): the same refusals as a run. Compiles the scene's integrator (or takes it from
    the cache, where a later :func:`run` finds it).
    """
    Propagation(scene).release()


class Propagation:
    """One scene's integration, advanced stretch by stretch; :func:`run` is one stretch.

    A run that must survive interruption (``cayley-heyoka reference``) advances to fixed
    boundary times, saves :meth:`snapshot` after each and, after an interruption, continues a
    new ``Propagation`` from the last one with :meth:`restore`. A boundary ends a step (it is
    the last point of a ``propagate_grid`` call), so the trajectory depends on the boundaries,
    never on whether the run was interrupted: a resumed run ends with the same bits.

    Parameters
    ----------
    scene
        A validated scene.
    progress
        Called with the current time after each step.
    keep
        Keep the recorded states in memory for :meth:`result` (a caller that stores each
        stretch's rows itself passes False and gives them back to :meth:`result`).
    """

    _parity: EventParity | None  # the crossings beside terminal events (None: not needed)

    def __init__(self, scene: Scene, progress: Progress | None = None, keep: bool = True) -> None:
        self._wall0 = time.perf_counter()
        self.scene = scene
        self.precision = prec = scene.integrator.precision
        held = _held(scene)
        self.model = model = held.model
        # The whole parameter vector (outputs may use parameters the equations do not);
        # the integrator holds its leading part, copied back whenever a handler changes it.
        initial, self._pars = start_values(model, prec)
        if not held.checked:
            check_fits(scene, model)
            check_units(scene, [*model.outputs, *model.monitors])
        self.grid = scene.time_grid
        self.compiled, self._cached = compile_model(model, scene.integrator)
        self._compile_seconds = 0.0 if self._cached else self.compiled.compile_seconds
        self._first = model
        # A variant a terminal handler asked for (:class:`Handover`), taken over after the call.
        self._handover: Handover | None = None
        if not held.checked:
            first = evaluate_outputs(
                self.compiled, model, initial[None, :], self._pars[None, :], self.grid[:1]
            )
            if not all_finite(first, model.unbounded):
                raise start_failure(model, prec, initial, self._pars, self.grid[0], first)
            check_sources(model, prec, initial, self._pars, self.grid[0])
            held.checked = True  # a scene's numbers do not change: checked once
        self._initial = initial
        self._ta = ta = self._fresh_integrator()
        self._held = len(ta.pars)
        ta.pars[:] = self._pars[: self._held]
        self._start_parity()
        self._signals = DeferredSignals(self._stop_stepping)
        self._zero = ZeroSteps()
        self._callback = ProgressCallback(progress, self._signals, self._zero) if progress else None
        # Whether a signal stops heyoka by poisoning the parameters (see Watch), set per call
        # of advance().
        self._poisoning = False
        # Runtime only: a step cap changes no compiled code, so it shares the cached integrator.
        self._limit = {}
        if scene.integrator.max_step is not None:
            self._limit["max_delta_t"] = prec.number(scene.integrator.max_step)
        self._keep = keep
        # The rows kept, the parameters each was computed with, the current call's schedule.
        self._rows = Rows()
        self.terminal = own_terminal(model.terminal)
        self.counters = {"steps": 0, **{spec.counter: 0 for spec in model.terminal}}
        self.status, self.message = 0, "every output time was reached"
        # Occurrences of recorded events logged by terminal events that stand for them.
        self._logged: list[tuple] = []
        self._probe = SpanProbe(scene, self.grid[0])
        self._scene_record = held
        if held.probed:
            self._probe.done()

    @property
    def time(self) -> Any:
        """The integrator's current time."""
        return self._ta.time

    @property
    def done(self) -> int:
        """Output times recorded so far."""
        return self._rows.done

    @property
    def finished(self) -> bool:
        """Whether every output time is recorded or the run has stopped."""
        return self.status != 0 or self.done == len(self.grid)

    def advance(self, until: Any = None) -> tuple[np.ndarray, np.ndarray]:
        """Propagate through the output times up to ``until`` and end exactly there.

        Parameters
        ----------
        until
            A time in the run's precision, at most the last output time; None: to the end.

        Returns
        -------
        states, pars
            The rows recorded by this call: states, and the whole parameter vector at each.
        """
        grid, model = self.grid, self.model
        if until is None:
            until = grid[-1]
        end = int(np.searchsorted(grid, until, side="right"))
        first = len(self._rows.states)
        budget = self.scene.integrator.max_steps
        try:
            with self._signals, quiet_heyoka():
                self._poisoning = self._signals.active and self._can_poison()
                if not self._poisoning:
                    self._propagate(until, end, budget)
                else:
                    if self._probe.limit is not None:
                        # The first call takes at most PROBES[0] steps (µs in double): here,
                        # without a thread; a run that needs no more ends with it.
                        self._propagate(until, end, budget, calls=1)
                    if self.status == 0 and (self.done < end or self._ta.time < until):
                        WORKER.run(
                            lambda: self._propagate(until, end, budget),
                            self._stop_stepping,
                            self._stop_harder,
                        )
        finally:
            if self._poisoning and self._ta is not None:
                self._ta.pars[:] = self._pars[: self._held]  # a signal may have poisoned them
            state, pars = self._rows.joined(first, (len(model.system), len(model.pars)))
            if not self._keep:
                self._rows.forget(first)
        return state, pars

    def _can_poison(self) -> bool:
        """Whether a signal can stop heyoka without a per-step callback (:class:`Watch`)."""
        return self._callback is None and self.precision.kind == "double"

    def _stop_stepping(self) -> None:
        """Called in the main thread when a signal is noted: with :class:`Watch`, make the
        next step non-finite, so that heyoka returns after the last whole step: by its
        parameters, or for equations without any (a Hamiltonian of integers) by its state.
        A step under way when the state is poisoned writes it back, finite: the next one is
        poisoned by :meth:`_stop_harder`."""
        ta = self._ta
        if self._poisoning and ta is not None:
            if self.compiled.rhs_pars:
                ta.pars[self.compiled.rhs_pars] = np.nan
            else:
                ta.state[:] = np.nan

    def _stop_harder(self) -> bool:
        """Called by :class:`Watch` while heyoka steps: whether the run must be stopped by
        poisoning its state as well as its parameters, which it then does.

        Steps of size zero (:func:`.outcomes.zero_step`) see neither the parameters nor change
        the state, and heyoka goes on taking them to its step limit: stopped so when a signal
        has not stopped the run within a wait, or when the waits found heyoka's last step of
        size zero and its time unchanged for a second (:class:`ZeroSteps`). Poisoned again
        at each call, since each such step writes back the state it read.
        """
        ta = self._ta
        if not (self._poisoning and ta is not None):
            return False
        if not (self._signals.received or self._zero.watch(ta, self._began)):
            return False
        ta.pars[self.compiled.rhs_pars] = np.nan
        ta.state[:] = np.nan
        return True

    def _propagate(
        self,
        until: Any,
        end: int,
        budget: int,
        calls: int | None = None,
    ) -> None:
        """heyoka's calls up to ``until`` (the output times before ``end``), each call's rows
        kept (:class:`.row_pars.Rows`); at most ``calls`` calls (None: as many as it takes).

        Outputs come from heyoka's dense output: only the last point of a ``propagate_grid``
        call ends a step there. One call covers every output time up to ``until``: terminal
        events are handled inside it (:class:`TerminalCallback`), so the trajectory depends
        neither on the output grid nor on where events fall. A call returns early only to stop
        (a handler's stop, the step budget, a non-finite state, a signal) or at the end of the
        first call's probe (:class:`.span_probe.SpanProbe`).
        """
        ta = self._ta
        while self.status == 0 and (self.done < end or ta.time < until):
            self._raise_if_interrupted()
            if calls is not None:
                if calls == 0:
                    return
                calls -= 1
            left = budget - self.counters["steps"]
            if left <= 0:
                self._out_of_steps(budget)
                break
            points, outputs, resume = self._call_points(until, end)
            callback, limit = self._call_guard(left)
            call = outcomes.GridRun.of(
                ta.propagate_grid(points, callback=callback, max_steps=limit, **self._limit)
            )
            ended = call.ended
            stuck = (ended.zero_step or self._zero.seen) and not self._signals.received
            if self._probe.limit is not None:
                cut = ended.outcome == hy.taylor_outcome.step_limit and limit < left and not stuck
                self._probe.after(self.counters["steps"] + ended.steps, ta.dtime, budget, cut)
                self._scene_record.probed = self._probe.fits
                if cut:
                    # Resuming this call would change bits (see below): start again, uncut.
                    ta = self._restart()
                    continue
            if isinstance(callback, HeldProgress):
                callback.release()
            self._record(call.states[int(resume) : int(resume) + outputs], ended)
            if self._handover is not None:
                ta = self._take_over(self._handover.variant)
                self._settle(ta, ta.time)  # in the variant's terms (its events' expressions)
                continue
            if not self._goes_on(ended, stuck, budget):
                break

    def _raise_if_interrupted(self) -> None:
        """A signal received: the run is interrupted (its status and message say where)."""
        if not self._signals.received:
            return
        self.status = INTERRUPTED
        # A poisoned step leaves heyoka's time NaN: name the last output time kept.
        t = self._ta.time
        when = t if math.isfinite(float(t)) else self.grid[max(self.done - 1, 0)]
        self.message = (
            f"interrupted ({self._signals.received}) at t = {when}; results kept up to there"
        )
        raise KeyboardInterrupt

    def _call_points(self, until: Any, end: int) -> tuple[np.ndarray, int, bool]:
        """The next call's grid — the output times left before ``end``, ``until`` after them
        if it is none, the current time before them if the run stands between two — with how
        many are outputs and whether the current time leads them; and the rows it records,
        for :meth:`_on_terminal`."""
        prec, grid, i = self.precision, self.grid, self.done
        points = grid[i:end]
        outputs = len(points)
        if outputs == 0 or points[-1] != until:
            points = _ending_at(prec, points, until)  # a boundary, not an output
        resume = self._ta.time != points[0]
        if resume:
            points = _starting_at(prec, self._ta.time, points)
        self._rows.begin(grid[i : i + outputs])
        return points, outputs, resume

    def _call_guard(self, left: int) -> tuple[Callable[[Any], bool] | None, int]:
        """The next call's step callback and step limit.

        A call that returned mid-stretch could not be resumed without changing bits (heyoka
        starts each call with a step to its first point, and the double-length time is not a
        grid point), so a signal ends the call after a whole step: by poisoning the
        parameters (Watch), or else by a callback after each step."""
        callback: Callable[[Any], bool] | None = self._callback
        if callback is None and self._signals.active and not self._poisoning:
            callback = SignalCallback(self._signals, self._zero)
        probe = self._probe.limit
        if probe is not None and isinstance(callback, ProgressCallback):
            # Progress is reported once a step is kept: a cut probe is taken again.
            callback = HeldProgress(callback)
        return callback, left if probe is None else min(left, probe)

    def _record(self, out: np.ndarray, ended: outcomes.Ended) -> None:
        """Keep a call's output rows, each with the parameters in force when it was computed."""
        self.counters["steps"] += ended.steps
        self._rows.keep(out, self._pars)

    def _goes_on(self, ended: outcomes.Ended, stuck: bool, budget: int) -> bool:
        """After a call: whether the run goes on, or else why it stopped (status, message)."""
        outcome, ta = ended.outcome, self._ta
        if outcome == hy.taylor_outcome.time_limit:
            return True
        if stuck:
            when = self._zero.at if self._zero.seen else ta.time
            self.status, self.message = -1, outcomes.zero_step_message(self.model, when)
            return False
        if outcome == hy.taylor_outcome.step_limit:
            self._out_of_steps(budget)
            return False
        if self._signals.received and self.status == 0:
            return True  # reported at the top of the loop
        if -len(self.terminal) <= int(outcome) <= -1:
            return True  # a handler stopped the run (its status and message are set)
        self.status = -1
        if outcome == hy.taylor_outcome.err_nf_state:
            # heyoka's time may itself be NaN then: name the last output time kept instead.
            t = ta.time
            when = t if math.isfinite(float(t)) else self.grid[max(self.done - 1, 0)]
            self.message = outcomes.nonfinite(when)
            if self.done == 0 and (cause := self._cause_at_start()) is not None:
                raise cause  # the first step cannot be taken: nothing was integrated
        elif outcome == hy.taylor_outcome.cb_stop:
            self.message = f"stopped by the progress callback at t = {ta.time}"
        else:
            self.message = outcomes.other(outcome, ta.time)
        return False

    def _cause_at_start(self) -> SceneError | None:
        """Why the first step could not be finite: the first of the model's expressions and
        right-hand sides not finite at the start (:func:`explain_start`), if any."""
        prec, model = self.precision, self._first
        pars = prec.array(model.pars.values)
        return explain_start(model, prec, self._initial, pars, self.grid[0])

    def _fresh_integrator(self) -> Any:
        ta = self.compiled.take()
        ta.time = self._began = self.grid[0]  # (a fresh integrator's last step is 0)
        ta.state[:] = self._initial
        for ev in ta.t_events if self.model.terminal else ():
            ev.callback.target = self._on_terminal
        self._ta_pars = ta.pars  # a view of the integrator's parameters (building one: ~1 µs)
        self._recorders = [ev.callback for ev in ta.nt_events] if self.model.events else []
        return ta

    def _release_integrator(self) -> None:
        ta, self._ta = self._ta, None
        for ev in ta.t_events if self.model.terminal else ():
            ev.callback.target = None  # no reference from a spare integrator to this run
        self.compiled.give(ta)

    def release(self) -> None:
        """Hand the integrator back for reuse by later runs; this propagation is done with it
        (its :meth:`result` taken)."""
        if self._ta is not None:
            self._release_integrator()

    def _take_over(self, variant: str) -> Any:
        """Go on with the model's ``variant``: the same time, state, parameters, tallies,
        handlers' own state and recorded events, in the variant's compiled integrator."""
        self._handover = None
        old, model = self._ta, self.model
        if model.variants is None:
            raise RuntimeError(f"a handler asked for variant {variant!r} of a model without any")
        target = model.variants(variant)
        if target.pars.names != model.pars.names or target.state_names != model.state_names:
            raise RuntimeError(f"variant {variant!r} does not share its model's state and pars")
        compiled, cached = compile_model(target, self.scene.integrator)
        if not cached:
            self._compile_seconds += compiled.compile_seconds
        dtime, state = old.dtime, old.state.copy()
        self._began = old.time
        recorded = [
            (list(ev.callback.times), list(ev.callback.directions))
            for ev in (old.nt_events if model.events else [])
        ]
        kept = {
            spec.counter: spec.handle.checkpoint()
            for spec in self.terminal
            if hasattr(spec.handle, "checkpoint")
        }
        self._release_integrator()
        self.model, self.compiled = target, compiled
        self.terminal = own_terminal(target.terminal)
        for spec in self.terminal:
            if spec.counter in kept and hasattr(spec.handle, "resume"):
                spec.handle.resume(kept[spec.counter])
            self.counters.setdefault(spec.counter, 0)
        self._ta = ta = self._fresh_integrator()
        ta.dtime = dtime
        ta.state[:] = state
        self._held = len(ta.pars)
        ta.pars[:] = self._pars[: self._held]
        for ev, (times, directions) in zip(
            ta.nt_events if target.events else [], recorded, strict=True
        ):
            ev.callback.times, ev.callback.directions = times, directions
        values = compiled.event_values
        if self._parity is not None:
            if values is not None:
                self._parity.flush(self._crossings())  # the states noted, in the old terms
            else:
                self._parity.finish(self._crossings())  # and decided: none follow
        if values is None:
            self._parity = None
        elif self._parity is None:
            # Nothing of the stretch before to account for: the variant's signs from here.
            self._parity = EventParity(values)
            self._parity.start(ta.state, self._pars, ta.time, self._crossings())
        else:
            self._parity.values = values
        return ta

    def _restart(self) -> Any:
        """Back to the first output time with the integrator reset (its event recorders
        empty), the terminal handlers, their tallies and the parameters as at the start;
        nothing was recorded yet."""
        self._release_integrator()
        if self.model is not self._first:
            self.model = self._first
            self.compiled, _ = compile_model(self._first, self.scene.integrator)
        self._pars = self.precision.array(self.model.pars.values)
        self.terminal = own_terminal(self.model.terminal)
        self.counters = dict.fromkeys(self.counters, 0)
        self._logged = []
        self._ta = ta = self._fresh_integrator()
        ta.pars[:] = self._pars[: self._held]
        self._start_parity()
        return ta

    def _out_of_steps(self, budget: int) -> None:
        self.status, self.message = -1, outcomes.out_of_steps(budget, self._ta.time)

    def _on_terminal(self, index: int, ta: Any) -> bool:
        """Terminal event ``index`` reached, within heyoka's call: run its handler; whether
        the integration goes on."""
        if self._signals.received:
            return False  # the parameters may hold a signal's poison: stop, reported after
        t = ta.time
        self._rows.passing(ta.dtime, self._pars)
        spec = self.terminal[index]
        stop = call_handler(spec, ta, self._pars, t)
        self._ta_pars[:] = self._pars[: self._held]
        self.counters[spec.counter] += 1
        if isinstance(stop, Handover):
            self._handover = stop  # taken over when heyoka's call returns (_propagate)
            return False
        if stop is not None:
            self.status, self.message = -1, stop
            if spec.records is not None:
                self._logged.append((spec.records, t, spec.direction))
            return False
        self._settle(ta, t)
        if self._signals.received:
            # A signal noted while the parameters were copied back: its poison was overwritten.
            self._stop_stepping()
        return True

    def _start_parity(self) -> None:
        """The accounting of every crossing of the recorded events beside terminal events
        (:mod:`.event_parity`; None for a model without both), from the start."""
        values = self.compiled.event_values
        self._parity = EventParity(values) if values is not None else None
        if self._parity is not None:
            self._parity.start(self._initial, self._pars, self.grid[0], self._crossings())

    def _crossings(self) -> list[tuple[list, list]]:
        return [(rec.times, rec.directions) for rec in self._recorders]

    def _settle(self, ta: Any, t: Any) -> None:
        """After a terminal handler at ``t``: note the state for :class:`EventParity`."""
        if self._parity is not None:
            self._parity.note(ta.state, self._pars, t, self._crossings())

    def snapshot(self) -> dict[str, Any]:
        """Everything :meth:`restore` needs to continue this run, as JSON-ready values.

        Numbers are decimal text that loads back bit-for-bit; the time is heyoka's
        double-length time (its two parts).
        """
        if self.status != 0:
            raise ValueError(f"a stopped run cannot be continued: {self.message}")
        prec, ta = self.precision, self._ta
        if self._parity is not None:
            self._parity.flush(self._crossings())  # the records as they stand
        return {
            "variant": self.model.variant,
            "done": self.done,
            "time": list(prec.to_text(prec.array(ta.dtime))),
            "state": list(prec.to_text(ta.state)),
            "pars": list(prec.to_text(self._pars)),
            "counters": dict(self.counters),
            "events": [
                [list(prec.to_text(prec.array(ev.callback.times))), list(ev.callback.directions)]
                for ev in (ta.nt_events if self.model.events else [])
            ],
            "handlers": [
                spec.handle.checkpoint() if hasattr(spec.handle, "checkpoint") else None
                for spec in self.terminal
            ],
            "logged": [
                [spec.name, list(prec.to_text(prec.array([t])))[0], d]
                for spec, t, d in self._logged
            ],
            "parity": (
                self._parity.checkpoint(lambda t: str(prec.to_text(prec.array([t]))[0]))
                if self._parity is not None
                else None
            ),
        }

    def restore(self, snapshot: dict[str, Any]) -> None:
        """Continue from a :meth:`snapshot` of a run of the same scene."""
        variant = snapshot.get("variant", "")
        if variant != self.model.variant:
            self._take_over(variant)
        prec, ta = self.precision, self._ta
        self._probe.done()  # its first steps were taken (and the span estimated) before
        self._rows.done = int(snapshot["done"])
        hi, lo = prec.from_text(snapshot["time"])
        ta.dtime = (hi, lo)
        ta.state[:] = prec.from_text(snapshot["state"])
        self._pars = prec.from_text(snapshot["pars"])
        ta.pars[:] = self._pars[: self._held]
        self.counters = {k: int(v) for k, v in snapshot["counters"].items()}
        recorded = ta.nt_events if self.model.events else []
        if len(snapshot["events"]) != len(recorded):
            raise ValueError("the snapshot is of a scene with other events")
        for spec, value in zip(self.terminal, snapshot["handlers"], strict=True):
            if value is not None:
                if not hasattr(spec.handle, "resume"):
                    raise ValueError("the snapshot is of a scene with other event handlers")
                spec.handle.resume(value)
        for ev, (times, directions) in zip(recorded, snapshot["events"], strict=True):
            ev.callback.times = list(prec.from_text(times))
            ev.callback.directions = [int(d) for d in directions]
        specs = {spec.name: spec for spec in self.model.events}
        self._logged = [
            (specs[name], prec.from_text(np.array([t]))[0], int(d))
            for name, t, d in snapshot.get("logged", [])
        ]
        if self._parity is not None:
            parity = snapshot.get("parity")
            if parity is None:
                # A snapshot that kept no baseline: the signs of the restored state.
                self._parity.start(ta.state, self._pars, ta.time, self._crossings())
            elif len(parity["signs"]) != len(recorded):
                raise ValueError("the snapshot is of a scene with other events")
            else:
                self._parity.resume(parity, lambda t: prec.from_text(np.array([t]))[0])

    def result(self, states: np.ndarray | None = None, pars: np.ndarray | None = None) -> Result:
        """The result of what has been recorded (``states``/``pars``: every row, if not kept)."""
        model, prec = self.model, self.precision
        if states is None:
            states, pars = self._rows.joined(0, (len(model.system), len(model.pars)))
        elif pars is None:
            raise ValueError("result(states, pars): the rows' parameters go with their states")
        times = self.grid[: len(states)]
        if self._parity is not None:
            self._parity.finish(self._crossings())
        values = evaluate_outputs(self.compiled, model, states, pars, times)
        if self.status == 0 and (bad := first_nonfinite(model, values, times)) is not None:
            # A finite state can still give an infinite output (V = "1/(t - 1)" at t = 1): the
            # run stops at the last row whose every output is finite, as for the state.
            k, self.message = bad
            self.status = -1
            times = times[:k]
            values = {n: v[:k] for n, v in values.items()}
        return Result(
            t=times,
            variables={k: values[k] for k in model.outputs},
            monitors={k: values[k] for k in model.monitors},
            conserved=model.conserved,
            events=event_logs(model, self._ta, prec, self._logged),
            precision=prec,
            status=self.status,
            message=self.message,
            counters=dict(self.counters),
            scene=self.scene.to_dict(),
            metadata={
                **versions(),
                "wall_seconds": time.perf_counter() - self._wall0,
                "compile_seconds": self._compile_seconds,
                "compiled_from_cache": self._cached,
                "order": int(self._ta.order),
                "tolerance": str(self._ta.tol),
            },
        )


# ---------------------------------------------------------------------- internals
def _starting_at(prec: Precision, t: Any, points: np.ndarray) -> np.ndarray:
    """``points`` preceded by the current time ``t`` (heyoka's grids start there)."""
    if prec.kind != "real":
        # Not np.concatenate: at every terminal event, and this is half its cost.
        out = np.empty(len(points) + 1, dtype=points.dtype)
        out[0], out[1:] = t, points
        return out
    # Through Python objects: numpy's copies of heyoka's multiprecision dtype alias limbs.
    return prec.array([t, *points])


def _ending_at(prec: Precision, points: np.ndarray, t: Any) -> np.ndarray:
    """``points`` followed by ``t``."""
    if prec.kind != "real":
        return np.concatenate((points, np.array([t], dtype=points.dtype)))
    return prec.array([*points, t])
