"""Callbacks that heyoka calls after each step of a run, and the watch for a stalled one.

A run stops after the step in which a signal was noted (:class:`SignalCallback`, or the
progress bar's :class:`ProgressCallback`), and when heyoka takes steps of size zero, which it
would go on taking to its step limit without counting them (:class:`ZeroSteps`,
:func:`.outcomes.zero_step`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from .signals import DeferredSignals

#: Called with the time reached, in the run's precision (a float, a heyoka real128 or real).
Progress = Callable[[Any], None]


class ZeroSteps:
    """Whether heyoka is taking steps of size zero (:func:`.outcomes.zero_step`), which it
    goes on taking to its step limit, seen by a per-step callback (:meth:`step`: this many
    in a row) or, between steps, by the thread that waits for the run (:meth:`watch`: the
    last step of size zero and the time unchanged at :attr:`LOOKS` looks in a row)."""

    #: Steps of size zero in a row that a per-step callback takes for a stall.
    IN_A_ROW = 100
    #: Looks in a row (0.25 s apart) that find a step of size zero and the same time.
    LOOKS = 4

    def __init__(self) -> None:
        self.seen = False
        #: The time at which the run was found stalled.
        self.at: Any = None
        self._count = 0
        self._looks = 0
        self._time: Any = None  # at the last look (watch)
        self._after: Any = None  # after the last step (step)

    def step(self, ta: Any, t: Any = None) -> bool:
        """After a step: whether the run is stalled (then :attr:`seen`). ``t``: the time the
        caller read, if it did (a time that moved needs no look at the step, ~0.3 µs)."""
        if t is not None:
            moved = t != self._after
            self._after = t
            if moved:
                self._count = 0
                return self.seen
        self._count = self._count + 1 if ta.last_h == 0 else 0
        if self._count >= self.IN_A_ROW and not self.seen:
            self.seen, self.at = True, ta.time
        return self.seen

    def watch(self, ta: Any, start: Any) -> bool:
        """At a look from another thread: whether the run is stalled (then :attr:`seen`).
        ``start``: where the integrator began (the run's start, a hand-over), at which a fresh
        integrator's last step is zero before its first step ends."""
        t = ta.time
        still = ta.last_h == 0 and t == self._time and t != start
        self._looks = self._looks + 1 if still else 0
        if self._looks >= self.LOOKS and not self.seen:
            self.seen, self.at = True, t
        self._time = t
        return self.seen


class ProgressCallback:
    def __init__(self, progress: Progress, signals: DeferredSignals, zero: ZeroSteps) -> None:
        self.progress = progress
        self.signals = signals
        self.zero = zero

    def __call__(self, ta: Any) -> bool:
        t = ta.time
        self.progress(t)
        return not (self.signals.received or self.zero.step(ta, t))


class SignalCallback:
    """Stops heyoka after the step in which a signal was noted, or in a stall."""

    def __init__(self, signals: DeferredSignals, zero: ZeroSteps) -> None:
        self.signals = signals
        self.zero = zero

    def __call__(self, ta: Any) -> bool:
        return not (self.signals.received or self.zero.step(ta))


class HeldProgress:
    """The progress callback of a run's first call, which may be cut and taken again
    (:class:`.span_probe.SpanProbe`): the times are held, and reported by :meth:`release` once
    the call's steps are kept, so that progress never goes back (and a caller that maps steps
    to times, as the validation reports do, sees each kept step once)."""

    def __init__(self, callback: ProgressCallback) -> None:
        self.callback = callback
        self.times: list[Any] = []

    def __call__(self, ta: Any) -> bool:
        t = ta.time
        self.times.append(t)
        return not (self.callback.signals.received or self.callback.zero.step(ta, t))

    def release(self) -> None:
        for t in self.times:
            self.callback.progress(t)
        self.times.clear()
