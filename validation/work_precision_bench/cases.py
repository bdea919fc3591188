"""The cases and the sweeps, fixed before any run.

Cases (spans kept modest; the e = 0.5, 10⁴-orbit IAS15 accuracy study is another section's):

* ``free_regular``, ``free_separatrix`` — torque-free bodies of validation/rotation_cases.py (the
  generic body and the one 1e-6 from the separatrix), 20 periods, against the closed form
  ``cayley_heyoka.reference.FreeRigidBody``;
* ``heavy_top`` — the bundled examples/heavy_top.toml over t = 50, against a real128 run;
* ``orbit_j2`` — a J2 orbit at e = 0.1 over 100 orbits, against a real128 Cartesian run;
* ``planets`` — the predominant-mass system of examples/planets.toml over 100 inner orbits,
  against a real128 canonical run;
* ``free_extended`` — the generic body over a short span in extended precision: real128,
  MPFR at 113 and 256 bits, mpmath's ``odefun``.

Here: each precision's tolerance sweep, the peers' sweeps, the error levels of the ratio tables,
and the scenes each case runs (as the dicts ``cayley_heyoka.Scene.from_dict`` reads) with the
initial states the peers are handed.
"""

from __future__ import annotations

import copy
from pathlib import Path

import hamilton_planets
import mpmath
import rotation_cases

import cayley_heyoka as ch
from cayley_heyoka.hamilton.predominant_mass import system as hp
from cayley_heyoka.hamilton.predominant_mass.numbers import initial_state as planets_initial_state
from cayley_heyoka.mechanics import kepler as oe

ROOT = Path(__file__).resolve().parents[2]

# ---------------------------------------------------------------------------- the sweeps
TOL = {
    "double": ("1e-6", "1e-9", "1e-12", "1e-14", "1e-16"),
    "quad": ("1e-16", "1e-20", "1e-26", "1e-32"),
    "real113": ("1e-16", "1e-20", "1e-26", "1e-32"),
    "real256": ("1e-20", "1e-40", "1e-60", "1e-76"),
}
QUICK_TOL = {
    "double": ("1e-9", "1e-16"),
    "quad": ("1e-20",),
    "real113": ("1e-20",),
    "real256": ("1e-40",),
}
SPECS = {"double": "double", "quad": "quad", "real113": {"bits": 113}, "real256": {"bits": 256}}
LABEL = {"double": "double", "quad": "real128", "real113": "real 113", "real256": "real 256"}
# DOP853 refuses rtol below 100 ε (scipy raises it to 2.2e-14 with a warning).
RTOL = (1e-4, 1e-6, 1e-8, 1e-10, 1e-12, 1e-13)
QUICK_RTOL = (1e-6, 1e-10)
IAS15_EPSILON = (1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, None)  # None: REBOUND's default
QUICK_IAS15_EPSILON = (1e-4, None)
# Error levels of the ratio tables: double-accessible ones against our best double
# formulation, extended ones against our best real128 formulation.
DOUBLE_LEVELS = (1e-8, 1e-11, 1e-13)
EXTENDED_LEVELS = (1e-20, 1e-30)
REFERENCE_TOL = "1e-32"
TINY = 1e-6  # the span of the run that measures run()'s fixed cost


def tolerances(quick: bool, precision: str) -> tuple[str, ...]:
    """Our tolerance sweep at ``precision``."""
    return (QUICK_TOL if quick else TOL)[precision]


def quad_tolerances(quick: bool, k: int, reference: bool = False) -> tuple[str, ...]:
    """The real128 tolerances of the ``k``-th formulation of a case.

    ``reference``: the case's reference is formulation 0 at 1e-32 (not run twice); the others
    get one point (real128 compiles take 5–60 s each at high order, and the reference is
    checked by :func:`our_side.reference_check`). The quick run sweeps formulation 0 only.
    """
    if quick:
        return QUICK_TOL["quad"] if k == 0 else ()
    if not reference:
        return TOL["quad"]
    if k == 0:
        return tuple(t for t in TOL["quad"] if t != REFERENCE_TOL)
    return ("1e-20",)


