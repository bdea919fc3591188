"""Hamilton's projectile as the family offers it (``Family.closed_form``): evaluated as a
reference (:class:`~.projectile_job.ProjectileJob` in worker processes), and compared with a
run."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..core.certificate import Certificate, rounding_of, worst, written
from ..core.closed_form import ClosedForm
from ..core.exact import exact_array, upper
from ..core.precision import Precision
from ..core.scene import Scene


def closed_form(scene: Scene) -> ClosedForm | None:
    """The closed form of a canonical projectile scene without user events, else None."""
    model = scene.model
    if model.model == "projectile" and model.form.closed_form and not scene.events:
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
        """The run's error against the closed form at every output time: each variable it
        gives and the energy (against the exact motion's, in balls)."""
        import mpmath

        from ..core.balls import exact_rational, gap_bound
        from .projectile_bounds import projectile_bounds
        from .projectile_job import ProjectileJob, energy

        h = self.scene.model
        c = h.constants
        dps = digits + 10
        t = result.t
        names = [n for n in ProjectileJob.VARIABLES if n in result.variables]
        monitors = [n for n in ProjectileJob.MONITORS if n in getattr(result, "monitors", {})]
        cols: dict[str, list[float]] = {n: [] for n in names + monitors}
        times = exact_array(t)
        columns = {n: exact_array(result.variables[n]) for n in names}
        with mpmath.workdps(dps + 10):
            for k in range(len(t)):
                tk = exact_rational(times[k]) - exact_rational(times[0])
                s = projectile_bounds(c["g"], c["mu"], c["nu"], h.eta, h.varpi, tk, dps=dps)
                for n in names:
                    got, want = columns[n][k], s.values[n]
                    # The proved bound and the subtraction's rounding.
                    rounding = 4 * mpmath.eps * (abs(want) + abs(got))
                    cols[n].append(upper(abs(got - want) + s.bounds[n] + rounding))
                if monitors:
                    H = energy(c["g"], c["mu"], c["nu"], s, dps)
                    cols["energy"].append(gap_bound(result.monitors["energy"][k], H))
        errors = {n: np.array(v) for n, v in cols.items()}
        cert = Certificate("closed form", self.name, errors, proved=self.proved)
        return worst(cert, written(result), np.asarray(t, dtype=float))
