"""Build → compile (cached) → propagate → record: the one path every model family takes.

Compiled integrators are cached in memory by the *structure* of the equations (the numbers
live in runtime parameters), so running a scene again, or a scene differing only in its
numbers, costs a reset of an integrator a finished run handed back (or a copy of the template)
instead of an LLVM compilation; the model of a scene run again is kept too.

Before anything is compiled a run is refused (:class:`SceneError`) if it cannot fit or cannot
mean anything: recorded rows beyond :data:`MAX_RECORD_BYTES`, a ``max_step`` that needs more
steps than the step budget, a non-finite initial state or parameter, and — once compiled — an
output or monitor that is not finite at the first output time. A run spends at most
``integrator.max_steps`` steps, then stops with its results. In the main thread, Ctrl-C (or a
SIGTERM the caller turns into one) is noted and acted on after the current step: the run ends
there with everything recorded so far (:class:`Interrupted`), the same bits as an
uninterrupted run up to there.
"""

from __future__ import annotations

import contextlib
import copy
import hashlib
import math
import queue
import re
import signal
import threading
import time
import warnings
import weakref
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any

import heyoka as hy
import numpy as np

from .errors import IntegrationError, Interrupted, SceneError
from .families import FAMILIES
from .model import Model, own_terminal
from .precision import Precision, exact_fraction
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
    #: Indices of the parameters the right-hand sides use (see :class:`_Watch`).
    rhs_pars: list[int] = field(default_factory=list)


#: Integrators kept for reuse per compiled structure (one per thread that runs it at once).
_SPARE = 8


_CACHE: dict[str, Compiled] = {}

#: Largest estimated memory of a run's recorded rows (output times × (state + parameters +
#: outputs + monitors) numbers); the results, their evaluation and the saved file need a few
#: times this again, so a run above it would exhaust an ordinary machine.
MAX_RECORD_BYTES = 2**30


def clear_cache() -> None:
    """Forget every compiled integrator (for measuring compile time)."""
    _CACHE.clear()


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
    with _signals_end_process(), quiet_heyoka():
        compiled = _compile(model, options)
    _CACHE[key] = compiled
    return compiled, False


@contextlib.contextmanager
def signals_end_compilation() -> Iterator[None]:
    """Within this context, SIGINT or SIGTERM during an LLVM compilation ends the process.

    LLVM compiles in C++ without returning to Python, so Python's handlers (Ctrl-C's
    KeyboardInterrupt) would run only when it is done — after seconds or minutes. Nothing is
    computed before the compilation, so for a command-line process ending at once loses
    nothing; the signals get their default disposition while compiling, Python's handlers
    back afterwards. Only in the main thread.
    """
    global _END_ON_SIGNAL
    _END_ON_SIGNAL += 1
    try:
        yield
    finally:
        _END_ON_SIGNAL -= 1


_END_ON_SIGNAL = 0
_SIGNALS = (signal.SIGINT, signal.SIGTERM)


