"""The torque-free body's closed form as the family offers it (``Family.closed_form``):
evaluated as a reference (:class:`~.free_body_job.FreeBodyJob` in worker processes), with its
invariable-plane crossings, and compared with a run."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..core.certificate import Certificate, rounding_of, worst, written
from ..core.closed_form import ClosedForm
from ..core.exact import exact_array, upper
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
        """The run's error against the closed form at every output time: each variable it
        gives, each monitor (against the monitor of the exact motion, in balls) and each
        invariable-plane crossing."""
        import mpmath

        from ..core.balls import exact_rational, gap_bound
        from .free_body_job import FreeBodyJob, free_body, monitor_balls

        body = self.scene.model
        dps = digits + 10
        # The attitude as the scene states it: the proved bounds start from it exactly.
        exact = free_body(body.inertia, body.rates, body.attitude, dps)
        t = result.t
        names = [n for n in FreeBodyJob.VARIABLES if n in result.variables]
        monitors = [n for n in FreeBodyJob.MONITORS if n in getattr(result, "monitors", {})]
        cols: dict[str, list[Any]] = {n: [] for n in names + monitors}
        times = exact_array(t)
        columns = {n: exact_array(result.variables[n]) for n in names}
        with mpmath.workdps(dps + 10):
            t0 = times[0]
            for k in range(len(t)):
                s = exact.enclose(exact_rational(times[k]) - exact_rational(t0))
                got = {n: columns[n][k] for n in names}
                want = {n: s.values[n] for n in FreeBodyJob.VARIABLES}
                if "qw" in got:
                    # q and −q are one attitude: compare with the sign the run took.
                    ours = [got[n] for n in ("qw", "qx", "qy", "qz")]
                    theirs = [want[n] for n in ("qw", "qx", "qy", "qz")]
                    if sum(a * b for a, b in zip(ours, theirs, strict=True)) < 0:
                        want.update((n, -want[n]) for n in ("qw", "qx", "qy", "qz"))
                for n in names:
                    # The proved bound (λ, μ, ν: of the closed form's own quotient, so the
                    # sign taken for q does not matter), and the subtraction's rounding.
                    rounding = 4 * mpmath.eps * (abs(want[n]) + abs(got[n]))
                    cols[n].append(upper(abs(got[n] - want[n]) + s.bounds[n] + rounding))
                for n, value in monitor_balls(monitors, s, body.inertia, dps).items():
                    run = np.ravel(result.monitors[n][k])
                    if isinstance(value, list):
                        cols[n].append([gap_bound(x, c) for x, c in zip(run, value, strict=True)])
                    else:
                        cols[n].append(gap_bound(run[0], value))
            event_errors = {}
            log = result.events.get("invariable_plane")
            if log is not None:
                event_errors["invariable_plane"] = self._crossings(exact, log, times[-1], t0)
        errors = {n: np.array(v, dtype=float) for n, v in cols.items()}
        cert = Certificate("closed form", self.name, errors, event_errors, self.proved)
        return worst(cert, written(result), np.asarray(t, dtype=float))

    @staticmethod
    def _crossings(exact: Any, log: Any, t1: Any, t0: Any) -> np.ndarray:
        """Each recorded crossing's error, in the log's order."""
        span = t1 - t0
        errors = np.zeros(len(log))
        for axis in ("x1", "y1", "z1"):
            ours = [x - t0 for x in exact_array(log.where(axis))]
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
