"""Which parameter vector each output row of a call was computed with.

Within one heyoka call, a terminal event's handler may change the parameters (a chart's new
base, an orbit's revolution count). The rows of the call's dense output before the event were
computed with the parameters in force until then, those after it with the new ones. The
scalar engine and the batch lanes both keep, per call, a :class:`RowPars`: at each event,
before its handler acts, :meth:`RowPars.passing` notes how many rows come at or before it
and one copy of the parameters for them; :meth:`RowPars.take` gives the rows their vectors.
"""

from __future__ import annotations

from bisect import bisect_left, bisect_right
from typing import Any

import numpy as np

__all__ = ["RowPars", "Rows", "rows_up_to"]


def rows_up_to(rows: np.ndarray, hi: Any, lo: Any) -> int:
    """How many of the increasing output times ``rows`` come at or before the double-length
    time ``hi + lo`` (heyoka's time, its high and low parts).

    The comparison is heyoka's own: where the time's last bit is coarse (t ≈ 1e15 in double)
    an event a little before an output time can have that time as its high part, and the row
    then comes after the event.

    Examples
    --------
    >>> import numpy as np
    >>> rows_up_to(np.array([0.0, 1.0, 2.0]), 1.0, 0.0), rows_up_to(np.array([1.0]), 1.0, -1e-17)
    (2, 0)
    """
    return bisect_left(rows, hi) if lo < 0 else bisect_right(rows, hi)


class RowPars:
    """The parameter vectors of one call's output rows ``rows`` (increasing times).

    Examples
    --------
    >>> import numpy as np
    >>> pars = np.array([1.0])
    >>> schedule = RowPars(np.array([0.0, 1.0, 2.0]))
    >>> schedule.passing((1.5, 0.0), pars)  # an event at t = 1.5, before its handler
    >>> pars[0] = 2.0
    >>> schedule.take(3, pars)[:, 0].tolist()
    [1.0, 1.0, 2.0]
    """

    __slots__ = ("_marks", "_next", "rows")

    def __init__(self, rows: np.ndarray) -> None:
        self.rows = rows
        # (how many rows, the parameters they were computed with), counts increasing.
        self._marks: list[tuple[int, np.ndarray]] = []
        self._next: Any = rows[0] if len(rows) else None

    def passing(self, dtime: tuple[Any, Any], pars: np.ndarray) -> None:
        """A terminal event at the double-length time ``dtime``, before its handler changes
        ``pars``: the rows up to it (a row exactly at the event too) keep a copy of them."""
        if self._next is None or self._next > dtime[0]:
            return  # the usual case, an event between two rows already noted: one comparison
        rows = self.rows
        count = rows_up_to(rows, *dtime)
        if count == (self._marks[-1][0] if self._marks else 0):
            return
        self._marks.append((count, pars.copy()))
        self._next = rows[count] if count < len(rows) else None

    def take(self, n: int, pars: np.ndarray) -> np.ndarray:
        """The first ``n`` rows' parameter vectors, ``(n, len(pars))``: each the copy noted
        for it, the rest ``pars`` (in force now). The schedule is then spent: a later take
        gives every row ``pars``."""
        marks, self._marks, self._next = self._marks, [], None
        if pars.dtype == np.float64:
            out = np.empty((n, len(pars)))
            done = 0
            for count, noted in marks:
                if count > done:
                    out[done : min(count, n)] = noted
                    done = min(count, n)
            out[done:] = pars
            return out
        # heyoka's real128 and real: an array of the vectors (no block assignment into an
        # uninitialised array of those dtypes).
        vectors: list[np.ndarray] = []
        for count, noted in marks:
            vectors += [noted] * (min(count, n) - len(vectors))
        vectors += [pars] * (n - len(vectors))
        return np.array(vectors).reshape(n, len(pars))


_NO_ROWS = np.empty(0)


class Rows:
    """The output rows a run has kept — states, and (``with_pars``) the parameter vector each
    was computed with — and its current call's :class:`RowPars`: one record for a run
    (:class:`~.engine.Propagation`) and for each member of the batch lanes (:mod:`.lanes`).

    Examples
    --------
    >>> import numpy as np
    >>> rows, pars = Rows(), np.array([1.0])
    >>> rows.begin(np.array([0.0, 1.0]))
    >>> rows.keep(np.zeros((2, 3)), pars)
    >>> rows.done, rows.joined(dims=(3, 1))[1].shape
    (2, (2, 1))
    """

    __slots__ = ("call", "done", "pars", "states", "with_pars")

    def __init__(self, with_pars: bool = True) -> None:
        self.states: list[np.ndarray] = []
        self.pars: list[np.ndarray] = []
        self.done = 0
        self.call: RowPars | None = None
        self.with_pars = with_pars

    def begin(self, rows: np.ndarray) -> None:
        """A call that may record the output times ``rows``."""
        self.call = RowPars(rows)

    def passing(self, dtime: tuple[Any, Any], pars: np.ndarray) -> None:
        """A terminal event within the call (:meth:`RowPars.passing`)."""
        if self.call is not None:
            self.call.passing(dtime, pars)

    def keep(self, states: np.ndarray, pars: np.ndarray) -> None:
        """Keep the call's next rows ``states``, each with the parameters it was computed with
        (``pars``: those in force now, for the rows no terminal event preceded)."""
        if self.with_pars:
            self.pars.append((self.call or RowPars(_NO_ROWS)).take(len(states), pars))
        self.states.append(states)
        self.done += len(states)

    def joined(
        self, start: int = 0, dims: tuple[int, int] = (0, 0)
    ) -> tuple[np.ndarray, np.ndarray]:
        """The rows kept from piece ``start`` on, as arrays ``(rows, dims[0])`` and their
        parameters ``(rows, dims[1])`` (kept ``with_pars``)."""
        if not self.with_pars:
            raise RuntimeError("these rows were kept without their parameters")
        return _joined(self.states[start:], dims[0]), _joined(self.pars[start:], dims[1])

    def joined_states(self, width: int) -> np.ndarray:
        """Every state kept, ``(rows, width)``."""
        return _joined(self.states, width)

    def forget(self, start: int) -> None:
        """Drop the pieces from ``start`` on (a caller that stores them itself); ``done``
        still counts them."""
        del self.states[start:]
        del self.pars[start:]


def _joined(pieces: list[np.ndarray], width: int) -> np.ndarray:
    if not pieces:
        return np.empty((0, width))
    return pieces[0] if len(pieces) == 1 else np.concatenate(pieces)