@contextlib.contextmanager
def _signals_end_process() -> Iterator[None]:
    if not _END_ON_SIGNAL or threading.current_thread() is not threading.main_thread():
        yield
        return
    old = {sig: signal.signal(sig, signal.SIG_DFL) for sig in _SIGNALS}
    try:
        yield
    finally:
        for sig, handler in old.items():
            signal.signal(sig, handler)


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
    nt_events = [
        hy.nt_event(e.expression, _Recorder(), direction=_direction(e.direction), **ev_kw)
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
    outputs = _flat_outputs(model)
    evaluator = hy.cfunc(
        [e for _, e in outputs], [v for v, _ in model.system], compact_mode=compact, **kw
    )
    rhs_pars = sorted(int(str(p)[1:]) for p in hy.get_params([rhs for _, rhs in model.system]))
    return Compiled(ta, evaluator, time.perf_counter() - t0, rhs_pars=rhs_pars)


def run(scene: Scene, progress: Progress | None = None) -> Result:
    """Integrate a scene and record its outputs, events and monitors.

    Parameters
    ----------
    scene
        A validated :class:`~cayley_heyoka.core.scene.Scene`.
    progress
        Called with the current time after each step (slows stepping; for progress bars).

    Returns
    -------
    Result
        Every output time.

    Raises
    ------
    SceneError
        If the scene cannot be run (see the module docstring).
    IntegrationError
        If the run stops early (a non-finite state, a terminal event, the step budget); its
        ``result`` holds what was computed up to there.
    Interrupted
        On Ctrl-C (or another signal raising KeyboardInterrupt) during the propagation; its
        ``result`` holds what was computed, marked interrupted.
    """
    propagation = Propagation(scene, progress)
    try:
        try:
            propagation.advance()
        except KeyboardInterrupt:
            if propagation.status != INTERRUPTED:
                raise
            raise Interrupted(propagation.message, propagation.result()) from None
        result = propagation.result()
    finally:
        propagation.release()
    if result.status != 0:
        raise IntegrationError(result.message, result)
    return result


#: :attr:`Result.status` of a run ended by a signal (other early stops are -1).
INTERRUPTED = -2


def model_of(scene: Scene) -> Model:
    """``scene``'s model, built once per scene object while it lives.

    Running one scene again (a benchmark, a notebook cell) then costs no build. (Each run
    takes its own copies of terminal-event handlers that keep state: :func:`own_terminal`.)
    """
    key = id(scene)
    held = _MODELS.get(key)
    if held is not None and held[0]() is scene:
        return held[1]
    model = FAMILIES[scene.family].build(scene)
    if len(_MODELS) >= _MODELS_HELD:
        _MODELS.pop(next(iter(_MODELS)))
    _MODELS[key] = (weakref.ref(scene), model)
    return model


#: Models of the scenes run last (by object: a scene is immutable once validated).
_MODELS: dict[int, tuple[weakref.ref, Model]] = {}
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

    def __init__(self, scene: Scene, progress: Progress | None = None, keep: bool = True) -> None:
        self._wall0 = time.perf_counter()
        self.scene = scene
        self.precision = prec = scene.integrator.precision
        # Overflows while building are not reported by numpy: the checks below name them.
        with np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            self.model = model = model_of(scene)
            initial = prec.array(model.initial_state)
            # The whole parameter vector (outputs may use parameters the equations do not);
            # the integrator holds its leading part, copied back whenever a handler changes it.
            self._pars = prec.array(model.pars.values)
        check_fits(scene, model)
        self.grid = scene.output.time_grid(prec)
        _require_finite(initial, [f"initial.{n}" for n in model.state_names], "initial state")
        _require_finite(self._pars, [f"parameters.{n}" for n in model.pars.names], "parameter")
        self.compiled, self._cached = compile_model(model, scene.integrator)
        first = evaluate_outputs(
            self.compiled, model, initial[None, :], self._pars[None, :], self.grid[:1], prec
        )
        for name, value in first.items():
            if name in model.unbounded:
                continue
            kind = "monitors" if name in model.monitors else "outputs"
            _require_finite(np.ravel(value), [f"{kind}.{name}"] * np.size(value), kind[:-1])
        self._initial = initial
        self._ta = ta = self._fresh_integrator()
        self._held = len(ta.pars)
        ta.pars[:] = self._pars[: self._held]
        self._signals = _DeferredSignals(self._stop_stepping)
        self._callback = _ProgressCallback(progress, self._signals) if progress else None
        # Whether a signal stops heyoka by poisoning the parameters (see _Watch), set per call
        # of advance().
        self._poisoning = False
        # Runtime only: a step cap changes no compiled code, so it shares the cached integrator.
        self._limit = {}
        if scene.integrator.max_step is not None:
            self._limit["max_delta_t"] = prec.number(scene.integrator.max_step)
        self._keep = keep
        self._states: list[np.ndarray] = []
        self._pars_rows: list[np.ndarray] = []
        self.terminal = own_terminal(model.terminal)
        self.counters = {"steps": 0, **{spec.counter: 0 for spec in model.terminal}}
        self.status, self.message = 0, "every output time was reached"
        self._stopped_at: tuple | None = None
        # The output times the current call may record (increasing), the parameter vectors of
        # the first of them — those passed before a terminal handler changed the parameters —
        # and the time of the next one (None: none left), for :meth:`_on_terminal`.
        self._rows: np.ndarray = self.grid[:0]
        self._rows_pars: list[np.ndarray] = []
        self._next_row: Any = None
        #: Output times recorded so far.
        self.done = 0
        # The first steps estimate what the whole span needs (``_estimate``): the limits of
        # the probing calls still to make, each cut short to take them and then taken again.
        self._probes = list(_PROBES)

    @property
    def time(self) -> Any:
        """The integrator's current time."""
        return self._ta.time

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
        states: list[np.ndarray] = []
        pars_rows: list[np.ndarray] = []
        budget = self.scene.integrator.max_steps
        try:
            with self._signals, quiet_heyoka():
                self._poisoning = self._signals.active and self._can_poison()
                if not self._poisoning:
                    self._propagate(until, end, budget, states, pars_rows)
                else:
                    if self._probes:
                        # The first call takes at most _PROBES[0] steps (µs in double): here,
                        # without a thread; a run that needs no more ends with it.
                        self._propagate(until, end, budget, states, pars_rows, calls=1)
                    if self.status == 0 and (self.done < end or self._ta.time < until):
                        _WORKER.run(
                            lambda: self._propagate(until, end, budget, states, pars_rows),
                            self._stop_stepping,
                        )
        finally:
            if self._poisoning and self._ta is not None:
                self._ta.pars[:] = self._pars[: self._held]  # a signal may have poisoned them
            width = (len(model.system), len(model.pars))
            state = np.concatenate(states) if states else np.empty((0, width[0]))
            pars = np.array(pars_rows) if pars_rows else np.empty((0, width[1]))
            if self._keep:
                self._states.append(state)
                self._pars_rows.append(pars)
        return state, pars

    def _can_poison(self) -> bool:
        """Whether a signal can stop heyoka without a per-step callback (:class:`_Watch`)."""
        return (
            self._callback is None
            and self.precision.kind == "double"
            and bool(self.compiled.rhs_pars)
        )

    def _stop_stepping(self) -> None:
        """Called in the main thread when a signal is noted: with :class:`_Watch`, make the
        next step non-finite, so that heyoka returns after the last whole step."""
        ta = self._ta
        if self._poisoning and ta is not None:
            ta.pars[self.compiled.rhs_pars] = np.nan

    def _propagate(
        self,
        until: Any,
        end: int,
        budget: int,
        states: list,
        pars_rows: list,
        calls: int | None = None,
    ) -> None:
        ta, prec, grid = self._ta, self.precision, self.grid
        # Outputs come from heyoka's dense output: only the last point of a propagate_grid call
        # ends a step there. One call covers every output time up to ``until``: terminal
        # events are handled inside it (:class:`TerminalCallback`), so the trajectory depends
        # neither on the output grid nor on where events fall. A call returns early only to
        # stop (a handler's stop, the step budget, a non-finite state, a signal) or at the end
        # of the first call's probe.
        while self.status == 0 and (self.done < end or ta.time < until):
            if self._signals.received:
                self.status = INTERRUPTED
                # A poisoned step leaves heyoka's time NaN: name the last output time kept.
                when = ta.time if math.isfinite(float(ta.time)) else grid[max(self.done - 1, 0)]
                self.message = (
                    f"interrupted ({self._signals.received}) at t = {when}; results kept "
                    "up to there"
                )
                raise KeyboardInterrupt
            if calls is not None:
                if calls == 0:
                    return
                calls -= 1
            left = budget - self.counters["steps"]
            if left <= 0:
                self._out_of_steps(budget)
                break
            i = self.done
            points = grid[i:end]
            outputs = len(points)
            if outputs == 0 or points[-1] != until:
                points = _ending_at(prec, points, until)  # a boundary, not an output
            resume = ta.time != points[0]
            if resume:
                points = _starting_at(prec, ta.time, points)
            # A call that returned mid-stretch could not be resumed without changing bits
            # (heyoka starts each call with a step to its first point, and the double-length
            # time is not a grid point), so a signal ends the call after a whole step: by
            # poisoning the parameters (_Watch), or else by a callback after each step.
            callback = self._callback
            if callback is None and self._signals.active and not self._poisoning:
                callback = self._signals.callback
            probe = self._probes[0] if self._probes else None
            limit = left if probe is None else min(left, probe)
            if probe is not None and isinstance(callback, _ProgressCallback):
                # Progress is reported once a step is kept: a cut probe is taken again.
                callback = _HeldProgress(callback)
            self._rows, self._rows_pars = grid[i : i + outputs], []
            self._next_row = grid[i] if outputs else None
            res = ta.propagate_grid(points, callback=callback, max_steps=limit, **self._limit)
            outcome, out = res[0], res[-1]
            taken = self.counters["steps"] + res[3]
            cut = probe is not None and outcome == hy.taylor_outcome.step_limit and limit < left
            if probe is not None:
                self._estimate(taken, ta.time, budget, cut)
            if cut:
                # Resuming this call would change bits (see below): start again, uncut.
                ta = self._restart()
                continue
            if isinstance(callback, _HeldProgress):
                callback.release()
            out = out[int(resume) : int(resume) + outputs]
            self.counters["steps"] += res[3]
            states.append(out)
            given = self._rows_pars[: len(out)]
            pars_rows += given + [self._pars.copy() for _ in range(len(out) - len(given))]
            self.done += len(out)
            code = int(outcome)
            if outcome == hy.taylor_outcome.time_limit:
                continue
            if outcome == hy.taylor_outcome.step_limit:
                self._out_of_steps(budget)
                break
            if self._signals.received and self.status == 0:
                continue  # reported at the top of the loop
            if -len(self.terminal) <= code <= -1:
                continue  # a handler stopped the run (its status and message are set)
            self.status = -1
            if outcome == hy.taylor_outcome.err_nf_state:
                # heyoka's time may itself be NaN then: name the last output time kept instead.
                when = ta.time if math.isfinite(float(ta.time)) else grid[max(self.done - 1, 0)]
                self.message = (
                    f"the state became non-finite after t = {when}; results kept up to there"
                )
            elif outcome == hy.taylor_outcome.cb_stop:
                self.message = f"stopped by the progress callback at t = {ta.time}"
            else:
                self.message = f"stopped at t = {ta.time} with outcome {outcome}"

    def _fresh_integrator(self) -> Any:
        ta = self.compiled.take()
        ta.time = self.grid[0]
        ta.state[:] = self._initial
        for ev in ta.t_events if self.model.terminal else ():
            ev.callback.target = self._on_terminal
        self._ta_pars = ta.pars  # a view of the integrator's parameters (building one: ~1 µs)
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

    def _restart(self) -> Any:
        """Back to the first output time with the integrator reset (its event recorders
        empty), the terminal handlers, their tallies and the parameters as at the start;
        nothing was recorded yet."""
        self._release_integrator()
        self._pars = self.precision.array(self.model.pars.values)
        self.terminal = own_terminal(self.model.terminal)
        self.counters = dict.fromkeys(self.counters, 0)
        self._ta = ta = self._fresh_integrator()
        ta.pars[:] = self._pars[: self._held]
        return ta

    def _estimate(self, steps: int, reached: Any, budget: int, cut: bool) -> None:
        """After a probing call: refuse a run whose first steps show it needs far more steps
        than its budget, or decide whether a longer probe must look first.

        A span of 1e300 would otherwise spend the whole budget (10⁹ steps: many minutes)
        before stopping. The rate of the first steps (those of a probing call, at most
        :data:`_PROBES`) extrapolated over the span must stay within :data:`_ESTIMATE_MARGIN`
        times the budget; the margin leaves room for motions whose steps lengthen (an
        estimate, so only the absurd is refused). The first probe is short, so that a run
        pays for it a few steps only: when its estimate is not :data:`_CLEAR` times inside
        the limit, a longer probe decides.
        """
        probes = self._probes
        probes.pop(0)
        if not cut:
            probes.clear()  # the call ended of itself: nothing is taken again
        needed = self._needed(steps, reached) if steps >= _PROBES[0] else None
        if needed is None:
            return
        limit = _ESTIMATE_MARGIN * budget
        if cut and probes and needed * _CLEAR > limit:
            return  # not clearly within the budget: the next, longer probe decides
        probes.clear()
        if needed > limit:
            first, last = self.scene.output.span()
            raise SceneError(
                "output.times",
                f"the span to t = {last} needs about "
                f"{float(needed):.3g} steps (the first {steps} reached t = {reached}), more than "
                f"{_ESTIMATE_MARGIN} times the step budget integrator.max_steps = {budget}; "
                "shorten the span, or raise integrator.max_steps if the steps will lengthen",
            )

    def _needed(self, steps: int, reached: Any) -> Fraction | None:
        """The steps the whole span needs at the rate of ``steps`` to ``reached`` (None if
        that cannot be told: no time covered, or a non-finite time)."""
        first, last = self.scene.output.span()
        start, stop = exact_fraction(first), exact_fraction(last)
        try:
            covered = exact_fraction(str(reached)) - start
        except (ValueError, ArithmeticError):  # the state (and heyoka's time) became NaN
            return None
        if covered <= 0:
            return None
        return steps * (stop - start) / covered

    def _out_of_steps(self, budget: int) -> None:
        self.status = -1
        self.message = (
            f"the step budget integrator.max_steps = {budget} was spent at t = {self._ta.time}; "
            "results kept up to there (raise integrator.max_steps to go on)"
        )

    def _on_terminal(self, index: int, ta: Any) -> bool:
        """Terminal event ``index`` reached, within heyoka's call: run its handler; whether
        the integration goes on."""
        if self._signals.received:
            return False  # the parameters may hold a signal's poison: stop, reported after
        t = ta.time
        if self._next_row is not None and self._next_row <= t:
            self._pass_rows(t)
        spec = self.terminal[index]
        stop = spec.handle(ta, self._pars)
        self._ta_pars[:] = self._pars[: self._held]
        self.counters[spec.counter] += 1
        if stop is not None:
            self.status, self.message = -1, stop
            if spec.records is not None:
                self._stopped_at = (spec.records, t, spec.direction)
            return False
        if self._signals.received:
            # A signal noted while the parameters were copied back: its poison was overwritten.
            self._stop_stepping()
        return True

    def _pass_rows(self, t: Any) -> None:
        """The output rows up to ``t`` (a terminal event's time) were computed before its
        handler: they keep the parameters in force now (a row exactly at ``t`` too)."""
        rows, given = self._rows, self._rows_pars
        pass_rows(rows, given, t, self._pars)
        self._next_row = rows[len(given)] if len(given) < len(rows) else None

    def snapshot(self) -> dict[str, Any]:
        """Everything :meth:`restore` needs to continue this run, as JSON-ready values.

        Numbers are decimal text that loads back bit-for-bit; the time is heyoka's
        double-length time (its two parts).
        """
        if self.status != 0:
            raise ValueError(f"a stopped run cannot be continued: {self.message}")
        prec, ta = self.precision, self._ta
        return {
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
        }

    def restore(self, snapshot: dict[str, Any]) -> None:
        """Continue from a :meth:`snapshot` of a run of the same scene."""
        prec, ta = self.precision, self._ta
        # Its first steps were taken (and the span estimated) before the snapshot.
        self._probes = []
        self.done = int(snapshot["done"])
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
                spec.handle.resume(value)
        for ev, (times, directions) in zip(recorded, snapshot["events"], strict=True):
            ev.callback.times = list(prec.from_text(times))
            ev.callback.directions = [int(d) for d in directions]

    def result(self, states: np.ndarray | None = None, pars: np.ndarray | None = None) -> Result:
        """The result of what has been recorded (``states``/``pars``: every row, if not kept)."""
        model, prec = self.model, self.precision
        if states is None:
            width = (len(model.system), len(model.pars))
            states = np.concatenate(self._states) if self._states else np.empty((0, width[0]))
            pars = np.concatenate(self._pars_rows) if self._pars_rows else np.empty((0, width[1]))
        times = self.grid[: len(states)]
        values = evaluate_outputs(self.compiled, model, states, pars, times, prec)
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
            events=event_logs(model, self._ta, prec, self._stopped_at),
            precision=prec,
            status=self.status,
            message=self.message,
            counters=dict(self.counters),
            scene=self.scene.to_dict(),
            metadata={
                **versions(),
                "wall_seconds": time.perf_counter() - self._wall0,
                "compile_seconds": 0.0 if self._cached else self.compiled.compile_seconds,
                "compiled_from_cache": self._cached,
                "order": int(self._ta.order),
                "tolerance": str(self._ta.tol),
            },
        )


