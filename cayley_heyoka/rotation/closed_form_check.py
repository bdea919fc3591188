"""The rotation family's consistency check: the closed form, or Cayley's element equations.

A torque-free body is run and compared, at its output times and invariable-plane crossings,
with Cayley's 1843 solution (:class:`~cayley_heyoka.reference.FreeRigidBody`, docs/reference.md)
through the closed-form certificate of ``cayley-heyoka reference``
(:func:`cayley_heyoka.rotation.free_body_reference.closed_form`). A forced body has no closed
form: its check is Cayley's 1846 element equations (:mod:`.element_check`).

The bound of each row is fixed before the run by Brouwer's round-off law: N steps each round
the state by about ε, the errors add like a random walk, and the flow carries each to the
output times multiplied by at most its sensitivity to the initial state, measured on the
closed form itself (:func:`~cayley_heyoka.core.consistency.flow_sensitivity`). So the bound is
``10 ε √N × sensitivity`` (:func:`~cayley_heyoka.core.consistency.round_off_scale`); the sensitivity
grows with the span (the period depends on the invariants, so the phase walks), and near the
separatrix with the period's dependence on them.
"""

from __future__ import annotations

import math
from types import SimpleNamespace
from typing import Any

import mpmath
import numpy as np

from ..core import outcomes
from ..core.consistency import (
    CheckOptions,
    CheckReport,
    CheckRow,
    flow_sensitivity,
    round_off_scale,
)
from ..core.exact import difference, exact_array
from ..core.precision import exact_fraction, scene_mpf
from ..core.scene import Scene
from ..core.scene_dicts import edited
from .attitude import quaternion_multiply
from .scene import with_formulation

__all__ = ["check_closed_form", "check_rotation", "check_twin"]

#: Digits of the closed form in the sensitivity, and the perturbation it measures it with.
#: Digits of the sensitivity's closed forms, and the relative move of the initial state
#: (text: read in their working precision).
_SENSITIVITY_DPS, _DELTA = 30, "1e-12"
#: Times at which the sensitivity is measured, evenly over the span (it grows with t).
_SENSITIVITY_TIMES = 16


def check_rotation(scene: Scene, options: CheckOptions) -> CheckReport:
    """The check of a rotation scene.

    * torque-free: :func:`check_closed_form`; option ``times`` (compare at this many output
      times, evenly spread; default all);
    * forced: option ``method``: ``elements`` (Cayley's 1846 element equations,
      :func:`~.element_check.check_element_equations`, with its options ``upsilon0``,
      ``samples`` and ``nodes``) or ``twin`` (:func:`check_twin`). Default: ``elements``
      where it applies (a force function of the state alone, and a passage of υ₀ that can be
      followed along the whole run), else ``twin`` (the report says why); giving
      ``upsilon0``, ``samples`` or ``nodes`` means ``elements``.
    """
    if scene.model.torque_free:
        options.accept(("times",), "closed-form check of a torque-free body")
        return check_closed_form(scene, times=options.integer("times", minimum=2))
    from .element_check import check_element_equations

    element_keys = ("upsilon0", "samples", "nodes")
    options.accept(("method", *element_keys), "check of a forced body")
    method = options.choice("method", ("elements", "twin"))
    if not scene.model.form.element_check:
        if method == "elements" or any(options.text(k) is not None for k in element_keys):
            raise ValueError(
                "method: Cayley's element check needs the attitude, which the Euler–Poisson "
                "reduction does not integrate: use method=twin (the default here)"
            )
        options.accept(("method",), "twin check of a reduced body")
        return check_twin(
            scene,
            why="Cayley's element check needs an integrated attitude, which the Euler–Poisson "
            "reduction has not",
        )
    if method == "twin":
        options.accept(("method",), "twin check of a forced body")
        return check_twin(scene)
    try:
        return check_element_equations(
            scene,
            # Each sample is a quadrature in mpmath (1000 take ~30 s); the nodes' default is
            # at most 308 (1024 bits).
            samples=options.integer("samples", maximum=10**4),
            upsilon0=options.number("upsilon0", scene.integrator.precision),
            nodes=options.integer("nodes", maximum=400),
        )
    except ValueError as exc:  # SceneError included: e.g. a force function of t
        chosen = method or any(options.text(k) is not None for k in element_keys)
        if chosen:
            raise
        return check_twin(scene, why=f"Cayley's element check does not apply ({exc})")


