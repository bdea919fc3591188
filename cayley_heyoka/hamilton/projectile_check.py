"""The hamiltonian family's consistency check.

* Hamilton's projectile (Second Essay, 1835, art. 19–20; docs/hamilton.md): the run against
  its closed form (113.)–(114.) and the principal function (120.), through the closed-form
  certificate of ``cayley-heyoka reference``, and the partial derivatives of S
  (:mod:`.principal`);
* the system with one predominant mass: Hamilton's elements against the canonical equations
  (:mod:`.predominant_mass.check`);
* any other Hamiltonian: the partial derivatives of S (:mod:`.principal`).

The closed-form rows are bounded as the torque-free body's are
(:mod:`cayley_heyoka.rotation.closed_form_check`): 10 ε √N times the flow's sensitivity to
the initial state, measured on the closed form.
"""

from __future__ import annotations

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
from ..core.precision import scene_mpf
from ..core.scene import Scene

__all__ = ["check_hamiltonian", "check_projectile"]

#: Digits of the closed form in the sensitivity, and the perturbation it measures it with.
#: Digits of the sensitivity's closed forms, and the relative move of the initial state
#: (text: read in their working precision).
_SENSITIVITY_DPS, _DELTA = 30, "1e-12"
_SENSITIVITY_TIMES = 16


def check_hamiltonian(scene: Scene, options: CheckOptions) -> CheckReport:
    """The check of a hamiltonian scene (see the module's docstring). It takes no options."""
    options.accept((), "check of a hamiltonian scene")
    if scene.model.model == "predominant_mass":
        from .predominant_mass.check import check_formulations

        return check_formulations(scene)
    from .principal import check_principal_function

    principal = check_principal_function(scene).report()
    if scene.model.model != "projectile":
        return principal
    closed = check_projectile(scene)
    return CheckReport(
        f"{closed.title}; {principal.title}",
        closed.rows + principal.rows,
        {**closed.series, **{f"principal_{k}": v for k, v in principal.series.items()}},
    )


def check_projectile(scene: Scene) -> CheckReport:
    """Run a projectile scene and compare η, ϖ (and S, if recorded) with the closed form.

    Parameters
    ----------
    scene
        A ``model = "projectile"`` scene (its user events are left out).

    Returns
    -------
    CheckReport
        One row per group (η, ϖ, S): the largest absolute difference from the closed form at
        the output times, against ``10 ε √N s + 10 ε max(1, max|x|)`` (the second term for the
        rounding of the recorded values and the closed form's own error), with N the run's
        steps and s the largest change of the group per unit change δ of the initial state,
        over each of η₀ᵢ moved by δ max|η| and ϖ₀ᵢ by δ max|ϖ| (and, for S, S₀ by δ max|S|),
        measured on the closed form at 16 times over the span.
    """
    from ..core.engine import run
    from .projectile_reference import closed_form

    if scene.model.model != "projectile":
        raise ValueError("scene: needs model = 'projectile'")
    result = run(scene.derive(drop=("events",)))
    # The closed form needs only the constants and the initial state; whichever formulation
    # the run took, it records η and ϖ.
    closed = closed_form(scene.derive({"hamiltonian.formulation": "canonical"}, drop=("events",)))
    prec = scene.integrator.precision
    cert = closed.certificate(result, prec.dps + 3)
    steps = int(result.counters.get("steps", 0))
    tolerance = scene.integrator.tolerance
    K = round_off_scale(steps, prec.epsilon, None if tolerance is None else float(tolerance))
    t = np.asarray(result.t, dtype=float)
    groups = {"η": ["eta1", "eta2", "eta3"], "ϖ": ["varpi1", "varpi2", "varpi3"]}
    if "S" in cert.errors:
        groups["S"] = ["S"]
    sizes = {
        g: max(float(np.max(np.abs(np.asarray(result[n], dtype=float)))) for n in names)
        for g, names in groups.items()
    }
    s = _sensitivity(scene, float(t[-1] - t[0]), sizes)
    rows, series = [], {"t": t}
    for group, names in groups.items():
        error = max(float(np.max(cert.errors[n])) for n in names)
        rows.append(
            CheckRow(
                f"{group} − closed form",
                error,
                K * s[group] + 10 * prec.epsilon * max(sizes[group], 1.0),
                f"10 ε √N × sensitivity; N = {steps}, sensitivity {s[group]:.3g}",
            )
        )
        for n in names:
            series[f"error_{n}"] = cert.errors[n]
    title = f"Hamilton's projectile against its closed form ({prec.name}; {len(t)} times)"
    return CheckReport(title, tuple(rows), series)


def _sensitivity(scene: Scene, span: float, sizes: dict[str, float]) -> dict[str, float]:
    from .projectile import projectile_solution

    h = scene.model
    c = h.constants
    with mpmath.workdps(_SENSITIVITY_DPS + 10):
        delta = mpmath.mpf(_DELTA)
        e0 = [scene_mpf(x) for x in h.eta]
        p0 = [scene_mpf(x) for x in h.varpi]
        moves = []
        for i in range(3):
            moved = list(e0)
            moved[i] += delta * sizes["η"]
            moves.append((moved, p0))
        for i in range(3):
            moved = list(p0)
            moved[i] += delta * sizes["ϖ"]
            moves.append((e0, moved))
        times = [
            mpmath.mpf(span) * k / _SENSITIVITY_TIMES for k in range(1, _SENSITIVITY_TIMES + 1)
        ]

        def evaluate(direction: int | None, t: Any) -> dict[str, Any]:
            e, p = (e0, p0) if direction is None else moves[direction]
            sol = projectile_solution(c["g"], c["mu"], c["nu"], e, p, t, dps=_SENSITIVITY_DPS)
            out = {"S": sol.S}
            out.update({f"eta{i}": x for i, x in enumerate(sol.eta)})
            out.update({f"varpi{i}": x for i, x in enumerate(sol.varpi)})
            return out

        measured = flow_sensitivity(evaluate, 6, times, delta)
    return {
        "η": max(measured[f"eta{i}"] for i in range(3)),
        "ϖ": max(measured[f"varpi{i}"] for i in range(3)),
        # S₀ enters S(t) additively: its own rounding is carried with factor one.
        "S": measured["S"] + sizes.get("S", 0.0),
    }