# ---------------------------------------------------------------------- internals
#: Steps at most of a run's probing calls (a run that needs more starts again after each, so
#: that its bits do not depend on the cut; :meth:`Propagation._estimate` extrapolates from
#: them): a short one, and a longer one only when the short one's estimate is not
#: ``_CLEAR`` times inside ``_ESTIMATE_MARGIN`` times the budget.
_PROBES = (16, 1_000)
_CLEAR = 100
_ESTIMATE_MARGIN = 10


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


def pass_rows(rows: np.ndarray, given: list[np.ndarray], t: Any, pars: np.ndarray) -> None:
    """Give the output rows up to ``t`` (a terminal event's time; increasing ``rows``, the
    first ``len(given)`` already given) a copy of ``pars``: they were computed before the
    event's handler changes the parameters (a row exactly at ``t`` too)."""
    while len(given) < len(rows) and rows[len(given)] <= t:
        given.append(pars.copy())


class _ProgressCallback:
    def __init__(self, progress: Progress, signals: _DeferredSignals) -> None:
        self.progress = progress
        self.signals = signals

    def __call__(self, ta: Any) -> bool:
        self.progress(float(ta.time))
        return not self.signals.received


class _HeldProgress:
    """The progress callback of a run's first call, which may be cut and taken again
    (:meth:`Propagation._estimate`): the times are held, and reported by :meth:`release` once
    the call's steps are kept, so that progress never goes back (and a caller that maps steps
    to times, as the validation reports do, sees each kept step once)."""

    def __init__(self, callback: _ProgressCallback) -> None:
        self.callback = callback
        self.times: list[float] = []

    def __call__(self, ta: Any) -> bool:
        self.times.append(float(ta.time))
        return not self.callback.signals.received

    def release(self) -> None:
        for t in self.times:
            self.callback.progress(t)
        self.times.clear()