def check_closed_form(scene: Scene, times: int | None = None) -> CheckReport:
    """Run a torque-free rotation scene and compare it with Cayley's 1843 closed form.

    Parameters
    ----------
    scene
        A rotation scene without forces (its user events are left out: the closed form has
        the motion, not them).
    times
        Compare at this many of the output times, evenly spread with the first and last
        (default: all of them).

    Returns
    -------
    CheckReport
        Rows for the body rates, the quaternion (if the run records it), the Rodrigues
        parameters (error over the bound at each time: λ grows without limit near a half-turn,
        and with it its conditioning) and the invariable-plane crossing times (if recorded).

    Raises
    ------
    ValueError
        For a forced scene, or a state the closed form does not cover (exactly on the
        separatrix).

    Notes
    -----
    With K = 10 ε √N (N the run's steps; plus N × (tolerance − ε) for a tolerance above ε)
    and the sensitivities s measured on the closed form — the largest change of a quantity
    per unit change δ of the initial state, over the rates moved by δ|ω| along each body axis
    and the attitude turned by δ about each, at 16 times over the span:

    * rates: K s_ω, s_ω the sensitivity of (p, q, r);
    * quaternion: K s_q + 10 ε (the norm of an integrated quaternion walks too);
    * Rodrigues (λ, μ, ν) at each time: K s_q (1 + |λ|) √(1 + |λ|²), the change of λ = v/w
      under a change of the unit quaternion by K s_q;
    * a crossing of the invariable plane by axis i is where ω_i = 0: its time errs by the
      rates' bound over |dω_i/dt| there, which the invariants fix (the least over the axes),
      plus 10 ε max(1, t) for the event's root.
    """
    from ..core.engine import run
    from .free_body_reference import closed_form

    if not scene.model.torque_free:
        raise ValueError("scene: the closed form is that of a torque-free body; it has forces")
    scene = scene.derive(drop=("events",))
    closed = closed_form(scene)
    result = run(scene)
    prec = scene.integrator.precision
    compared = _thinned(result, times)
    try:
        cert = closed.certificate(compared, prec.dps + 3)
        events_note = ""
    except RuntimeError as exc:  # the run and the closed form disagree on the crossings
        events_note = str(exc)
        compared = SimpleNamespace(t=compared.t, variables=compared.variables, events={})
        cert = closed.certificate(compared, prec.dps + 3)
    steps = int(result.counters.get("steps", 0))
    tolerance = scene.integrator.tolerance
    K = round_off_scale(steps, prec.epsilon, None if tolerance is None else float(tolerance))
    t = np.asarray(compared.t, dtype=float)
    s = _sensitivity(scene, float(t[-1] - t[0]))
    rows, series = _attitude_rows(cert.errors, compared.variables, t, K, s, steps, prec)
    if events_note or "invariable_plane" in cert.event_errors:
        crossing = cert.event_errors.get("invariable_plane", np.array([math.nan]))
        speed = _crossing_speed(scene)
        span = max(1.0, float(np.max(np.abs(t))))
        rows.append(
            CheckRow(
                "invariable-plane crossing times − closed form",
                float(np.max(crossing)) if crossing.size else 0.0,
                K * s["rates"] / speed + 10 * prec.epsilon * span,
                events_note
                or f"rates' bound / |dω_i/dt| at a crossing ({speed:.3g}); "
                f"{crossing.size} crossings",
            )
        )
        series["error_crossings"] = crossing
    title = (
        f"Torque-free body against Cayley's 1843 closed form: {scene.title or 'the scene'} "
        f"({prec.name}; {len(t)} times over [{t[0]:g}, {t[-1]:g}])"
    )
    return CheckReport(title, tuple(rows), series)


LAMBDA = ("lambda", "mu", "nu")
_QUATERNION = ("qw", "qx", "qy", "qz")


