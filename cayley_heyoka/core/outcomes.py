"""How a propagation ends, said once: the messages of every path that integrates.

A run (:mod:`.engine`), a member in the batch lanes (:mod:`.lanes`) and a member of heyoka's
ensemble (:mod:`cayley_heyoka.workflows.members`) end the same ways, and say so in the same
words (the model is scipy's ``solve_ivp`` table of messages). Each message ends with what was
kept, so that a partial result is never mistaken for a whole one.

A step of size zero is one of them: an expression whose Taylor coefficients are not finite
where the state is (an event ``sqrt(z)`` where z reaches 0) makes heyoka take steps of size
zero, which it reports as ``step_limit`` whatever its step count (:func:`zero_step`).
"""

from __future__ import annotations

from typing import Any, NamedTuple

import heyoka as hy

from .model import Model


class Ended(NamedTuple):
    """How one heyoka call ended, by name: its ``taylor_outcome``, its smallest and largest
    step, its step count (the first four items of ``propagate_until``'s, ``propagate_grid``'s
    and each lane's ``propagate_res`` tuple)."""

    outcome: Any
    min_h: Any
    max_h: Any
    steps: int

    @classmethod
    def of(cls, res: Any) -> Ended:
        """The first four items of heyoka's result ``res``."""
        return cls(res[0], res[1], res[2], int(res[3]))

    @property
    def zero_step(self) -> bool:
        """The call ended on a step of size zero (:func:`zero_step`)."""
        return zero_step(self.outcome, self.min_h)


class GridRun(NamedTuple):
    """One ``propagate_grid`` call of a scalar integrator, by name: how it ended, and the
    states at the grid's points (one row a point; a point not reached stays NaN)."""

    ended: Ended
    states: Any

    @classmethod
    def of(cls, res: Any) -> GridRun:
        return cls(Ended.of(res), res[-1])

    def whole(self, what: str, t: Any) -> Any:
        """The states, if the call reached its last point (its integrator at ``t``); else a
        ``ValueError`` saying that ``what`` ended early, and how — for a check's own
        integration, whose rows past the end would be NaN."""
        if self.ended.outcome != hy.taylor_outcome.time_limit:
            raise ValueError(f"{what} ended early: {other(self.ended.outcome, t)}")
        return self.states


def batch_states(res: Any) -> Any:
    """The states of a batch integrator's ``propagate_grid`` call, ``(points, dim, lanes)``
    (each lane's outcome is in the integrator's ``propagate_res``)."""
    return res[-1]


class EnsembleRun(NamedTuple):
    """One member of ``heyoka.ensemble_propagate_grid``, by name: the member's integrator,
    how its call ended, and the states on the grid."""

    integrator: Any
    ended: Ended
    states: Any

    @classmethod
    def of(cls, res: Any) -> EnsembleRun:
        return cls(res[0], Ended.of(res[1:5]), res[-1])


#: What every message of a run that stopped early ends with.
KEPT = "results kept up to there"


def out_of_steps(budget: int, t: Any) -> str:
    """The step budget ``integrator.max_steps = budget`` spent at time ``t``."""
    return (
        f"the step budget integrator.max_steps = {budget} was spent at t = {t}; {KEPT} "
        "(raise integrator.max_steps to go on)"
    )


def nonfinite(t: Any) -> str:
    """The state became non-finite after ``t`` (the last time known: heyoka's own is NaN
    once the state is)."""
    return f"the state became non-finite after t = {t}; {KEPT}"


def other(outcome: Any, t: Any) -> str:
    """Any other end of a heyoka call at time ``t``."""
    return f"stopped at t = {t} with outcome {outcome}"


def zero_step(outcome: Any, min_h: Any) -> bool:
    """Whether a heyoka call ended on a step of size zero (``min_h``: the call's smallest
    step): every later call would end at once, at the same time — the run cannot go on."""
    return outcome == hy.taylor_outcome.step_limit and min_h == 0


def zero_step_message(model: Model, t: Any) -> str:
    """What a run whose step size fell to zero at ``t`` (:func:`zero_step`) says."""
    where = "the equations of motion"
    if model.events:
        names = ", ".join(repr(e.name) for e in model.events)
        where += f" or of an event's expression (output.events: {names})"
    return (
        f"the step size fell to zero at t = {t}: a Taylor coefficient of {where} is not "
        f"finite there (a square root, a fractional power or a logarithm at its zero); {KEPT}"
    )