class _DeferredSignals:
    """Within the context (in the main thread), SIGINT and SIGTERM handled by Python are only
    noted (and ``on_signal`` called); the propagation then ends after the current step.

    Python runs a signal's handler only between bytecodes of the main thread, so while heyoka
    steps there nothing would note it. Two ways out: a Python callback after each step
    (:meth:`callback`: it cost 6–18 % of the wall time of cheap double steps, the free body's
    ~1 µs, nothing measurable in quad), or heyoka stepping in another thread while the main
    thread waits in Python (:class:`_Watch`, double precision: no cost measurable,
    ``python validation/interrupt_cost.py``).
    """

    def __init__(self, on_signal: Callable[[], None] | None = None) -> None:
        self.received = ""
        self.on_signal = on_signal
        self._old: dict[int, Any] = {}

    @property
    def active(self) -> bool:
        """Whether signals are being noted (the context is entered in the main thread)."""
        return bool(self._old)

    def callback(self, ta: Any) -> bool:
        return not self.received

    def _note(self, signum: int, frame: Any) -> None:
        self.received = signal.Signals(signum).name
        if self.on_signal is not None:
            self.on_signal()

    def __enter__(self) -> _DeferredSignals:
        if threading.current_thread() is threading.main_thread():
            for sig in _SIGNALS:
                old = signal.getsignal(sig)
                if callable(old):  # SIG_DFL and SIG_IGN keep their meaning
                    self._old[sig] = signal.signal(sig, self._note)
        return self

    def __exit__(self, *exc: object) -> None:
        for sig, handler in self._old.items():
            signal.signal(sig, handler)
        self._old.clear()