def _attitude_rows(
    errors: dict[str, np.ndarray],
    variables: Any,
    t: np.ndarray,
    K: float,
    s: dict[str, float],
    steps: int,
    prec: Any,
    against: str = "closed form",
) -> tuple[list[CheckRow], dict[str, np.ndarray]]:
    """Rows for the rates, the quaternion and the Rodrigues parameters, from their errors, the
    round-off scale K and the sensitivities ``s`` (see the Notes of :func:`check_closed_form`)."""
    law = f"10 ε √N × sensitivity; N = {steps}"
    # The recorded rates are rounded once more: 10 ε of their size (all the bound at t₀).
    rates = np.sqrt(sum(np.asarray(variables[n], dtype=float) ** 2 for n in "pqr"))
    rows = [
        CheckRow(
            f"p, q, r − {against}",
            max(float(np.max(errors[n])) for n in "pqr"),
            K * s["rates"] + 10 * prec.epsilon * float(np.max(rates)),
            f"{law}, sensitivity {s['rates']:.3g}",
        )
    ]
    series: dict[str, np.ndarray] = {"t": t}
    for n in "pqr":
        series[f"error_{n}"] = errors[n]
    quaternion = _QUATERNION
    if all(n in errors for n in quaternion):
        rows.append(
            CheckRow(
                f"qw, qx, qy, qz − {against}",
                max(float(np.max(errors[n])) for n in quaternion),
                K * s["quaternion"] + 10 * prec.epsilon,
                f"{law}, sensitivity {s['quaternion']:.3g}",
            )
        )
        for n in quaternion:
            series[f"error_{n}"] = errors[n]
    if "lambda" in errors:
        size = np.sqrt(sum(np.asarray(variables[n], dtype=float) ** 2 for n in LAMBDA))
        bound = K * s["quaternion"] * (1 + size) * np.sqrt(1 + size**2)
        error = np.max([errors[n] for n in LAMBDA], axis=0)
        k = int(np.argmax(error / bound))
        rows.append(
            CheckRow(
                f"λ, μ, ν − {against} / bound at t",
                float(error[k] / bound[k]),
                1.0,
                f"worst at t = {t[k]:.6g}: {error[k]:.2e} against {bound[k]:.2e} "
                f"(|λ| = {size[k]:.3g})",
            )
        )
        series["error_rodrigues"], series["bound_rodrigues"] = error, bound
    return rows, series


def check_twin(scene: Scene, why: str = "") -> CheckReport:
    """Run a rotation scene and its twin in the other attitude formulation, and compare.

    The twin integrates the same forces from the same state with the attitude as a quaternion
    where the scene has Rodrigues parameters (with their chart changes), or the reverse, in
    the same precision: the two share nothing but the equations of motion, so their
    round-off is independent.

    Parameters
    ----------
    scene
        A rotation scene with an attitude (its events are left out of both runs).
    why
        Why this check was chosen, for the title.

    Returns
    -------
    CheckReport
        Rows for the rates, the quaternion and the Rodrigues parameters, bounded as in
        :func:`check_closed_form` with N the steps of both runs, and sensitivities measured by
        heyoka's variational equations (``var_ode_sys``) of the quaternion formulation along
        the run, at 16 times over the span: the largest change of the rates (quaternion) per
        unit change δ of the initial state, over each rate moved by δ|ω| and each component of
        the quaternion by δ. For a chaotic motion (a heavy top is one) the sensitivity grows
        exponentially, and so does the bound: the check then says that the run is as accurate
        as the motion's conditioning allows.
    """
    from ..core.certificate import difference_certificate
    from ..core.engine import run

    body = scene.model
    form = body.form
    if form.reduced:
        return _check_poisson_twin(scene, why)
    other = form.twin
    if other is None:
        raise ValueError(
            f"scene: the twin check needs an attitude (formulation {form.name!r} has none)"
        )
    own = scene.derive(drop=("events", "output.events"))
    a, b = run(own), run(Scene.from_dict(with_formulation(own, other)))
    cert = difference_certificate(a, b)
    prec = own.integrator.precision
    steps = int(a.counters.get("steps", 0)) + int(b.counters.get("steps", 0))
    tolerance = own.integrator.tolerance
    K = round_off_scale(steps, prec.epsilon, None if tolerance is None else float(tolerance))
    t = np.asarray(a.t, dtype=float)
    s = _variational_sensitivity(own, float(t[-1] - t[0]))
    rows, series = _attitude_rows(
        cert.errors, a.variables, t, K, s, steps, prec, f"the {other} formulation"
    )
    title = (
        f"Rotation ({body.formulation}, {prec.name}) against its {other} twin: "
        f"{scene.title or 'the scene'} ({len(t)} times over [{t[0]:g}, {t[-1]:g}])"
    )
    if why:
        title += f"; the twin because {why}"
    return CheckReport(title, tuple(rows), series)


#: Rᵀ of a unit quaternion, row j = the body axis j in space axes (γ_j = Σᵢ R_ij uᵢ).
_MATRIX = (
    ("1 - 2*(qy*qy + qz*qz)", "2*(qx*qy - qw*qz)", "2*(qx*qz + qw*qy)"),
    ("2*(qx*qy + qw*qz)", "1 - 2*(qx*qx + qz*qz)", "2*(qy*qz - qw*qx)"),
    ("2*(qx*qz - qw*qy)", "2*(qy*qz + qw*qx)", "1 - 2*(qx*qx + qy*qy)"),
)


