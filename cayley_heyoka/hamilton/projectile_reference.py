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
    name = "Hamilton's projectile, (113.)-(114.), (120.)"

    def _job(self, variant: Scene, model: Any, prec: Precision, t0: str) -> Any:
        from .projectile_job import ProjectileJob

        names = self._outputs(model, ProjectileJob)
        if names is None:
            return None
        variables, monitors = names
        h = self.scene.model
        c = h.constants
        return ProjectileJob(
            g=str(c["g"]),
            mu=str(c["mu"]),
            nu=str(c["nu"]),
            eta=tuple(str(x) for x in h.eta),
            varpi=tuple(str(x) for x in h.varpi),
            dps=prec.dps,
            t0=t0,
            variables=variables,
            monitors=monitors,
            rounding=rounding_of(prec),
        )

    def certificate(self, result: Any, digits: int) -> Certificate:
        import mpmath

        from .projectile import projectile_solution

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
                tk = times[k] - times[0]
                s = projectile_solution(c["g"], c["mu"], c["nu"], h.eta, h.varpi, tk, dps=dps)
                want = {f"eta{i + 1}": s.eta[i] for i in range(3)}
                want.update({f"varpi{i + 1}": s.varpi[i] for i in range(3)})
                want["S"] = s.S
                for n in names:
                    got = columns[n][k]
                    bound = s.errors[n] * max(1, abs(want[n]))
                    cols[n].append(upper(abs(got - want[n]) + bound))
        errors = {n: np.array(v) for n, v in cols.items()}
        cert = Certificate("closed form", self.name, errors)
        return worst(cert, result.variables, np.asarray(t, dtype=float))
