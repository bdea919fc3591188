"""The cases of the set-up section, fixed before any run: the families of scenes of growing size
(orbit zonal harmonics, a rigid body with a growing force function, the predominant-mass system
with more bodies, Hamilton's elements), the scenes of the cache table, and the ensemble systems
with their members."""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

import cayley_heyoka as ch

# A cold non-compact compile longer than this is where a user starts to wait; heyoka's disk
# cache pays it once per structure and machine, the step cost is paid on every run.
PATIENCE = 10.0


# ---------------------------------------------------------------------- scene families
def orbit_zonal(degree: int, compact: Any = "auto") -> ch.Scene:
    """A Cartesian orbit with the zonal harmonics J2 … J_degree."""
    J = {f"J{n}": f"{(-1) ** n * 1e-3 / n**2:.3e}" for n in range(2, degree + 1)}
    return ch.Scene.from_dict(
        {
            "orbit": {
                "mu": 1.0,
                "position": [0.9, 0.2, 0.1],
                "velocity": [-0.25, 0.85, 0.45],
                "formulation": "cartesian",
            },
            "perturbations": {"zonal": {**J, "radius": 0.5}},
            "integrator": {"compact_mode": compact},
            "output": {"times": [0.0, 1.0]},
        }
    )


_COSINES = [f"R{i}{j}" for i in (1, 2, 3) for j in (1, 2, 3)]
_TRIPLES = list(itertools.combinations_with_replacement(_COSINES, 3))


def rigid_potential(terms: int, compact: Any = "auto") -> ch.Scene:
    """A rigid body (quaternion attitude) whose force function has ``terms`` cubic terms in
    the direction cosines: a user potential of growing length."""
    V = " + ".join(
        f"{0.1 / (j + 1):.4f} * {a} * {b} * {c}" for j, (a, b, c) in enumerate(_TRIPLES[:terms])
    )
    return ch.Scene.from_dict(
        {
            "body": {"inertia": [1.0, 1.5, 2.5]},
            "initial": {"rates": [0.3, 1.0, 0.5]},
            "attitude": {"formulation": "quaternion"},
            "forces": {"potential": {"V": V}},
            "integrator": {"compact_mode": compact},
            "output": {"times": [0.0, 1.0]},
        }
    )


def predominant_mass(
    bodies: int, compact: Any = "auto", formulation: str = "canonical"
) -> ch.Scene:
    """``bodies`` planets about a predominant mass (Hamilton 1835), in either formulation."""
    table = [
        {
            "mass": 1e-3 / (k + 1),
            "elements": {
                "a": 1.0 + 0.6 * k,
                "e": 0.05,
                "inclination": 0.05 + 0.01 * k,
                "node": 0.3 * k,
                "argument_of_pericentre": 1.1 + k,
                "mean_anomaly": 0.4 + 0.7 * k,
            },
        }
        for k in range(bodies)
    ]
    return ch.Scene.from_dict(
        {
            "hamiltonian": {
                "model": "predominant_mass",
                "G": 1.0,
                "central_mass": 1.0,
                "formulation": formulation,
                "bodies": table,
            },
            "integrator": {"compact_mode": compact},
            "output": {"times": [0.0, 1.0]},
        }
    )


def elements(bodies: int, compact: Any = "auto") -> ch.Scene:
    return predominant_mass(bodies, compact, "elements")


@dataclass
class Family:
    label: str
    unit: str  # what the size parameter counts
    build: Callable[..., ch.Scene]
    sizes: tuple[int, ...]
    quick: tuple[int, ...]


FAMILIES_BY_SIZE = [
    Family("orbit, zonal J2…Jn (Cartesian)", "n", orbit_zonal, (2, 3, 4, 6, 8, 12, 16), (2, 3)),
    Family("rigid body, V of k cubic terms", "k", rigid_potential, (1, 3, 10, 20, 40), (1,)),
    Family("predominant mass, N bodies (canonical)", "N", predominant_mass, (2, 3, 4, 6, 8), ()),
    Family("Hamilton's elements, N bodies", "N", elements, (2,), ()),
]
STEP_SPAN = 50.0  # time units stepped for the step cost: 100–300 steps in every family


# ---------------------------------------------------------------------- cache tiers
def cache_cases(quick: bool) -> list[tuple[str, ch.Scene, ch.Scene, ch.Scene]]:
    """(label, scene, the same structure with other numbers, a different structure)."""
    j2 = orbit_zonal(2)
    j2_numbers = ch.Scene.from_dict(
        {
            **j2.to_dict(),
            "orbit": {**j2.to_dict()["orbit"], "position": [1.1, -0.3, 0.2], "mu": 1.3},
            "perturbations": {"zonal": {"J2": 0.002, "radius": 0.7}},
        }
    )
    cases = [("orbit, J2 (Cartesian)", j2, j2_numbers, orbit_zonal(3))]
    if not quick:
        base = predominant_mass(3).to_dict()
        base["hamiltonian"]["central_mass"] = 1.2
        base["hamiltonian"]["bodies"][0]["mass"] = 2e-3
        cases.append(
            (
                "predominant mass, 3 bodies",
                predominant_mass(3),
                ch.Scene.from_dict(base),
                predominant_mass(4),
            )
        )
    return cases


# ---------------------------------------------------------------------- ensembles
@dataclass
class System:
    label: str
    scene: ch.Scene
    t_end: float
    members: Callable[[np.random.Generator, int], list[dict]]  # scene dictionaries


_BODY = {
    "body": {"inertia": [1.0, 1.5, 2.5]},
    "initial": {"rates": [0.3, 1.0, 0.5]},
    "attitude": {"formulation": "quaternion"},
}


def _body_members(rng: np.random.Generator, n: int) -> list[dict]:
    q = rng.standard_normal((n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    rates = np.array([0.3, 1.0, 0.5]) * (1 + 0.1 * rng.standard_normal((n, 3)))
    return [
        {**_BODY, "initial": {"rates": r.tolist(), "quaternion": qq.tolist()}}
        for r, qq in zip(rates, q, strict=True)
    ]


def _orbit_members(rng: np.random.Generator, n: int) -> list[dict]:
    base = orbit_zonal(2).to_dict()
    x = np.array([0.9, 0.2, 0.1]) * (1 + 0.05 * rng.standard_normal((n, 3)))
    v = np.array([-0.25, 0.85, 0.45]) * (1 + 0.05 * rng.standard_normal((n, 3)))
    return [
        {**base, "orbit": {**base["orbit"], "position": xi.tolist(), "velocity": vi.tolist()}}
        for xi, vi in zip(x, v, strict=True)
    ]


def with_times(data: dict, t_end: float) -> dict:
    """A scene dictionary whose output times are 0 and ``t_end``."""
    return {**data, "output": {"times": [0.0, t_end]}}


SYSTEMS = [
    System(
        "free rigid body (quaternion), t = 0…10",
        ch.Scene.from_dict(with_times(_BODY, 10.0)),
        10.0,
        _body_members,
    ),
    System(
        "J2 orbit (Cartesian), t = 0…2π",
        orbit_zonal(2),
        2 * math.pi,
        _orbit_members,
    ),
]