def _check_poisson_twin(scene: Scene, why: str) -> CheckReport:
    """The Euler–Poisson reduction against its quaternion twin: the rates, and γ = Rᵀu of
    the twin's attitude (user monitors of the twin, in its precision). γ's bound is 4× the
    quaternion's (|δγ| ≤ |δR| ≤ 4|δq| for unit quaternions). With ``output.azimuth`` the
    reduction's whole attitude too: its quaternion (up to sign: q and −q are one attitude) and
    λ, μ, ν against the twin's."""
    from ..core.engine import run
    from .poisson import GAMMA, direction

    own = scene.derive(drop=("events", "output.events", "monitors", "output.monitors"))
    prec = own.integrator.precision
    u = [str(x) for x in direction(own.model.forces, prec)]
    gamma = {
        name: {
            "expression": " + ".join(f"({_MATRIX[i][j]})*({u[i]})" for i in range(3)),
            "conserved": False,
        }
        for j, name in enumerate(GAMMA)
    }
    twin = edited(with_formulation(own, "quaternion", more=True), {"monitors": gamma})
    a, b = run(own), run(Scene.from_dict(twin))
    attitude = [n for n in (*_QUATERNION, *LAMBDA) if n in a.variables]
    errors = {n: difference(a[n], b[n]) for n in ("p", "q", "r", *GAMMA, *attitude)}
    flipped = {n: difference(a[n], -np.asarray(b[n])) for n in attitude if n in _QUATERNION}
    if flipped:
        # The sign of each row's quaternion is the formulation's choice: q and −q are one
        # attitude, so each row is compared with the nearer of the twin's two.
        nearer = np.max(list(flipped.values()), axis=0) < np.max(
            [errors[n] for n in _QUATERNION], axis=0
        )
        for n in _QUATERNION:
            errors[n] = np.where(nearer, flipped[n], errors[n])
    steps = int(a.counters.get("steps", 0)) + int(b.counters.get("steps", 0))
    tolerance = own.integrator.tolerance
    K = round_off_scale(steps, prec.epsilon, None if tolerance is None else float(tolerance))
    t = np.asarray(a.t, dtype=float)
    s = _variational_sensitivity(own, float(t[-1] - t[0]))
    rows, series = _attitude_rows(errors, a.variables, t, K, s, steps, prec, "the quaternion twin")
    rows.append(
        CheckRow(
            "γ₁, γ₂, γ₃ − the quaternion twin's Rᵀu",
            max(float(np.max(errors[n])) for n in GAMMA),
            4 * K * s["quaternion"] + 10 * prec.epsilon,
            f"10 ε √N × 4 × the quaternion's sensitivity {s['quaternion']:.3g}; N = {steps}",
        )
    )
    for n in GAMMA:
        series[f"error_{n}"] = errors[n]
    title = (
        f"Rotation (poisson, {prec.name}) against its quaternion twin: "
        f"{scene.title or 'the scene'} ({len(t)} times over [{t[0]:g}, {t[-1]:g}])"
    )
    if why:
        title += f"; the twin because {why}"
    return CheckReport(title, tuple(rows), series)


def _variational_sensitivity(scene: Scene, span: float) -> dict[str, float]:
    """Sensitivities of the rates and the quaternion to the initial state, from heyoka's
    first-order variational equations of the quaternion formulation (in double: a bound's
    factor needs no more)."""
    import heyoka as hy

    from ..core.precision import Precision
    from ..core.structures import model_for

    # Only the start is the twin's own (the span is given): times that are distinct in the
    # scene's precision but not in double must not refuse the check.
    start = [repr(float(scene.time_grid[0]))]
    data = with_formulation(scene, "quaternion", more=True)
    twin = Scene.from_dict(
        edited(data, {"integrator": {"precision": "double"}, "output.times": start})
    )
    model = model_for(twin)
    prec = Precision("double")
    names = [str(v) for v, _ in model.system]
    variational = hy.var_ode_sys(model.system, hy.var_args.vars, order=1)
    ta = hy.taylor_adaptive(
        variational,
        prec.array(model.initial_state),
        pars=prec.array(model.pars.values[: model.integrator_parameters()]),
        compact_mode=True,
    )
    t0 = float(twin.time_grid[0])
    ta.time = t0
    grid = [t0 + span * k / _SENSITIVITY_TIMES for k in range(_SENSITIVITY_TIMES + 1)]
    run = outcomes.GridRun.of(ta.propagate_grid(grid))
    states = run.whole("scene: the twin's variational equations (its sensitivity)", ta.time)
    rates = [names.index(n) for n in "pqr"]
    quaternion = [names.index(n) for n in ("qw", "qx", "qy", "qz")]
    w0 = np.asarray(model.initial_state, dtype=float)[rates]
    scale = np.ones(len(names))
    scale[rates] = np.sqrt(np.sum(w0**2))
    out = {"rates": 0.0, "quaternion": 0.0}
    for row in states:
        J = np.array([row[ta.get_vslice(order=1, component=i)] for i in range(len(names))])
        J = J * scale[None, :]
        out["rates"] = max(out["rates"], float(np.max(np.abs(J[rates]))))
        out["quaternion"] = max(
            out["quaternion"], float(np.max(np.linalg.norm(J[quaternion], axis=0)))
        )
    return out


