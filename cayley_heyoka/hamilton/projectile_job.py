"""Hamilton's projectile as the closed-form evaluation runs it in worker processes
(:mod:`cayley_heyoka.core.evaluation`): picklable, importing mpmath and python-flint only."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import mpmath

from ..core.evaluation import Rounding, Row
from ..core.exact import upper


@dataclass(frozen=True)
class ProjectileJob:
    """Hamilton's projectile of a scene (canonical form), evaluated at output times."""

    # The scene's numbers as it states them (decimal text, or floats at their binary value).
    g: object
    mu: object
    nu: object
    eta: tuple[object, object, object]
    varpi: tuple[object, object, object]
    dps: int
    t0: str
    variables: tuple[str, ...]
    monitors: tuple[str, ...]
    rounding: Rounding

    VARIABLES = ("eta1", "eta2", "eta3", "varpi1", "varpi2", "varpi3", "S")
    MONITORS = ("energy",)

    def evaluator(self) -> Callable[[str], Row]:
        from ..core.balls import exact_mid, exact_rational, gap_bound
        from .projectile_bounds import projectile_bounds

        rnd = self.rounding
        t0 = rnd.read(self.t0)

        def at(text: str) -> Row:
            with mpmath.workdps(self.dps + 30):
                # The time since the start, exactly (both are numbers of the file's precision).
                t = exact_rational(rnd.read(text)) - exact_rational(t0)
                s = projectile_bounds(self.g, self.mu, self.nu, self.eta, self.varpi, t, self.dps)
                values, errors = {}, {}
                for name in self.variables:
                    v = s.values[name]
                    values[name], written = rnd.write(v)
                    # The proved bound, the rounding to the file's precision (exact: short
                    # binary numbers) and this subtraction's rounding.
                    gap = abs(written - v)
                    errors[name] = upper(s.bounds[name] + gap * (1 + 2 * mpmath.eps))
            if "energy" in self.monitors:
                H = energy(self.g, self.mu, self.nu, s, self.dps)
                values["energy"], x = rnd.write(exact_mid(H))
                errors["energy"] = gap_bound(x, H)
            return values, errors

        return at


def energy(g: object, mu: object, nu: object, s: Any, dps: int) -> Any:
    """H of the exact motion as a ball that provably holds it, from the enclosure ``s`` of
    (η, ϖ) and the constants ``g, mu, nu`` as the scene states them."""
    from flint import arb, ctx

    from ..core.balls import ball, to_ball

    with ctx.workprec(math.ceil(dps * math.log2(10)) + 64):
        g, mu, nu = (ball(c) for c in (g, mu, nu))
        eta = [to_ball(s.values[f"eta{i}"], s.bounds[f"eta{i}"]) for i in (1, 2, 3)]
        varpi = [to_ball(s.values[f"varpi{i}"], s.bounds[f"varpi{i}"]) for i in (1, 2, 3)]
        return (
            sum((p * p for p in varpi), arb(0)) / 2
            + g * eta[2]
            + (mu * mu * (eta[0] ** 2 + eta[1] ** 2) + nu * nu * eta[2] ** 2) / 2
        )
