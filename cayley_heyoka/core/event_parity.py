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
A terminal handler only notes the state it leaves (:meth:`EventParity.note`, a copy); the
signs of the states noted are taken together, in one call of the compiled function, when the
records are read (:meth:`EventParity.flush`: before a snapshot, a hand-over, the result) or
:data:`PENDING` states have been noted — a Rodrigues run re-bases its chart every few steps,
and a call per re-basing cost more than the steps between them.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from .compiler import EventValues

#: Per recorded event, the lists of its crossings' times and directions (in the order found).
Crossings = Sequence[tuple[list[Any], list[int]]]


#: States noted before their signs are taken (bounds the memory a long run holds for them).
PENDING = 4096


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
        # The states noted since the last flush: (state, pars, t, each event's record count).
        self._pending: list[tuple[Any, Any, Any, list[int]]] = []

    def start(self, state: Any, pars: Any, t: Any, crossings: Crossings) -> None:
        """Take the signs at ``state`` (parameters ``pars``, time ``t``) as the baseline, with
        ``crossings`` recorded so far."""
        self._pending = []
        signs, rates = self.values.at(_rows(state), _rows(pars), _times([t]))
        self._signs = _sides(signs[0], rates[0])
        self._counts = [len(times) for times, _ in crossings]
        self._withdrawn = [None] * len(self._counts)

    def note(self, state: Any, pars: Any, t: Any, crossings: Crossings) -> None:
        """After a terminal handler at time ``t`` whose run goes on from ``state``: keep a
        copy, to be accounted for (the module docstring's rules) at the next :meth:`flush`."""
        counts = [len(times) for times, _ in crossings]
        self._pending.append((state.copy(), pars.copy(), t, counts))
        if len(self._pending) >= PENDING:
            self.flush(crossings)

    def flush(self, crossings: Crossings) -> None:
        """Account for every state noted, in order, correcting ``crossings`` in place: each
        event's records since the baseline are taken up to each noted state's count, and a
        sign the records do not explain adds or withdraws a crossing there."""
        pending, self._pending = self._pending, []
        if not pending:
            return
        states = np.array([p[0] for p in pending])
        pars = np.array([p[1] for p in pending])
        signs, rates = self.values.at(states, pars, _times([p[2] for p in pending]))
        counts = np.array([p[3] for p in pending], dtype=np.int64)
        for i, (times, directions) in enumerate(crossings):
            if self._explained(i, signs[:, i], rates[:, i], counts[:, i]):
                self._signs[i] = _sides(signs[-1:, i], rates[-1:, i])[0]
                self._counts[i] = int(counts[-1, i])
                continue
            got_t, got_d = times[self._counts[i] :], directions[self._counts[i] :]
            del times[self._counts[i] :], directions[self._counts[i] :]
            taken = self._counts[i]  # records of the raw lists already taken
            before = self._signs[i]
            for k, (_, _, t, seen) in enumerate(pending):
                upto = seen[i] - taken
                new_t, new_d = got_t[:upto], got_d[:upto]
                got_t, got_d, taken = got_t[upto:], got_d[upto:], seen[i]
                self._decide(i, times, directions, new_d)
                times += new_t
                directions += new_d
                now = int(signs[k, i]) or -int(rates[k, i])
                recorded = len(times) - self._counts[i]
                if before and now and (before == now) == bool(recorded % 2):
                    if rates[k, i] == -now and recorded and directions[-1] == -now:
                        self._withdrawn[i] = (times.pop(), directions.pop())  # rule 2
                    else:
                        times.append(t)  # rule 1
                        directions.append(now)
                before = now
                self._counts[i] = len(times)
            times += got_t  # recorded since the last state noted
            directions += got_d
            self._signs[i] = before

    def _explained(self, i: int, signs: Any, rates: Any, counts: Any) -> bool:
        """Whether every change of event ``i``'s sign at the states noted is explained by the
        crossings recorded, with none withdrawn: then there is nothing to correct (the usual
        case, checked at once for all the states)."""
        if self._withdrawn[i] is not None:
            return False
        now = np.where(signs != 0, signs, -rates)
        before = np.concatenate(([self._signs[i]], now[:-1]))
        recorded = np.diff(counts, prepend=self._counts[i])
        odd = (recorded % 2).astype(bool)
        wrong = (before != 0) & (now != 0) & ((before == now) == odd)
        return not wrong.any()

    def finish(self, crossings: Crossings) -> None:
        """At the run's end: account for what is noted, and decide on the crossings still
        withdrawn (rule 2)."""
        self.flush(crossings)
        for i, (times, directions) in enumerate(crossings):
            k = self._counts[i]
            after_t, after_d = times[k:], directions[k:]
            del times[k:], directions[k:]
            self._decide(i, times, directions, after_d)
            times += after_t
            directions += after_d

    def _decide(self, i: int, times: list, directions: list, after: list[int]) -> None:
        """The crossing of event ``i`` withdrawn at the baseline: found again by the next step
        (``after``, the directions recorded since, begins with its own), or put back at the
        end of ``times``, ``directions`` (the records up to the baseline)."""
        held = self._withdrawn[i]
        if held is None:
            return
        self._withdrawn[i] = None
        if after and after[0] == held[1]:
            return
        times.append(held[0])
        directions.append(held[1])
        self._counts[i] += 1

    def checkpoint(self, text: Callable[[Any], str]) -> dict[str, Any]:
        """The baseline as JSON-ready values (times through ``text``), for a snapshot of the
        run (after a :meth:`flush`: nothing noted is kept); :meth:`resume` continues from it."""
        if self._pending:
            raise RuntimeError("EventParity.checkpoint: flush the states noted first")
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


def _rows(values: Any) -> np.ndarray:
    """One state or parameter vector as a batch of one."""
    return np.asarray(values)[None, :]


def _times(times: list[Any]) -> np.ndarray:
    """Times in the run's precision as one array (heyoka's real128 and real keep their type)."""
    return np.array(times)


def _sides(signs: np.ndarray, rates: np.ndarray) -> list[int]:
    """Each event's side of its zero (an exact zero: the side it is leaving, since the next
    step records its crossing)."""
    return [int(s) or -int(r) for s, r in zip(signs, rates, strict=True)]
