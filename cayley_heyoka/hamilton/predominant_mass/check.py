"""A predominant-mass scene checked against its other formulation.

The canonical equations of (F2.) and Hamilton's varying elements (S2.) share nothing but H and
the starting state: one integrates (ξ, p), the other the elements through Kepler's equation
and the gradient of H₂. :func:`check_formulations` runs a scene both ways and compares ξ and
x′ on the output grid, each row against a bound from the round-off law of the phase fixed
before the runs (docs/hamilton.md):

* every step rounds the energy by ~ε, so the mean motion walks like ε√N over N steps and the
  along-track error grows like (3/2) ε √N n t a; the bound is 10 ε √N t max(n a), N the steps
  of both runs, plus 4 ε max(a/e) for the starting state (the eccentricity of Hamilton's
  elements comes from 1 − e² and carries ε/e);
* velocities: the same times max n;
* the energy and the angular momentum of each run: Brouwer's 10 ε √N, relative.
"""

from __future__ import annotations

import math
from typing import Any

import mpmath
import numpy as np

from ...core.consistency import CheckReport, CheckRow
from ...core.exact import difference
from ...core.precision import scene_mpf
from ...core.scene import Scene
from ..formulations import FORMULATIONS
from . import system as planets


def check_formulations(scene: Scene) -> CheckReport:
    """Run a ``model = "predominant_mass"`` scene in both formulations and compare them.

    Parameters
    ----------
    scene
        A predominant-mass scene (its own formulation is ignored; both are run, in the scene's
        precision and with its integrator options).

    Returns
    -------
    CheckReport
        Rows for ξ, x′, and the conservation of each run; series ``t``, ``position``,
        ``velocity`` (largest difference over the bodies at each output time).

    Raises
    ------
    ValueError
        When the scene is not of this model.
    SceneError
        When a body cannot be given Hamilton's elements (circular, planar or unbound orbits),
        naming it.
    """
    from ...core.engine import run

    if scene.family != "hamiltonian" or scene.model.model != "predominant_mass":
        raise ValueError("scene: needs model = 'predominant_mass'")
    data = scene.to_dict()
    runs = {}
    for formulation in FORMULATIONS:
        data["hamiltonian"]["formulation"] = formulation
        runs[formulation] = run(Scene.from_dict(data))
    a, b = runs["elements"], runs["canonical"]
    eps = scene.integrator.precision.epsilon
    steps = a.counters["steps"] + b.counters["steps"]
    t = np.asarray(b.t, dtype=float)
    span = float(t[-1] - t[0])
    scale = _orbit_scales(scene)
    position_bound = 10 * eps * math.sqrt(steps) * span * scale["na"] + 4 * eps * scale["a/e"]
    velocity_bound = position_bound * scale["n"]
    n = len(scene.model.bodies)
    series: dict[str, np.ndarray] = {"t": t}
    rows = []
    for label, prefix, bound in (
        ("ξ: elements − canonical", "", position_bound),
        ("x′: elements − canonical", "v", velocity_bound),
    ):
        worst = np.zeros(len(t))
        for i in range(1, n + 1):
            d = [difference(a[f"{prefix}{axis}{i}"], b[f"{prefix}{axis}{i}"]) for axis in "xyz"]
            worst = np.maximum(worst, [math.hypot(*c) for c in zip(*d, strict=True)])
        series["position" if not prefix else "velocity"] = worst
        rows.append(CheckRow(label, float(np.max(worst)), bound, "10 ε √N t max(n a) law"))
    for name, res in runs.items():
        for monitor in res.conserved:
            drift = float(np.max(np.abs(res.drift(monitor))))
            bound = 10 * eps * math.sqrt(res.counters["steps"])
            rows.append(CheckRow(f"{monitor} drift ({name})", drift, bound, "10 ε √N"))
    title = "Predominant mass: Hamilton's elements (S2.) against the canonical equations of (F2.)"
    return CheckReport(title, tuple(rows), series)


def _orbit_scales(scene: Scene) -> dict[str, float]:
    """max n·a, max n and max a/e over the bodies' starting relative orbits."""
    ham = scene.model
    G, M = ham.constants["G"], ham.constants["central_mass"]
    na, n, ae = 0.0, 0.0, 0.0
    with mpmath.workdps(30):
        for body in ham.bodies:
            x, v = body.state(M, G)
            m, Mf, Gf = (_mpf(value) for value in (body.mass, M, G))
            el = planets.classical_elements(x, v, m, Mf, Gf)
            mean_motion = mpmath.sqrt(Gf * (Mf + m) / el.a**3)
            na = max(na, float(mean_motion * el.a))
            n = max(n, float(mean_motion))
            ae = max(ae, float(el.a / el.e))
    return {"na": na, "n": n, "a/e": ae}


def _mpf(value: Any) -> mpmath.mpf:
    return scene_mpf(value)
