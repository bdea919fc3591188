"""The step budget's estimate from a run's first steps: a span that plainly cannot fit in
``integrator.max_steps`` is refused after a few milliseconds instead of running for minutes.

The engine's first calls are probes (:data:`PROBES` steps at most): each is cut short to
take its steps and then taken again from the start, uncut, so that the run's bits do not
depend on the cut. After each, :meth:`SpanProbe.after` extrapolates the rate of those steps
over the span: it must stay within :data:`ESTIMATE_MARGIN` times the budget; the margin leaves
room for motions whose steps lengthen (an estimate, so only the absurd is refused). The first
probe is short, so that a run pays for it a few steps only: when its estimate is not
:data:`CLEAR` times inside the limit, the longer probe decides. A scene object whose span
was found to fit is not probed again when it is run again (its first steps are the same).
"""

from __future__ import annotations

from fractions import Fraction
from typing import Any

from .errors import SceneError
from .precision import approx, exact_fraction
from .scene import Scene

#: Steps at most of a run's probing calls: a short one, and a longer one only when the short
#: one's estimate is not ``CLEAR`` times inside ``ESTIMATE_MARGIN`` times the budget.
PROBES = (16, 1_000)
CLEAR = 100
ESTIMATE_MARGIN = 10


class SpanProbe:
    """The probing calls a run has still to make, and the estimate after each.

    Parameters
    ----------
    scene
        The run's scene (its span).
    start
        The first time of the run's checked grid, where its integrator starts.

    Examples
    --------
    >>> import cayley_heyoka as ch
    >>> scene = ch.load_scene("examples/projectile.toml")
    >>> SpanProbe(scene, scene.time_grid[0]).limit
    16
    """

    def __init__(self, scene: Scene, start: Any) -> None:
        self.scene = scene
        self.start = start
        self._left = list(PROBES)
        #: Whether an estimate found the span within the budget's margin (a run of the same
        #: scene, taking the same first steps, need not probe again).
        self.fits = False

    @property
    def limit(self) -> int | None:
        """The step limit of the next call, if it is a probe (else None)."""
        return self._left[0] if self._left else None

    def done(self) -> None:
        """No more probes: the run's first steps were taken (a run resumed from a snapshot)."""
        self._left = []

    def after(self, steps: int, reached: Any, budget: int, cut: bool) -> None:
        """After a probing call that took ``steps`` and reached heyoka's double-length time
        ``reached`` (hi, lo: at t = -1e25 a double's hi part does not move for millions of
        steps of length 1, while the lo part counts them), ``cut`` if it ended at its limit:
        refuse a run whose first steps show it needs far more steps than ``budget``, or leave
        the next, longer probe to decide.

        Raises
        ------
        SceneError
            ``output.times``: the span needs more than :data:`ESTIMATE_MARGIN` times the budget.
        """
        probes = self._left
        probes.pop(0)
        if not cut:
            probes.clear()  # the call ended of itself: nothing is taken again
        needed = self._needed(steps, reached) if steps >= PROBES[0] else None
        if needed is None:
            return
        limit = ESTIMATE_MARGIN * budget
        if cut and probes and needed * CLEAR > limit:
            return  # not clearly within the budget: the next, longer probe decides
        probes.clear()
        self.fits = needed <= limit
        if needed > limit:
            _, last = self.scene.output.span()
            raise SceneError(
                "output.times",
                f"the span to t = {last} needs about {approx(needed)} steps (the first "
                f"{steps} reached t = {reached[0]}), more than {ESTIMATE_MARGIN} times the "
                f"step budget integrator.max_steps = {budget}; shorten the span, or raise "
                "integrator.max_steps if the steps will lengthen",
            )

    def _needed(self, steps: int, reached: Any) -> Fraction | None:
        """The steps the whole span needs at the rate of ``steps`` to ``reached`` (None if
        that cannot be told: no time covered, or a non-finite time)."""
        start = exact_fraction(str(self.start))
        stop = exact_fraction(self.scene.output.span()[1])
        try:
            covered = sum(exact_fraction(str(part)) for part in reached) - start
        except (ValueError, ArithmeticError):  # the state (and heyoka's time) became NaN
            return None
        if covered <= 0:
            return None
        return steps * (stop - start) / covered
