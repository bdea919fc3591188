"""Part 1: the reference values R1–R4, one formulation and precision per job."""

from __future__ import annotations

import math
import time
from typing import Any

import mpmath
import numpy as np
from orbit_cases import QUANTITIES, REFERENCE_BY_NAME

import cayley_heyoka as ch

from .departure import departure_run
from .runs import angle_difference, columns, integrate
from .tolerances import DPS


def reference_job(name: str, formulation: str, precision: str, case: Any = None) -> dict[str, Any]:
    """One formulation of R1–R4 at the cases' t; errors of every listed quantity.

    ``case`` replaces the named case (the tests pass a deliberately wrong scene)."""
    from cayley_heyoka.mechanics import kepler as el
    from cayley_heyoka.orbit.model import plane_angles_at

    case = case or REFERENCE_BY_NAME[name]
    t_end = float(case.t)
    wall0 = time.perf_counter()
    if formulation == "departure":
        # A fine grid so that Θ, Σ, ρ can be followed continuously (ρ̇ ≤ ~2.5 here).
        times = [float(x) for x in np.linspace(0.0, t_end, int(4 * t_end) + 1)]
        dep = departure_run(case.scene, times, precision)
        values = {k: v[-1] for k, v in dep["columns"].items()}
        steps, seconds, compile_s = dep["steps"], dep["seconds"], math.nan
    else:
        data = case.scene_for(formulation, precision, [0.0, t_end])
        result, _, seconds = integrate(data)
        steps, compile_s = int(result.counters["steps"]), result.metadata["compile_seconds"]
        cols = columns(result, QUANTITIES)
        values = {k: v[-1] for k, v in cols.items()}
        if formulation == "cartesian":
            with mpmath.workdps(DPS):
                frame = plane_angles_at(ch.Scene.from_dict(data).model.plane, mpmath.mpf(t_end))
                x = [values[k] for k in ("x", "y", "z")]
                v = [values[k] for k in ("vx", "vy", "vz")]
                s = el.cartesian_to_cayley(x, v, sigma=mpmath.mpf(0), frame=frame)
                values.update(r=s.r, rdot=s.rdot, h=s.h, Theta=s.Theta, Phi=s.Phi)
    errors = {}
    with mpmath.workdps(DPS):
        for k in QUANTITIES:
            if k not in values:
                continue
            ref = mpmath.mpf(case.values[k])
            d = angle_difference(values[k], ref) if k == "Theta" else values[k] - ref
            errors[k] = {
                "relative": float(abs(d) / abs(ref)),
                "scaled": float(abs(d) / max(abs(ref), 1)),
            }
    return {
        "kind": "reference",
        "case": name,
        "formulation": formulation,
        "precision": precision,
        "steps": steps,
        "seconds": seconds,
        "compile_seconds": compile_s,
        "wall_seconds": time.perf_counter() - wall0,
        "errors": errors,
    }
