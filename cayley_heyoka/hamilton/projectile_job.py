"""Hamilton's projectile as the closed-form evaluation runs it in worker processes
(:mod:`cayley_heyoka.core.evaluation`): picklable, and importing mpmath only."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import mpmath

from ..core.evaluation import Rounding, Row, upper


@dataclass(frozen=True)
class ProjectileJob:
    """Hamilton's projectile of a scene (canonical form), evaluated at output times."""

    g: str
    mu: str
    nu: str
    eta: tuple[str, str, str]
    varpi: tuple[str, str, str]
    dps: int
    t0: str
    variables: tuple[str, ...]
    monitors: tuple[str, ...]
    rounding: Rounding

    VARIABLES = ("eta1", "eta2", "eta3", "varpi1", "varpi2", "varpi3", "S")
    MONITORS = ("energy",)

    def evaluator(self) -> Callable[[str], Row]:
        from .projectile import projectile_solution

        rnd = self.rounding
        t0 = rnd.read(self.t0)

        def at(text: str) -> Row:
            with mpmath.workdps(self.dps + 30):
                s = projectile_solution(
                    self.g, self.mu, self.nu, self.eta, self.varpi, rnd.read(text) - t0, self.dps
                )
                exact = {f"eta{i + 1}": s.eta[i] for i in range(3)}
                exact.update({f"varpi{i + 1}": s.varpi[i] for i in range(3)})
                exact["S"] = s.S
                values, errors = {}, {}
                for name in self.variables:
                    v = exact[name]
                    values[name], written = rnd.write(v)
                    bound = s.errors[name] * max(1, abs(v)) + 2 * mpmath.eps * abs(v)
                    errors[name] = upper(abs(written - v) + bound)
                if "energy" in self.monitors:
                    g, mu, nu = (mpmath.mpf(c) for c in (self.g, self.mu, self.nu))
                    eta, varpi = s.eta, s.varpi
                    H = (
                        sum(p * p for p in varpi) / 2
                        + g * eta[2]
                        + (mu * mu * (eta[0] ** 2 + eta[1] ** 2) + nu * nu * eta[2] ** 2) / 2
                    )
                    values["energy"] = rnd.write(H)[0]
            return values, errors

        return at
