"""Parts 3 and 4: the inclination and eccentricity sweeps against real128 references."""

from __future__ import annotations

import math
import time
from typing import Any

import mpmath
import numpy as np
from orbit_cases import (
    EPSILON,
    FORMULATIONS,
    INCLINATION_E,
    SWEEP_ORBITS,
    eccentricity_base,
    inclination_base,
    scene,
)

from .departure import departure_run
from .runs import angle_difference, columns, integrate, steps_at
from .tolerances import C_LAW, DPS, K_x, law


def sweep_times(orbits: float, count: int) -> list[float]:
    period = 2 * math.pi  # a = 1, μ = 1
    return [float(x) for x in np.linspace(0.0, orbits * period, count)]


def inclination_job(inclination: str, mode: str) -> dict[str, Any]:
    """One inclination: real128 departure-vector reference and the three double formulations."""
    wall0 = time.perf_counter()
    base = inclination_base(inclination)
    orbits = SWEEP_ORBITS[mode]
    # 16 samples per orbit: fine enough to follow Θ, Σ continuously in the reference.
    times = sweep_times(orbits, int(16 * orbits) + 1)
    ref = departure_run(base, times, "quad")
    rc = ref["columns"]
    sin_phi_min = float(min(abs(mpmath.sin(p)) for p in rc["Phi"]))
    out = {
        "kind": "inclination",
        "inclination": inclination,
        "orbits": orbits,
        "reference_steps": ref["steps"],
        "reference_seconds": ref["seconds"],
        "sin_phi_min": sin_phi_min,
        "runs": {},
    }
    t = np.asarray(times)
    for f in FORMULATIONS:
        data = scene(base, f, "double", times, limit="0")
        result, steps, seconds = integrate(data)
        names = ("x", "y", "z", "Theta", "Sigma", "Phi")
        cols = columns(result, names)
        err: dict[str, np.ndarray] = {}
        with mpmath.workdps(DPS):
            pos = [
                mpmath.sqrt(sum((cols[k][i] - rc[k][i]) ** 2 for k in ("x", "y", "z")))
                for i in range(len(times))
            ]
            err["position"] = np.array([float(p) for p in pos])
            if "Theta" in cols:
                for k in ("Theta", "Sigma", "Phi"):
                    err[k] = np.array(
                        [
                            float(abs(angle_difference(a, b)))
                            for a, b in zip(cols[k], rc[k], strict=True)
                        ]
                    )
                err["Theta-Sigma"] = np.array(
                    [
                        float(abs(angle_difference(a - b, c - d)))
                        for a, b, c, d in zip(
                            cols["Theta"], cols["Sigma"], rc["Theta"], rc["Sigma"], strict=True
                        )
                    ]
                )
        n = np.maximum(steps_at(steps, t), 1)
        e = float(INCLINATION_E)
        base_tol = law(EPSILON["double"], t, n, 2 * math.pi, K_x(e))
        tol = {
            "position": base_tol,
            "Phi": base_tol,
            "Theta-Sigma": base_tol,
            "Theta": base_tol + C_LAW * EPSILON["double"] * np.sqrt(n) / sin_phi_min,
            "Sigma": base_tol + C_LAW * EPSILON["double"] * np.sqrt(n) / sin_phi_min,
        }
        out["runs"][f] = {
            "steps": int(result.counters["steps"]),
            "seconds": seconds,
            "max": {k: float(np.max(v)) for k, v in err.items()},
            "ratio": {k: float(np.max(v / tol[k])) for k, v in err.items()},
            "tol_end": {k: float(tol[k][-1]) for k in err},
        }
    out["wall_seconds"] = time.perf_counter() - wall0
    return out


def eccentricity_job(e: str, mode: str) -> dict[str, Any]:
    """One eccentricity: real128 Cartesian reference and the three double formulations."""
    wall0 = time.perf_counter()
    base = eccentricity_base(e)
    orbits = SWEEP_ORBITS[mode]
    times = sweep_times(orbits, int(4 * orbits) + 1)
    ref, ref_steps, ref_seconds = integrate(scene(base, "cartesian", "quad", times))
    rc = columns(ref, ("x", "y", "z"))
    out = {
        "kind": "eccentricity",
        "e": e,
        "orbits": orbits,
        "reference_steps": int(ref.counters["steps"]),
        "reference_seconds": ref_seconds,
        "runs": {},
    }
    t = np.asarray(times)
    for f in FORMULATIONS:
        result, steps, seconds = integrate(scene(base, f, "double", times))
        cols = columns(result, ("x", "y", "z"))
        with mpmath.workdps(DPS):
            err = np.array(
                [
                    float(mpmath.sqrt(sum((cols[k][i] - rc[k][i]) ** 2 for k in ("x", "y", "z"))))
                    for i in range(len(times))
                ]
            )
        n = np.maximum(steps_at(steps, t), 1)
        tol = law(EPSILON["double"], t, n, 2 * math.pi, K_x(float(e)))
        tol = tol + law(
            EPSILON["quad"], t, np.maximum(steps_at(ref_steps, t), 1), 2 * math.pi, K_x(float(e))
        )
        out["runs"][f] = {
            "steps": int(result.counters["steps"]),
            "seconds": seconds,
            "max": float(np.max(err)),
            "final": float(err[-1]),
            "ratio": float(np.max(err / tol)),
            "tol_end": float(tol[-1]),
            "t": t,
            "err": err,
        }
    out["wall_seconds"] = time.perf_counter() - wall0
    return out
