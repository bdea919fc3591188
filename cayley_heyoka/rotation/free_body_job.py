"""The torque-free body as the closed-form evaluation runs it in worker processes
(:mod:`cayley_heyoka.core.evaluation`): picklable, importing mpmath and python-flint only."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import mpmath
from flint import arb

from ..core.balls import ball, exact_mid, exact_rational, gap_bound, to_ball
from ..core.evaluation import Rounding, Row
from ..core.exact import upper


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

    VARIABLES = ("p", "q", "r", "lambda", "mu", "nu", "qw", "qx", "qy", "qz", "psi")
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
                values: dict[str, Any] = {}
                errors: dict[str, Any] = {}
                for name in self.variables:
                    v = s.values[name]
                    text_v, written = rnd.write(v)
                    values[name] = text_v
                    if not mpmath.isfinite(v):  # λ, μ, ν at a half-turn
                        errors[name] = math.inf
                        continue
                    # The proved bound, the rounding to the file's precision (exact at these
                    # digits: both are short binary numbers) and this subtraction's rounding.
                    gap = abs(written - v)
                    errors[name] = upper(s.bounds[name] + gap * (1 + 2 * mpmath.eps))
            exact = monitor_balls(self.monitors, s, self.inertia, self.dps)
            for name, value in exact.items():
                if isinstance(value, list):
                    texts = [rnd.write(exact_mid(c)) for c in value]
                    values[name] = [w for w, _ in texts]
                    errors[name] = [gap_bound(x, c) for (_, x), c in zip(texts, value, strict=True)]
                else:
                    values[name], x = rnd.write(exact_mid(value))
                    errors[name] = gap_bound(x, value)
            return values, errors

        return at


def monitor_balls(
    names: Sequence[str], s: Any, moments: Sequence[object], dps: int
) -> dict[str, arb | list[arb]]:
    """The monitors ``names`` of the exact motion, each as a ball (a list for a vector) that
    provably holds it: from the rates and quaternion of the enclosure ``s``, balls of their
    proved bounds, and the moments as the scene states them. A rotation's orthogonality
    defect is 0. In Arb at ``dps`` digits and 64 bits more (not python-flint's global
    precision)."""
    from flint import ctx

    from .attitude import quaternion_to_matrix

    out: dict[str, arb | list[arb]] = {}
    with ctx.workprec(math.ceil(dps * math.log2(10)) + 64):
        inertia = [ball(m, "body.inertia") for m in moments]
        w = [to_ball(s.values[n], s.bounds[n]) for n in "pqr"]
        L = [m * x for m, x in zip(inertia, w, strict=True)]
        for name in names:
            if name == "energy":
                out[name] = sum((m * x * x for m, x in zip(inertia, w, strict=True)), arb(0)) / 2
            elif name == "momentum_squared":
                out[name] = sum((x * x for x in L), arb(0))
            elif name == "momentum_space":
                q = [to_ball(s.values[n], s.bounds[n]) for n in ("qw", "qx", "qy", "qz")]
                # R(q) of the unit quaternion the balls hold: L in space axes.
                R = quaternion_to_matrix(q)
                out[name] = [sum((R[i][j] * L[j] for j in range(3)), arb(0)) for i in range(3)]
            elif name == "orthogonality":
                out[name] = arb(0)
            else:
                raise ValueError(f"the free body's closed form gives no monitor {name!r}")
    return out


#: A scene's attitude kinds and the :class:`.closed_form.FreeRigidBody` arguments taking them.
_KEYWORDS = {"quaternion": "attitude", "rodrigues": "rodrigues", "matrix": "matrix"}


def free_body(inertia, rates, attitude: tuple[str, Any] | None, dps: int) -> Any:
    """The closed form of a scene's body, its attitude ``(kind, value)`` passed as the scene
    states it."""
    from .closed_form import FreeRigidBody

    extra = {} if attitude is None else {_KEYWORDS[attitude[0]]: attitude[1]}
    return FreeRigidBody(inertia, rates, dps=dps, **extra)
