"""The torque-free body as the closed-form evaluation runs it in worker processes
(:mod:`cayley_heyoka.core.evaluation`): picklable, importing mpmath and python-flint only."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import mpmath

from ..core.balls import exact_rational
from ..core.evaluation import Rounding, Row, upper


@dataclass(frozen=True)
class FreeBodyJob:
    """The torque-free body of a scene, evaluated at output times.

    Attributes
    ----------
    inertia, rates
        The scene's moments and initial rates as it states them (decimal text, or floats at
        their binary value).
    attitude
        The scene's initial attitude ``(kind, value)`` as it states it, or None (rates only):
        the proved bounds start from it exactly (:func:`.enclosures.attitude_quaternion`).
    dps
        Digits the closed form certifies.
    t0
        The start time (the initial state's), as text of the file's precision.
    variables, monitors
        The names the integrated run writes, all among :attr:`VARIABLES` / :attr:`MONITORS`.
    rounding
        The file's precision.
    """

    inertia: tuple[object, object, object]
    rates: tuple[object, object, object]
    attitude: tuple[str, Any] | None
    dps: int
    t0: str
    variables: tuple[str, ...]
    monitors: tuple[str, ...]
    rounding: Rounding

    VARIABLES = ("p", "q", "r", "lambda", "mu", "nu", "qw", "qx", "qy", "qz")
    MONITORS = ("energy", "momentum_squared", "momentum_space", "orthogonality")

    def body(self) -> Any:
        return free_body(self.inertia, self.rates, self.attitude, self.dps)

    def evaluator(self) -> Callable[[str], Row]:
        body = self.body()
        t0 = self.rounding.read(self.t0)
        rnd = self.rounding

        def at(text: str) -> Row:
            with mpmath.workdps(self.dps + 30):
                # The time since the start, exactly (both are numbers of the file's precision).
                s = body.enclose(exact_rational(rnd.read(text)) - exact_rational(t0))
                exact = {n: s.values[n] for n in ("p", "q", "r", "qw", "qx", "qy", "qz")}
                exact.update({n: s.values[n] for n in ("lambda", "mu", "nu")})
                values, errors = {}, {}
                for name in self.variables:
                    v = exact[name]
                    text_v, written = rnd.write(v)
                    values[name] = text_v
                    if not mpmath.isfinite(v):  # λ, μ, ν at a half-turn
                        errors[name] = math.inf
                        continue
                    # The proved bound, the rounding to the file's precision (exact at these
                    # digits: both are short binary numbers) and this subtraction's rounding.
                    gap = abs(written - v)
                    errors[name] = upper(s.bounds[name] + gap * (1 + 2 * mpmath.eps))
                inertia = [mpmath.mpf(m) for m in self.inertia]
                for name in self.monitors:
                    values[name] = self._monitor(name, s, inertia)
            return values, errors

        return at

    def _monitor(self, name: str, s: Any, inertia: Sequence[mpmath.mpf]) -> Any:
        """The monitor of the exact motion at this time, rounded once."""
        rates = [s.values[n] for n in "pqr"]
        L = [m * w for m, w in zip(inertia, rates, strict=True)]
        if name == "energy":
            value: Any = sum(m * w * w for m, w in zip(inertia, rates, strict=True)) / 2
        elif name == "momentum_squared":
            value = sum(x * x for x in L)
        elif name == "momentum_space":
            from .quadratures import quaternion_rotate

            q = [s.values[n] for n in ("qw", "qx", "qy", "qz")]
            return [self.rounding.write(g)[0] for g in quaternion_rotate(q, L)]
        else:  # orthogonality: the closed form's attitude is a rotation by construction
            value = mpmath.mpf(0)
        return self.rounding.write(value)[0]


#: A scene's attitude kinds and the :class:`.closed_form.FreeRigidBody` arguments taking them.
_KEYWORDS = {"quaternion": "attitude", "rodrigues": "rodrigues", "matrix": "matrix"}


def free_body(inertia, rates, attitude: tuple[str, Any] | None, dps: int) -> Any:
    """The closed form of a scene's body, its attitude ``(kind, value)`` passed as the scene
    states it."""
    from .closed_form import FreeRigidBody

    extra = {} if attitude is None else {_KEYWORDS[attitude[0]]: attitude[1]}
    return FreeRigidBody(inertia, rates, dps=dps, **extra)