def with_integrator(data: dict, precision: str, tolerance: str, times: list) -> ch.Scene:
    """The scene ``data`` at one precision and tolerance, output at ``times``."""
    d = copy.deepcopy(data)
    d["integrator"] = {**d.get("integrator", {}), "precision": SPECS[precision]}
    d["integrator"]["tolerance"] = tolerance
    d.setdefault("output", {})["times"] = list(times)
    return ch.Scene.from_dict(d)


# ---------------------------------------------------------------------------- the scenes
ROTATION = ("p", "q", "r", "qw", "qx", "qy", "qz")


def rotation_data(case: rotation_cases.Case, formulation: str) -> dict:
    """A torque-free body of validation/rotation_cases.py, without events or monitors."""
    d = case.scene("double", [0.0, 1.0], events=False, formulation=formulation)
    d["output"]["monitors"] = []
    d.pop("events", None)
    return d


def heavy_top_example() -> dict:
    """The bundled examples/heavy_top.toml as a dict."""
    return ch.load_scene(ROOT / "examples" / "heavy_top.toml").to_dict()


def heavy_top_data(example: dict, formulation: str) -> dict:
    """The heavy top from the identity attitude, in ``formulation``."""
    d = copy.deepcopy(example)
    d["initial"] = {"rates": d["initial"]["rates"], "quaternion": [1.0, 0.0, 0.0, 0.0]}
    d["attitude"] = {"formulation": formulation}
    d["output"] = {"times": [0.0, 1.0], "monitors": []}
    d.pop("integrator", None)
    return d


J2_ORBIT = {
    "mu": 1.0,
    "elements": (1.0, 0.1, 0.4, 0.3, 1.2, 0.5),  # a, e, i, node, ω, M
    "J2": 1e-3,
    "radius": 0.5,
    "orbits": 100,
}


def j2_initial_state() -> tuple[list[float], list[float]]:
    """The J2 orbit's position and velocity, rounded once to binary64 and handed to every
    method as such, so all of them (and the real128 reference) integrate the same numbers."""
    a, e, i, node, w, M = J2_ORBIT["elements"]
    x0, v0 = oe.elements_to_cartesian(oe.Elements(a, e, i, node, w, M), J2_ORBIT["mu"])
    return [float(c) for c in x0], [float(c) for c in v0]


def j2_data(x0: list[float], v0: list[float], formulation: str) -> dict:
    """The J2 orbit from (x0, v0), in ``formulation``."""
    return {
        "orbit": {
            "mu": J2_ORBIT["mu"],
            "position": x0,
            "velocity": v0,
            "formulation": formulation,
        },
        "perturbations": {"zonal": {"J2": J2_ORBIT["J2"], "radius": J2_ORBIT["radius"]}},
        "output": {"times": [0.0, 1.0], "monitors": []},
    }


def planets_data(orbits: int, formulation: str) -> dict:
    """examples/planets.toml's system (validation/hamilton_planets.py) in ``formulation``."""
    d = hamilton_planets.n5_scene(formulation, orbits, 2)
    d["output"] = {"times": [0.0, 1.0], "monitors": []}
    d.pop("integrator", None)
    return d


def planets_barycentric(orbits: int) -> tuple[list[list[float]], list[list[float]]]:
    """Barycentric positions and velocities of the star and the planets for REBOUND, from the
    exact canonical state, rounded once."""
    masses = [float(m) for m, _ in hamilton_planets.BODIES]
    n = len(masses)
    scene = ch.Scene.from_dict(hamilton_planets.n5_scene("canonical", orbits, 2))
    with mpmath.workdps(50):
        state = [mpmath.mpf(s) for s in planets_initial_state(scene.model, "0", 50)]
        xi = [state[3 * k : 3 * k + 3] for k in range(n)]
        xprime = [
            [p / mpmath.mpf(masses[k]) for p in state[3 * n + 3 * k : 3 * n + 3 * k + 3]]
            for k in range(n)
        ]
        X, V = hp.barycentric(xi, xprime, [mpmath.mpf(m) for m in masses], mpmath.mpf(1))
        X = [[float(c) for c in x] for x in X]
        V = [[float(c) for c in v] for v in V]
    return X, V
