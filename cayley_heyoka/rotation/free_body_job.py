"""The torque-free body as the closed-form evaluation runs it in worker processes
(:mod:`cayley_heyoka.core.evaluation`): picklable, and importing mpmath only."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import mpmath

from ..core.evaluation import Rounding, Row, upper


@dataclass(frozen=True)
class FreeBodyJob:
    """The torque-free body of a scene, evaluated at output times.

    Attributes
    ----------
    inertia, rates
        The scene's moments and initial rates, as exact decimal text.
    attitude
        The initial unit quaternion as text (well beyond ``dps`` digits), or None (rates only).
    dps
        Digits the closed form certifies.
    t0
        The start time (the initial state's), as text of the file's precision.
    variables, monitors
        The names the integrated run writes, all among :attr:`VARIABLES` / :attr:`MONITORS`.
    rounding
        The file's precision.
    """

    inertia: tuple[str, str, str]
    rates: tuple[str, str, str]
    attitude: tuple[str, str, str, str] | None
    dps: int
    t0: str
    variables: tuple[str, ...]
    monitors: tuple[str, ...]
    rounding: Rounding

    VARIABLES = ("p", "q", "r", "lambda", "mu", "nu", "qw", "qx", "qy", "qz")
    MONITORS = ("energy", "momentum_squared", "momentum_space", "orthogonality")

    def body(self) -> Any:
        from .closed_form import FreeRigidBody

        return FreeRigidBody(self.inertia, self.rates, attitude=self.attitude, dps=self.dps)

    def evaluator(self) -> Callable[[str], Row]:
        body = self.body()
        t0 = self.rounding.read(self.t0)
        rnd = self.rounding

        def at(text: str) -> Row:
            with mpmath.workdps(self.dps + 30):
                s = body.at(rnd.read(text) - t0)
                bound = s.error  # the worst of the rates and quaternions, scaled
                w, x, y, z = s.quaternion
                exact = {"p": s.p, "q": s.q, "r": s.r, "qw": w, "qx": x, "qy": y, "qz": z}
                # λ = x/w: an error b in x and w becomes b(1 + |λ|)/|w|.
                for name, c in (("lambda", x), ("mu", y), ("nu", z)):
                    exact[name] = c / w if w != 0 else mpmath.inf
                values, errors = {}, {}
                for name in self.variables:
                    v = exact[name]
                    if name in ("lambda", "mu", "nu"):
                        err = bound * (1 + abs(v)) / abs(w) if w != 0 else mpmath.inf
                    else:
                        err = bound * max(1, abs(v))
                    err += 2 * mpmath.eps * abs(v)  # this division's rounding
                    text_v, written = rnd.write(v)
                    values[name] = text_v
                    errors[name] = upper(abs(written - v) + err) if mpmath.isfinite(v) else math.inf
                inertia = [mpmath.mpf(m) for m in self.inertia]
                for name in self.monitors:
                    values[name] = self._monitor(name, s, inertia)
            return values, errors

        return at

    def _monitor(self, name: str, s: Any, inertia: Sequence[mpmath.mpf]) -> Any:
        """The monitor of the exact motion at this time, rounded once."""
        L = [m * w for m, w in zip(inertia, (s.p, s.q, s.r), strict=True)]
        if name == "energy":
            value: Any = sum(m * w * w for m, w in zip(inertia, (s.p, s.q, s.r), strict=True)) / 2
        elif name == "momentum_squared":
            value = sum(x * x for x in L)
        elif name == "momentum_space":
            from .quadratures import quaternion_rotate

            return [self.rounding.write(g)[0] for g in quaternion_rotate(s.quaternion, L)]
        else:  # orthogonality: the closed form's attitude is a rotation by construction
            value = mpmath.mpf(0)
        return self.rounding.write(value)[0]