class _Watch:
    """Propagations of the main thread run here, in one long-lived thread, while the main
    thread waits in Python, where its signal handlers run at once.

    A noted signal then sets the parameters that the right-hand sides use to NaN: the step
    under way becomes non-finite, and heyoka returns the outputs of the whole steps before it
    (``err_nf_state``; the rows it returns are the uninterrupted run's). The engine restores
    the parameters and reports the interruption. No callback runs after each step, so an
    uninterrupted run costs what a run in any other thread does (measured:
    ``python validation/interrupt_cost.py``). Double precision with runtime parameters only;
    other runs keep the per-step callback.
    """

    def __init__(self) -> None:
        self._jobs: queue.SimpleQueue = queue.SimpleQueue()
        self._thread: threading.Thread | None = None
        self._lock = threading.Lock()

    def run(self, job: Callable[[], None], stop: Callable[[], None]) -> None:
        """Run ``job`` in the watch's thread and wait for it; re-raise what it raised.

        ``stop`` is called if the wait itself is interrupted (an exception raised by another
        signal handler): the job is stopped and waited for before the exception goes on, so
        that nothing steps the integrator behind the caller's back.
        """
        with self._lock:
            if self._thread is None or not self._thread.is_alive():
                self._thread = threading.Thread(
                    target=self._serve, name="cayley_heyoka-propagation", daemon=True
                )
                self._thread.start()
        done, box = threading.Event(), {}
        self._jobs.put((job, done, box))
        try:
            while not done.wait(0.25):
                pass
        except BaseException:
            stop()
            done.wait()
            raise
        if "error" in box:
            raise box["error"]

    def _serve(self) -> None:
        while True:
            job, done, box = self._jobs.get()
            try:
                job()
            except BaseException as exc:  # handed to the waiting caller
                box["error"] = exc
            finally:
                done.set()