def _thinned(result: Any, count: int | None) -> Any:
    """The run at ``count`` of its output times, evenly spread, first and last included."""
    n = len(result.t)
    if count is None or count >= n:
        return result
    keep = np.unique(np.round(np.linspace(0, n - 1, count)).astype(int))
    variables = {k: np.asarray(v)[keep] for k, v in result.variables.items()}
    return SimpleNamespace(t=np.asarray(result.t)[keep], variables=variables, events=result.events)


def _sensitivity(scene: Scene, span: float) -> dict[str, float]:
    """Sensitivities of the rates and the quaternion to the initial state (see the Notes of
    :func:`check_closed_form`), from the closed form at :data:`_SENSITIVITY_DPS` digits."""
    from ..core.precision import Precision
    from .closed_form import FreeRigidBody

    body = scene.model
    dps = _SENSITIVITY_DPS
    with mpmath.workdps(dps + 10):
        rates = [scene_mpf(x) for x in body.rates]
        size = mpmath.sqrt(sum(x * x for x in rates))
        q0 = exact_array(body.initial_quaternion(Precision("real", 4 * dps)))
        delta = mpmath.mpf(_DELTA)
        half = delta / 2
        starts = []
        for axis in range(3):
            moved = list(rates)
            moved[axis] += delta * size
            starts.append((moved, q0))
        for axis in range(3):
            turn = [mpmath.cos(half), 0, 0, 0]
            turn[axis + 1] = mpmath.sin(half)
            starts.append((rates, quaternion_multiply(q0, turn)))
        bodies = [
            FreeRigidBody(
                body.inertia,
                [mpmath.nstr(x, dps + 10) for x in w],
                attitude=[mpmath.nstr(x, dps + 10) for x in q],
                dps=dps,
            )
            for w, q in [(rates, q0), *starts]
        ]
        times = [
            mpmath.mpf(span) * k / _SENSITIVITY_TIMES for k in range(1, _SENSITIVITY_TIMES + 1)
        ]

        def evaluate(direction: int | None, t: Any) -> dict[str, Any]:
            state = bodies[0 if direction is None else direction + 1].at(t)
            out = dict(zip("pqr", state.rates, strict=True))
            out.update(dict(zip("wxyz", state.quaternion, strict=True)))
            return out

        measured = flow_sensitivity(evaluate, 6, times, delta)
    return {
        "rates": max(measured[n] for n in "pqr"),
        "quaternion": max(measured[n] for n in "wxyz"),
    }


def _crossing_speed(scene: Scene) -> float:
    """The least |dω_i/dt| at ω_i = 0 over the axes whose rate vanishes on the motion."""
    body = scene.model
    I = [float(exact_fraction(x)) for x in body.inertia]  # noqa: E741
    w = [float(exact_fraction(x)) for x in body.rates]
    h = sum(I[i] * w[i] ** 2 for i in range(3))
    k2 = sum((I[i] * w[i]) ** 2 for i in range(3))
    speeds = []
    for i in range(3):
        j, k = (i + 1) % 3, (i + 2) % 3
        if I[j] == I[k]:
            continue
        wj2 = (k2 - I[k] * h) / (I[j] * (I[j] - I[k]))
        wk2 = (k2 - I[j] * h) / (I[k] * (I[k] - I[j]))
        if wj2 > 0 and wk2 > 0:
            speeds.append(abs(I[j] - I[k]) / I[i] * math.sqrt(wj2 * wk2))
    return min(speeds) if speeds else math.inf
