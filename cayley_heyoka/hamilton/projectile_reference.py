"""Hamilton's projectile as the family offers it (``Family.closed_form``): evaluated as a
reference (:class:`~.projectile_job.ProjectileJob` in worker processes), and compared with a
run."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..core.certificate import Certificate, exact_values, precision_of, rounding_of, worst
from ..core.closed_form import ClosedForm
from ..core.evaluation import upper
from ..core.precision import Precision
from ..core.scene import Scene


def closed_form(scene: Scene) -> ClosedForm | None:
    """The closed form of a canonical projectile scene without user events, else None."""
    model = scene.model
    if model.model == "projectile" and model.formulation == "canonical" and not scene.events:
        return ProjectileClosedForm(scene)
    return None


class ProjectileClosedForm(ClosedForm):
    name = "Hamilton's projectile, (113.)-(114.), (120.), in Arb balls"
    proved = True

    def _job(self, variant: Scene, model: Any, prec: Precision, t0: str) -> Any:
        from .projectile_job import ProjectileJob

        names = self._outputs(model, ProjectileJob)
        if names is None:
            return None
        variables, monitors = names
        h = self.scene.model
        c = h.constants
        # The scene's numbers as it states them: a float is its binary value, as the run reads
        # it (its decimal text would be another number).
        return ProjectileJob(
            g=c["g"],
            mu=c["mu"],
            nu=c["nu"],
            eta=tuple(h.eta),
            varpi=tuple(h.varpi),
            dps=prec.dps,
            t0=t0,
            variables=variables,
            monitors=monitors,
            rounding=rounding_of(prec),
        )

    def certificate(self, result: Any, digits: int) -> Certificate:
        import mpmath

        from ..core.balls import exact_rational
        from .projectile_bounds import projectile_bounds

        h = self.scene.model
        c = h.constants
        dps = digits + 10
        t = result.t
        names = [n for n in result.variables if n[:-1] in ("eta", "varpi") or n == "S"]
        cols: dict[str, list[float]] = {n: [] for n in names}
        prec = precision_of(result)
        times = exact_values(t, prec)
        columns = {n: exact_values(result.variables[n], prec) for n in names}
        with mpmath.workdps(dps + 10):
            for k in range(len(t)):
                tk = exact_rational(times[k]) - exact_rational(times[0])
                s = projectile_bounds(c["g"], c["mu"], c["nu"], h.eta, h.varpi, tk, dps=dps)
                for n in names:
                    got, want = columns[n][k], s.values[n]
                    # The proved bound and the subtraction's rounding.
                    rounding = 4 * mpmath.eps * (abs(want) + abs(got))
                    cols[n].append(upper(abs(got - want) + s.bounds[n] + rounding))
        errors = {n: np.array(v) for n, v in cols.items()}
        cert = Certificate("closed form", self.name, errors, proved=self.proved)
        return worst(cert, result.variables, np.asarray(t, dtype=float))