_WORKER = _Watch()


def check_fits(scene: Scene, model: Model) -> None:
    """Refuse a run whose recorded rows would exceed :data:`MAX_RECORD_BYTES`, or whose
    ``max_step`` needs more steps than ``integrator.max_steps`` to cover its span."""
    options, output = scene.integrator, scene.output
    prec = options.precision
    width = 1 + len(model.system) + len(model.pars) + len(_flat_outputs(model))
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
                f"{options.max_step} needs at least {float(Fraction(steps)):.3g} steps from "
                f"t = {start} to {stop}, more than the step budget integrator.max_steps = "
                f"{options.max_steps}",
            )


def _require_finite(values: np.ndarray, names: list[str], what: str) -> None:
    bad = np.flatnonzero(~np.isfinite(values))
    if len(bad):
        i = int(bad[0])
        raise SceneError(
            names[i], f"the {what} is {values[i]} at the start: it must be finite to integrate"
        )


def first_nonfinite(
    model: Model, values: dict[str, np.ndarray], times: np.ndarray
) -> tuple[int, str] | None:
    """The first row at which an output or monitor of ``values`` is not finite, and the
    message of the stop there; None if every value is finite."""
    first = None
    for name, value in values.items():
        if name in model.unbounded:
            # Infinite (or 0/0) at a half-turn, rightly; a state gone NaN shows in the others.
            continue
        rows = np.asarray(value).reshape(len(value), -1)
        bad = np.flatnonzero(~np.all(np.isfinite(rows), axis=1))
        if len(bad) and (first is None or bad[0] < first[0]):
            first = (int(bad[0]), name)
    if first is None:
        return None
    k, name = first
    kind = "monitor" if name in model.monitors else "output"
    return k, f"the {kind} {name} became non-finite at t = {times[k]}; results kept up to there"


