"""The orbit family's consistency check: the scene against an independent twin.

The twin integrates the same disturbing function from the same starting state by other
equations — by default the Cartesian ẍ = −μx/r³ + ∇Ω for a Cayley, quaternion or Encke scene
(Cayley 1860; docs/orbits.md, "Formulations"), and for a Cartesian scene the same scene at the
next precision (double → quad → MPFR). Positions and velocities are compared at the output
times in the fixed frame.

The bounds follow Brouwer's round-off law (as the predominant-mass check's do,
:mod:`cayley_heyoka.hamilton.predominant_mass.check`): each of the N steps of both runs rounds
the state by about ε, the errors add like a random walk, and the flow carries each to the output
times multiplied by at most its sensitivity to the initial state. The sensitivity is that of the
Kepler orbit through the starting state, measured on its closed form (the disturbing function
moves it by a relative amount of its own size, covered by the factor 10): it grows along the
track like (3/2) n t, the mean motion's response to an energy error."""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

import mpmath
import numpy as np

from ..core.consistency import (
    CheckOptions,
    CheckReport,
    CheckRow,
    flow_sensitivity,
    round_off_scale,
)
from ..core.exact import difference, exact
from ..core.scene import Scene
from ..core.scene_dicts import edited
from ..mechanics import kepler as el
from .scene import FORMULATIONS, with_formulation

__all__ = ["TWINS", "check_orbit", "check_twin"]

#: What a scene can be checked against: another formulation, or its own at a higher precision.
TWINS = (*FORMULATIONS, "precision")
#: Digits of the sensitivity's Kepler orbits, and the relative move of the initial state
#: (text: read in their working precision).
_SENSITIVITY_DPS, _DELTA = 40, "1e-15"
_SENSITIVITY_TIMES = 16
_STATE = ("x", "y", "z", "vx", "vy", "vz")


def check_orbit(scene: Scene, options: CheckOptions) -> CheckReport:
    """The check of an orbit scene (:func:`check_twin`); option ``twin`` (``--set
    twin=…``): one of :data:`TWINS`."""
    options.accept(("twin",), "twin check of an orbit")
    return check_twin(scene, options.choice("twin", TWINS))


def check_twin(scene: Scene, twin: str | None = None) -> CheckReport:
    """Run an orbit scene and its twin, and compare positions and velocities.

    Parameters
    ----------
    scene
        An orbit scene (its events are left out of both runs: they do not change the motion).
    twin
        ``"cartesian"``, ``"cayley"``, ``"quaternion"`` or ``"encke"``: the same scene in
        that formulation, in the same precision; ``"precision"``: the same scene at the next
        precision. Default: ``"cartesian"``, or ``"precision"`` for a Cartesian scene.

    Returns
    -------
    CheckReport
        Rows for the position and the velocity: the largest distance between the runs at the
        output times against ``K s + 10 ε max|x|``, with K = 10 ε √N (N the steps of both runs)
        and s the sensitivity of the position (velocity) to the initial state: the largest
        change per unit change δ, over each component of the initial position moved by δ|x₀|
        and of the velocity by δ|v₀|, measured on the Kepler orbit at 16 times over the span.

    Raises
    ------
    ValueError
        When the twin is the scene's own formulation, or the orbit is not an ellipse (the
        bound's sensitivity is the Kepler ellipse's).
    """
    from ..core.certificate import label, next_precision
    from ..core.engine import run

    orbit = scene.model
    twin = twin or orbit.form.twin
    if twin == orbit.formulation:
        raise ValueError(f"--set twin: the scene is already {twin!r}; choose another twin")
    own = scene.derive(drop=("events", "output.events"))
    prec = own.integrator.precision
    if twin == "precision":
        other = next_precision(prec)
        changes = {"integrator.precision": other.to_spec(), "integrator.tolerance": "auto"}
        data = edited(own.to_dict(), changes)
        what = label(other)
    else:
        data = with_formulation(own, twin)
        what = f"the {twin} formulation"
    grid = own.time_grid
    # The sensitivity first: an orbit it cannot bound is refused before any run.
    s = _sensitivity(own, float(grid[-1] - grid[0]))
    a, b = run(own), run(Scene.from_dict(data))
    steps = int(a.counters.get("steps", 0)) + (
        0 if twin == "precision" else int(b.counters.get("steps", 0))
    )
    tolerance = own.integrator.tolerance
    K = round_off_scale(steps, prec.epsilon, None if tolerance is None else float(tolerance))
    t = np.asarray(a.t, dtype=float)
    rows, series = [], {"t": t}
    for name, axes in (("position", _STATE[:3]), ("velocity", _STATE[3:])):
        # Each component's difference exactly, in the runs' own precision (a quad twin's
        # differences lie far below double's ε); their length without underflow.
        d = [difference(a[n], b[n]) for n in axes]
        distance = np.array([math.hypot(*c) for c in zip(*d, strict=True)], dtype=float)
        size = float(np.max(np.sqrt(sum(np.asarray(a[n], dtype=float) ** 2 for n in axes))))
        rows.append(
            CheckRow(
                f"{name}: {orbit.formulation} − {what}",
                float(np.max(distance)),
                K * s[name] + 10 * prec.epsilon * size,
                f"10 ε √N × sensitivity; N = {steps}, sensitivity {s[name]:.3g}",
            )
        )
        series[name] = distance
    title = (
        f"Orbit ({orbit.formulation}, {prec.name}) against {what}: "
        f"{scene.title or 'the scene'} ({len(t)} times over [{t[0]:g}, {t[-1]:g}])"
    )
    return CheckReport(title, tuple(rows), series)


def _sensitivity(scene: Scene, span: float) -> dict[str, float]:
    """Sensitivities of the Kepler orbit through the starting state (see :func:`check_twin`)."""
    from ..core.precision import scene_mpf
    from .model import initial_cartesian

    orbit = scene.model
    t0 = scene.time_grid[0]
    with mpmath.workdps(_SENSITIVITY_DPS):
        delta = mpmath.mpf(_DELTA)
        mu = scene_mpf(orbit.mu)
        x0, v0 = initial_cartesian(orbit, exact(t0))
        start = el.cartesian_to_elements(x0, v0, mu)
        if not 0 <= start.e < 1:
            raise ValueError(
                f"orbit: the twin check's bound is the Kepler ellipse's; this orbit has "
                f"e = {mpmath.nstr(start.e, 6)} ≥ 1"
            )
        sizes = (mpmath.norm(x0), mpmath.norm(v0))
        moves = []
        for i in range(6):
            x, v = list(x0), list(v0)
            if i < 3:
                x[i] += delta * sizes[0]
            else:
                v[i - 3] += delta * sizes[1]
            moves.append(el.cartesian_to_elements(x, v, mu))
        times = [
            mpmath.mpf(span) * k / _SENSITIVITY_TIMES for k in range(1, _SENSITIVITY_TIMES + 1)
        ]

        def evaluate(direction: int | None, t: Any) -> dict[str, Any]:
            e = start if direction is None else moves[direction]
            moved = replace(e, mean_anomaly=e.mean_anomaly + mpmath.sqrt(mu / e.a**3) * t)
            x, v = el.elements_to_cartesian(moved, mu)
            return {"position": list(x), "velocity": list(v)}

        measured = flow_sensitivity(evaluate, 6, times, delta)
    return measured
