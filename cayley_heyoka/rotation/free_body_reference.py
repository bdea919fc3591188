"""The torque-free body's closed form as the family offers it (``Family.closed_form``):
evaluated as a reference (:class:`~.free_body_job.FreeBodyJob` in worker processes), with its
invariable-plane crossings, and compared with a run."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..core.certificate import (
    Certificate,
    exact_values,
    precision_of,
    rounding_of,
    worst,
)
from ..core.closed_form import ClosedForm
from ..core.evaluation import upper
from ..core.precision import Precision
from ..core.scene import Scene


def closed_form(scene: Scene) -> ClosedForm | None:
    """The closed form of a torque-free scene without user events, else None."""
    if scene.model.torque_free and not scene.events:
        return FreeBodyClosedForm(scene)
    return None


class FreeBodyClosedForm(ClosedForm):
    name = "FreeRigidBody, Jacobi elliptic functions in Arb balls"
    proved = True

    def _job(self, variant: Scene, model: Any, prec: Precision, t0: str) -> Any:
        from .free_body_job import FreeBodyJob

        names = self._outputs(model, FreeBodyJob, events=("invariable_plane",))
        if names is None:
            return None
        variables, monitors = names
        body = self.scene.model
        dps = prec.dps
        return FreeBodyJob(
            # As the scene states them: a float is its binary value, as the run reads it (its
            # decimal text would be another number, 1e-17 away).
            inertia=tuple(body.inertia),
            rates=tuple(body.rates),
            attitude=body.attitude,
            dps=dps,
            t0=t0,
            variables=variables,
            monitors=monitors,
            rounding=rounding_of(prec),
        )

    def _events(self, job: Any, model: Any, prec: Precision, grid: np.ndarray) -> tuple[dict, dict]:
        """The invariable-plane crossings of the output span, as the run records them."""
        import mpmath

        from ..core.result import EventLog

        axes = [e.label for e in model.events]
        if not axes:
            return {}, {}
        body = job.body()
        rnd = job.rounding
        t0 = rnd.read(job.t0)
        crossings = []
        with mpmath.workdps(job.dps + 30):
            span = rnd.read(prec.to_text(grid[-1:])[0]) - t0
            for axis in axes:
                # A zero at the start time is where the run starts, not a crossing it detects.
                found = body.crossing_times(axis, 0, span, proved=True)
                crossings += [c for c in found if c.time > 0]
            crossings.sort(key=lambda c: c.time)
            times, errors = [], []
            for c in crossings:
                exact = t0 + c.time
                text, written = rnd.write(exact)
                times.append(text)
                # The crossing's error is scaled (relative above 1): made absolute here.
                bound = c.error * max(1, abs(c.time)) + 2 * mpmath.eps * abs(exact)
                errors.append(upper(abs(written - exact) + bound))
        log = EventLog(
            time=prec.from_text(np.array(times, dtype=object)) if times else prec.array([]),
            direction=np.array([c.direction for c in crossings], dtype=int),
            label=np.array([c.axis for c in crossings], dtype=str),
        )
        return {"invariable_plane": log}, {"invariable_plane": np.array(errors)}

    def certificate(self, result: Any, digits: int) -> Certificate:
        import mpmath

        from ..core.balls import exact_rational
        from .free_body_job import free_body

        body = self.scene.model
        dps = digits + 10
        # The attitude as the scene states it: the proved bounds start from it exactly.
        exact = free_body(body.inertia, body.rates, body.attitude, dps)
        t = result.t
        names = [n for n in ("p", "q", "r", "qw", "qx", "qy", "qz") if n in result.variables]
        has_rodrigues = "lambda" in result.variables
        cols: dict[str, list[float]] = {
            n: [] for n in names + (["lambda", "mu", "nu"] if has_rodrigues else [])
        }
        prec = precision_of(result)
        times = exact_values(t, prec)
        columns = {n: exact_values(result.variables[n], prec) for n in cols}
        with mpmath.workdps(dps + 10):
            t0 = times[0]
            for k in range(len(t)):
                s = exact.enclose(exact_rational(times[k]) - exact_rational(t0))
                got = {n: columns[n][k] for n in cols}
                exact_q = [s.values[n] for n in ("qw", "qx", "qy", "qz")]
                if "qw" in got:
                    # q and −q are one attitude: compare with the sign the run took.
                    ours = [got["qw"], got["qx"], got["qy"], got["qz"]]
                    if sum(a * b for a, b in zip(ours, exact_q, strict=True)) < 0:
                        exact_q = [-c for c in exact_q]
                want = {n: s.values[n] for n in ("p", "q", "r", "lambda", "mu", "nu")}
                want.update(zip(("qw", "qx", "qy", "qz"), exact_q, strict=True))
                for n in cols:
                    # The proved bound (λ, μ, ν: of the closed form's own quotient, so the
                    # sign taken for q does not matter), and the subtraction's rounding.
                    rounding = 4 * mpmath.eps * (abs(want[n]) + abs(got[n]))
                    cols[n].append(upper(abs(got[n] - want[n]) + s.bounds[n] + rounding))
            event_errors = {}
            log = result.events.get("invariable_plane")
            if log is not None:
                event_errors["invariable_plane"] = self._crossings(exact, log, times[-1], t0, prec)
        errors = {n: np.array(v) for n, v in cols.items()}
        cert = Certificate("closed form", self.name, errors, event_errors, self.proved)
        return worst(cert, result.variables, np.asarray(t, dtype=float))

    @staticmethod
    def _crossings(exact: Any, log: Any, t1: Any, t0: Any, prec: Precision) -> np.ndarray:
        """Each recorded crossing's error, in the log's order."""
        span = t1 - t0
        errors = np.zeros(len(log))
        for axis in ("x1", "y1", "z1"):
            ours = [x - t0 for x in exact_values(log.where(axis), prec)]
            theirs = exact.crossing_times(axis, 0, span, proved=True)
            if len(ours) != len(theirs):
                raise RuntimeError(
                    f"invariable-plane crossings of {axis}: {len(ours)} recorded, "
                    f"{len(theirs)} in the closed form — no certificate"
                )
            # The crossing's error is scaled (relative above 1): made absolute here.
            errors[np.flatnonzero(log.label == axis)] = [
                upper(abs(a - c.time) + c.error * max(1, abs(c.time)))
                for a, c in zip(ours, theirs, strict=True)
            ]
        return errors