def event_direction(spec: Any) -> Any:
    """heyoka's direction of an :class:`EventSpec` or :class:`TerminalSpec`."""
    return _direction(spec.direction)


def _direction(d: int) -> Any:
    return {
        0: hy.event_direction.any,
        1: hy.event_direction.positive,
        -1: hy.event_direction.negative,
    }[d]


def cache_key(model: Model, options: IntegratorOptions) -> str:
    """The key of ``model``'s compiled code: equal keys share one compiled integrator."""
    text = "\n".join(
        [
            model.code_key,
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


def event_logs(
    model: Model, ta: Any, prec: Precision, stopped_at: tuple | None
) -> dict[str, EventLog]:
    """The occurrences recorded by ``ta``'s event callbacks (and a terminal stop), by name."""
    recorded = ta.nt_events if model.events else []
    return logs_of(
        model, [(ev.callback.times, ev.callback.directions) for ev in recorded], prec, stopped_at
    )


def logs_of(
    model: Model, recorded: list[tuple[list, list]], prec: Precision, stopped_at: tuple | None
) -> dict[str, EventLog]:
    """The event logs of ``model`` from each event's recorded (times, directions)."""
    gathered: dict[str, list[tuple[Any, int, str]]] = {}
    for spec, (times, directions) in zip(model.events, recorded, strict=True):
        gathered.setdefault(spec.name, [])
        gathered[spec.name] += [
            (t, d, spec.label_for(d)) for t, d in zip(times, directions, strict=True)
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
