"""The IAS15 case: μ = 1, a = 1, e = 0.5, i = 0.3, node 0.4, ω = 0.5, M = 0; J2 = 10⁻³ about z
with R = 0.1 (pericentre 0.5), its output grid, its scenes and its energy. Every method starts
from the same double state (the scenes carry its exact decimal expansion)."""

from __future__ import annotations

import dataclasses
import math
from decimal import Decimal
from typing import Any

import mpmath
import numpy as np

import cayley_heyoka as ch
from cayley_heyoka.mechanics.kepler import Elements, elements_to_cartesian

LD = np.longdouble
EPS = 2.0**-52
MU, J2, RADIUS = "1", "0.001", "0.1"
ELEMENTS = Elements(1.0, 0.5, 0.3, 0.4, 0.5, 0.0)
N_FULL, N_QUICK = 10_000, 100
ENSEMBLE = {False: (1000, 8), True: (30, 2)}  # quick → (orbits, members)
REF_TOL, CHECK_TOL = "1e-24", "1e-20"
PERIOD = 2 * math.pi  # of the osculating Kepler orbit at t = 0 (a = 1, μ = 1)

State = tuple[list[float], list[float]]


def initial_state(mean_anomaly: float = 0.0) -> State:
    """A double initial state (the elements converted in double: any double state will do, as
    long as every method gets the same one)."""
    x, v = elements_to_cartesian(dataclasses.replace(ELEMENTS, mean_anomaly=mean_anomaly), 1.0)
    return [float(c) for c in x], [float(c) for c in v]


START = initial_state()


def exact_text(x: float) -> str:
    """The exact decimal expansion of a double (scenes keep decimal text as written)."""
    return str(Decimal(x))


def grid(n_orbits: int) -> np.ndarray:
    """Output times: t = 0 and whole orbits log-spaced from 1 to 10⁴ (a prefix for fewer)."""
    k = np.unique(np.rint(np.logspace(0, 4, 121)))
    return np.array([0.0] + [PERIOD * kk for kk in k if kk <= n_orbits])


def scene(formulation: str, times: np.ndarray, start: State = START, **integrator: Any):
    orbit = {
        "mu": MU,
        "position": [exact_text(c) for c in start[0]],
        "velocity": [exact_text(c) for c in start[1]],
        "formulation": formulation,
    }
    return ch.Scene.from_dict(
        {
            "orbit": orbit,
            "perturbations": {"zonal": {"J2": J2, "radius": RADIUS}},
            "integrator": integrator,
            "output": {"times": [float(t) for t in times], "monitors": ["energy"]},
        }
    )


def k2() -> Any:
    """μ J2 R² in long double (its rounding is ~1e-20 of the energy)."""
    return LD(MU) * LD(J2) * LD(RADIUS) ** 2


def energy_xv(x: Any, v: Any) -> np.ndarray:
    """v²/2 − μ/r − Ω in long double; x, v of shape (3, n)."""
    x, v = np.asarray(x, dtype=LD), np.asarray(v, dtype=LD)
    r2 = (x * x).sum(axis=0)
    r = np.sqrt(r2)
    return (v * v).sum(axis=0) / 2 - LD(MU) / r + k2() * (3 * x[2] ** 2 / r2 - 1) / (2 * r * r2)


def energy_polar(r: Any, rdot: Any, h: Any, z: Any) -> np.ndarray:
    """The same energy from Cayley's r, ṙ, h (the state itself) and z (only in the J2 term)."""
    r, rdot, h, z = (np.asarray(a, dtype=LD) for a in (r, rdot, h, z))
    r2 = r * r
    return (rdot**2 + h**2 / r2) / 2 - LD(MU) / r + k2() * (3 * z**2 / r2 - 1) / (2 * r * r2)


def exact_energy(start: State = START) -> Any:
    """The energy of the double initial state, computed in mpmath."""
    with mpmath.workdps(40):
        x = [mpmath.mpf(c) for c in start[0]]
        v = [mpmath.mpf(c) for c in start[1]]
        r2 = sum(c * c for c in x)
        r = mpmath.sqrt(r2)
        k2 = mpmath.mpf(MU) * mpmath.mpf(J2) * mpmath.mpf(RADIUS) ** 2
        e = (
            sum(c * c for c in v) / 2
            - mpmath.mpf(MU) / r
            + k2 * (3 * x[2] ** 2 / r2 - 1) / (2 * r * r2)
        )
        return LD(mpmath.nstr(e, 30))
