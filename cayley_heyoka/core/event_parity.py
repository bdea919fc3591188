"""Every crossing of a recorded event, also beside a terminal event: accounting by parity.

heyoka finds a step's events on its Taylor polynomial, each by its own root search, and a
terminal event ends the step there. A recorded event's zero that falls within round-off of a
terminal event's can be ordered either way by the two searches, and the terminal handler's
change of the state (a revolution moved out of ρ, a chart re-based) moves the expression's
value by round-off too. So beside a terminal event a crossing can be lost — put after the
terminal event, it goes with the rest of the step, and the next step starts past the zero —
or found twice — found before it, and the handler puts the state back before the zero, where
the next step finds it again. Where a family's gauge puts the two zeros together (an orbit's
node and its revolution count at Σ = 0 or π) this happens every few revolutions.

Each crossing flips the sign of the event's expression, so between two moments the crossings
recorded must have the parity of the sign change. :class:`EventParity` keeps each recorded
event's sign where the run last went on — its start, or the state a terminal handler left —
and the count of crossings recorded then. After each terminal handler whose run goes on it
takes the signs again, at the state the next step starts from (which decides what that step
can still find). An event whose new sign the crossings recorded since do not explain crossed
beside this terminal event, and the sign of its rate of change tells how:

1. moving away from its zero, towards the new sign: the state is past a crossing that was not
   reported. It is logged at the terminal event's time, in the direction of the sign change.
2. moving towards its zero, back to the sign the crossings recorded give: the state is before
   the crossing recorded last, which the next step will find again. That record is withdrawn
   until the next terminal event (or the run's end): if the first crossing recorded after it
   is in its direction, that is it found again; if not, it is put back.

An expression exactly zero where a step starts is a crossing at that start for heyoka (the
constant term of its polynomial is zero), so such a state counts as on the side it leaves.

The single run (:class:`~.engine.Propagation`) and each member of the batch lanes
(:mod:`.lanes`) hold one of these, and hand it the run's records of each event: per event, the
lists of its crossings' times and directions (every direction), which it corrects in place.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from .compiler import EventValues

#: Per recorded event, the lists of its crossings' times and directions (in the order found).
Crossings = Sequence[tuple[list[Any], list[int]]]


class EventParity:
    """The recorded events' signs where a run last went on, and what was recorded by then.

    Parameters
    ----------
    values
        The compiled signs of the model's recorded events (:func:`.compiler.event_values`).
    """

    def __init__(self, values: EventValues) -> None:
        self.values = values
        self._signs: list[int] = []
        self._counts: list[int] = []
        # Per event, a crossing (time, direction) withdrawn at the baseline (rule 2), or None.
        self._withdrawn: list[tuple[Any, int] | None] = []

    def start(self, state: Any, pars: Any, t: Any, crossings: Crossings) -> None:
        """Take the signs at ``state`` (parameters ``pars``, time ``t``) as the baseline, with
        ``crossings`` recorded so far."""
        self._signs, _ = self._sides(state, pars, t)
        self._counts = [len(times) for times, _ in crossings]
        self._withdrawn = [None] * len(self._counts)

    def settle(self, state: Any, pars: Any, t: Any, crossings: Crossings) -> None:
        """After a terminal handler at time ``t`` whose run goes on from ``state``: correct
        ``crossings`` (the module docstring's rules) and move the baseline here.

        A side of 0 (NaN, or a zero that does not move) tells nothing: no crossing is
        inferred from it.
        """
        self._decide(crossings)
        signs, rates = self._sides(state, pars, t)
        for i, (times, directions) in enumerate(crossings):
            before, now = self._signs[i], signs[i]
            recorded = len(times) - self._counts[i]
            if not (before and now) or (before == now) != bool(recorded % 2):
                continue  # explained by what was recorded (or nothing to tell)
            if rates[i] == -now and recorded and directions[-1] == -now:
                self._withdrawn[i] = (times.pop(), directions.pop())  # rule 2
            else:
                times.append(t)  # rule 1
                directions.append(now)
        self._signs = signs
        self._counts = [len(times) for times, _ in crossings]

    def _sides(self, state: Any, pars: Any, t: Any) -> tuple[list[int], list[int]]:
        """Each event's side of its zero at ``state`` (an exact zero: the side it is leaving,
        since the next step records its crossing) and the sign of its rate of change."""
        signs, rates = self.values.at(state, pars, t)
        return [s or -r for s, r in zip(signs, rates, strict=True)], rates

    def finish(self, crossings: Crossings) -> None:
        """At the run's end: decide on the crossings still withdrawn (rule 2)."""
        self._decide(crossings)

    def _decide(self, crossings: Crossings) -> None:
        """Each crossing withdrawn at the baseline: found again by the next step (the first
        crossing recorded since is in its direction), or put back where it was."""
        for i, held in enumerate(self._withdrawn):
            if held is None:
                continue
            self._withdrawn[i] = None
            times, directions = crossings[i]
            k = self._counts[i]
            if len(directions) > k and directions[k] == held[1]:
                continue
            times.insert(k, held[0])
            directions.insert(k, held[1])
            self._counts[i] += 1

    def checkpoint(self, text: Callable[[Any], str]) -> dict[str, Any]:
        """The baseline as JSON-ready values (times through ``text``), for a snapshot of the
        run; :meth:`resume` continues from it."""
        return {
            "signs": list(self._signs),
            "counts": list(self._counts),
            "withdrawn": [None if w is None else [text(w[0]), w[1]] for w in self._withdrawn],
        }

    def resume(self, value: dict[str, Any], number: Callable[[str], Any]) -> None:
        """Continue from a :meth:`checkpoint` (times through ``number``)."""
        signs, counts, withdrawn = value["signs"], value["counts"], value["withdrawn"]
        if not len(signs) == len(counts) == len(withdrawn):
            raise ValueError("an event-parity checkpoint needs a count per sign")
        self._signs = [int(s) for s in signs]
        self._counts = [int(c) for c in counts]
        self._withdrawn = [None if w is None else (number(w[0]), int(w[1])) for w in withdrawn]
