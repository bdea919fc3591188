"""Cayley's element equations (62)–(63) checked along a forced run.

The elements of every sampled state of a forced rotation scene come from
:func:`.varying_constants.cayley_elements`; their actual rates (J ẋ, plus 1 for e, which
depends on t directly) are compared with the right-hand sides of (62)–(63) built from Cayley's
brackets (61) and ∂W/∂c = J⁻ᵀ ∇W, and, without J ẋ, the change of each element between samples
with the Gauss–Legendre integral of (62) over the run. Symbols as in :mod:`.varying_constants`.
"""

from __future__ import annotations

import hashlib
import math
import pickle
from typing import Any

import heyoka as hy
import mpmath
import numpy as np

from ..core.consistency import CheckReport, CheckRow
from ..core.errors import OptionError, SceneError
from ..core.exact import exact
from ..core.model import ParTable
from ..core.precision import Precision, number_argument
from ..core.scene import Scene
from ..core.vectors import dot
from . import attitude as att
from . import equations as eq
from .brackets import cayley_brackets, check_brackets
from .model import force_function, rodrigues_of_matrix
from .numbers import numbers
from .varying_constants import (
    ELEMENTS,
    SAFETY,
    CayleyElements,
    cayley_elements,
    column_scales,
    cross_array,
    floats,
    free_period,
    row_errors,
    solve,
    upsilon_range,
)

__all__ = ["check_element_equations"]


class _Forces:
    """Torque, body accelerations and W of a scene's forces, as one compiled function of
    (w, x, y, z, p, q, r): the attitude as a quaternion, so that θ = π is harmless."""

    _cache: dict[str, Any] = {}

    def __init__(self, scene: Scene) -> None:
        # The same force function the run integrates, written on the direction cosines as in
        # the quaternion formulation.
        body = scene.model
        prec = scene.integrator.precision
        pars = ParTable(prec)
        inertia = [pars.add(name, body.inertia[i]) for i, name in enumerate("ABC")]
        quat = list(hy.make_vars("qw", "qx", "qy", "qz"))
        rates = list(hy.make_vars("p", "q", "r"))
        names = [[hy.expression(f"R{i + 1}{j + 1}__") for j in range(3)] for i in range(3)]
        R = att.quaternion_to_matrix(quat)
        values = numbers(scene).values
        W = force_function(body, names, rodrigues_of_matrix(names), inertia, pars, values)
        torque = eq.matrix_torque(W, names, R)
        W = hy.subs(W, {str(names[i][j]): R[i][j] for i in range(3) for j in range(3)})
        L = eq.body_momentum(inertia, rates)
        gyro = cross_array(L, rates)
        accel = [(gyro[i] + torque[i]) / inertia[i] for i in range(3)]
        exprs = [*torque, *accel, W]
        key = hashlib.sha256(pickle.dumps(exprs) + prec.name.encode()).hexdigest()
        if key not in self._cache:
            self._cache[key] = hy.cfunc(
                exprs, [*quat, *rates], compact_mode=prec.kind == "real", **prec.heyoka_kwargs
            )
        self.cf = self._cache[key]
        self.pars = prec.array(pars.values)

    def __call__(self, quat: np.ndarray, rates: np.ndarray) -> tuple[np.ndarray, ...]:
        out = self.cf(np.concatenate([quat, rates]), pars=self.pars)
        return out[:3], out[3:6], out[6]


def _gauss_legendre(n: int, dps: int) -> tuple[list[str], list[str]]:
    """Nodes in (−1, 1), ascending, and weights of the n-point rule, as decimal text."""
    guess, _ = np.polynomial.legendre.leggauss(n)
    nodes, weights = [], []
    with mpmath.workdps(dps + 10):

        def legendre(x):
            p0, p1 = mpmath.mpf(1), x
            for j in range(2, n + 1):
                p0, p1 = p1, ((2 * j - 1) * x * p1 - (j - 1) * p0) / j
            return p1, n * (x * p1 - p0) / (x * x - 1)

        for x0 in guess:
            x = mpmath.mpf(float(x0))
            for _ in range(50):
                P, dP = legendre(x)
                x, step = x - P / dP, P / dP
                if abs(step) < mpmath.mpf(10) ** (-dps - 8):
                    break
            _, dP = legendre(x)
            nodes.append(mpmath.nstr(x, dps + 5))
            weights.append(mpmath.nstr(2 / ((1 - x * x) * dP * dP), dps + 5))
    return nodes, weights


def _validate_scene(scene: Scene) -> None:
    if scene.family != "rotation":
        raise ValueError(f"scene: the elements are those of a rotating body, not {scene.family!r}")
    body = scene.model
    if not body.forces:
        raise SceneError(
            "forces",
            "the scene has no force function: the elements are constant and (62) has nothing "
            "to check",
        )
    moving = [type(f).__name__ for f in body.forces if f.time_dependent]
    if moving:
        raise SceneError(
            "forces",
            f"W depends explicitly on t ({', '.join(moving)}); this check takes W as a "
            "function of the state alone (∂W/∂c from the state's gradient): use a "
            "time-independent force function",
        )


def _choose_upsilon0(inertia, rates, quat, t, prec: Precision) -> str:
    """υ₀ at the middle of υ's range; if the start state's passage there has a turning margin
    below 0.05, whichever of 0.5, 0.4, 0.6, 0.3, 0.7 of the way up the range has the largest."""
    lo, hi = upsilon_range(inertia, rates, quaternion=quat, precision=prec)
    candidates = []
    for fraction in ("0.5", "0.4", "0.6", "0.3", "0.7"):
        with mpmath.workdps(prec.dps + 5):
            low, high = exact(lo), exact(hi)
            text = mpmath.nstr(low + (high - low) * mpmath.mpf(fraction), 17)
        try:
            E = cayley_elements(inertia, rates, None, t, text, quaternion=quat, precision=prec)
        except ValueError:
            continue
        if fraction == "0.5" and E.turning_margin >= 0.05:
            return text
        candidates.append((E.turning_margin, text))
    if not candidates:
        raise ValueError(
            f"upsilon0: no usable value found inside υ's range [{float(lo)}, {float(hi)}]"
        )
    return max(candidates)[1]


def check_element_equations(
    scene: Scene,
    samples: int | None = None,
    upsilon0: Any = None,
    *,
    nodes: int | None = None,
) -> CheckReport:
    """Check Cayley's element equations (62)–(63) along a forced run of a rotation scene.

    The scene is run (:func:`cayley_heyoka.core.engine.run`, in its own precision) over its output
    span on a grid of ``samples`` intervals with ``nodes`` Gauss–Legendre nodes each. At every
    recorded state x the elements c and their Jacobian J (in the body-rotation coordinates
    x = (φ, ω) of :meth:`CayleyElements.jacobian`) are computed in the same precision,
    following one passage of υ₀ along the run (at the start, the latest passage at or before
    it), and compared:

    * **pointwise**: the actual rates ``dc/dt = ∂c/∂t + J ẋ`` (ẋ = (ω, ω̇) from the forced
      equations, ``∂e/∂t = 1``) against (62) with ``∂W/∂c = J⁻ᵀ ∇ₓW`` (∇ₓW = (N, 0), N the
      body torque); and ``dk/dt = a·ȧ/k`` against (63), ``∂W/∂δ``;
    * **integrated**: the change of each element over each interval, computed from the states
      at its ends, against the Gauss–Legendre integral of (62) (this does not use J ẋ); and,
      as the witness that the quadrature has converged, against the integral of the actual
      rates;
    * **brackets**: (61) against ``J P Jᵀ`` at every state (:func:`check_brackets`).

    Parameters
    ----------
    scene
        A rotation scene with a time-independent force function. Only the first and last of
        its output times are used.
    samples
        Intervals of the integrated comparison; default: one per eighth of the period of the
        rates at the start (at least 2).
    upsilon0
        υ₀; default: the middle of υ's range over the free motion through the start state, so
        that V₀ ≠ 0 (if the start state's passage there has a turning margin
        |V₀|/(k|L_b||ω|) below 0.05, whichever of 0.4, 0.6, 0.3, 0.7 of the way up the range
        has the largest). A value outside the range or at a turning value is refused
        (ValueError naming ``upsilon0``).
    nodes
        Gauss–Legendre nodes per interval; default ``⌈0.3 × bits⌉`` (16 in double, 34 in
        quad). Over an eighth of a period the truncation error of an n-node rule was measured
        to fall like about 0.15^(2n) relative on weakly forced runs (1e-13 at 8 nodes), more
        slowly under strong forcing (5e-12 at 12 nodes, 7e-15 at 20, on
        ``examples/heavy_top.toml``): the default keeps it below the round-off, and the
        quadrature-witness row measures it.

    Returns
    -------
    CheckReport
        One row per element and comparison. A row's error is the worst ratio, over the
        samples, of the measured difference to the law's bound there (so its bound is 1); the
        note gives the worst difference relative to the largest rate (or change) of that
        element. ``series`` holds the per-sample rates, bounds and element values.

    Raises
    ------
    SceneError
        For a scene without forces or with a time-dependent force function.
    ValueError
        For a scene of another family, or an unusable υ₀.

    Notes
    -----
    **Round-off law** (fixed before any run). ε is the precision's epsilon, n the Taylor steps
    of the free motion from the state to its passage, m = |V₀|/(k|L_b||ω|) at the passage.

    * Row i of J, its columns scaled by s = (1, 1, 1, |ω|, |ω|, |ω|), errs by at most ηᵢρᵢ in
      each entry, ρᵢ = maxⱼ |Jᵢⱼ sⱼ|: η = 10ε for a, b, c, h (algebraic) and
      η = 10ε(1 + n)/m for e and δ (each step at tolerance ε adds at most ε relative,
      accumulated linearly; V₀ = 2ġ divides the event-time derivative, and its absolute error
      ε k|L_b||ω| is relative ε/m). A bracket (61) errs by max(ηᵢ, ηⱼ) times the absolute
      sum of its terms.
    * The actual rate errs by ``ηᵢρᵢ Σⱼ|ẋⱼ|/sⱼ`` (+ 10ε for ∂e/∂t = 1); (62) by the
      brackets' error times |∂W/∂c| plus |(61)| times the error of ∂W/∂c = J⁻ᵀ∇W, propagated
      to first order through the row-equilibrated Ĵ = diag(ρ)⁻¹ J diag(s):
      ``|Δŵ| ≤ |Ĵ⁻ᵀ| β`` with ŵ = ρ∘∂W/∂c and ``β = Σᵢ ηᵢ|ŵᵢ| + 10ε|s∘∇W|``. A row's bound
      is the sum of both sides'.
    * An element's value errs as under a state error of relative size ηᵢ:
      ``ηᵢ(6ρᵢ + |cᵢ|)``. Its change over an interval errs by that at both ends, plus the
      weighted pointwise bounds over the nodes, plus the run's own local errors inside the
      interval, ``10 ε_run (1 + n_run) 6 max ρᵢ`` (n_run the interval's share of the run's
      steps, ε_run the scene's tolerance or ε). The Gauss–Legendre truncation error is not in
      the law: the quadrature witness row shows it is below it.
    """
    _validate_scene(scene)
    prec = scene.integrator.precision
    body = scene.model
    grid = scene.time_grid
    if len(grid) < 2:
        raise SceneError("output.times", "the check needs a time span: give at least two times")
    if nodes is None:
        nodes = math.ceil(0.3 * prec.bits)
    if samples is not None and samples < 1 or nodes < 1:
        raise ValueError(f"samples, nodes: must be positive, got {samples}, {nodes}")
    t_start, t_stop = grid[0], grid[-1]
    forces = _Forces(scene)
    inertia = prec.array(body.inertia)
    q_start = body.initial_quaternion(prec)
    rates_start = prec.array(body.rates)
    period = free_period(inertia, rates_start)
    if upsilon0 is None:
        upsilon0 = _choose_upsilon0(inertia, rates_start, q_start, t_start, prec)
    else:
        upsilon0 = number_argument(upsilon0, "upsilon0")
        try:
            prec.hold(upsilon0, "upsilon0")
        except SceneError as exc:
            raise OptionError("upsilon0", exc.constraint) from None
        # Refuse a bad υ₀ before the run, with the start state's range in the message.
        cayley_elements(
            inertia, rates_start, None, t_start, upsilon0, quaternion=q_start, precision=prec
        )

    count = (
        samples if samples is not None else max(2, math.ceil(8 * float(t_stop - t_start) / period))
    )
    gl_x, gl_w = _gauss_legendre(nodes, prec.dps)
    with mpmath.workdps(prec.dps + 10):
        a0, b0 = exact(t_start), exact(t_stop)
        ends = [a0 + (b0 - a0) * i / count for i in range(count + 1)]
        times = []
        for i in range(count):
            half = (ends[i + 1] - ends[i]) / 2
            times += [ends[i]] + [ends[i] + half * (1 + mpmath.mpf(x)) for x in gl_x]
        times.append(ends[-1])
        texts = [mpmath.nstr(x, prec.dps + 5) for x in times]
    from ..core.engine import run

    result = run(scene.derive({"output": {"times": texts}}, drop=("events",)))
    samples_data = _sample_along(result, inertia, upsilon0, forces, prec)
    eps_run = (
        float(scene.integrator.tolerance)
        if scene.integrator.tolerance is not None
        else prec.epsilon
    )
    return _report(
        samples_data,
        count,
        nodes,
        prec.array(gl_w),
        int(result.counters.get("steps", 0)),
        eps_run,
        prec,
        f"{scene.title or 'the scene'} ({prec.name}; υ₀ = {float(upsilon0):.10g})",
    )


def _sample_along(result, inertia, upsilon0, forces: _Forces, prec: Precision) -> list[dict]:
    quats = np.stack([result[n] for n in ("qw", "qx", "qy", "qz")], axis=1)
    rates = np.stack([result[n] for n in ("p", "q", "r")], axis=1)
    out = []
    previous = None
    for t, quat, w in zip(result.t, quats, rates, strict=True):
        try:
            E = cayley_elements(
                inertia, w, None, t, upsilon0, quaternion=quat, near=previous, precision=prec
            )
        except ValueError as exc:
            # The forcing has carried the motion to where the followed passage is lost.
            raise ValueError(
                f"{exc} — at t = {float(t):.6g} of the run: the forcing has moved the elements "
                "so far that this passage of υ₀ is lost; shorten the run or choose υ₀ "
                "(a weakly forced run keeps it)"
            ) from None
        previous = E
        torque, accel, _ = forces(E.quaternion, E.rates)
        out.append(_pointwise(E, torque, accel))
    return out


def _pointwise(E: CayleyElements, torque: np.ndarray, accel: np.ndarray) -> dict:
    """Actual and (62) rates at one state (native precision), with the law's bounds (floats)."""
    eps = E.precision.epsilon
    J = E.rotation_jacobian
    xdot = np.concatenate([E.rates, accel])
    grad = np.concatenate([torque, 0 * torque])
    one = 0 * E.k + 1
    explicit = np.array([0 * one] * 4 + [one, 0 * one])
    actual = explicit + J @ xdot
    dW = solve(np.array(J.T, copy=True), grad)
    B = cayley_brackets(E)
    predicted = B @ dW
    a_vec = np.array([E.a, E.b, E.c])

    Jf, s, eta = floats(J), column_scales(E), row_errors(E)
    rho = np.max(np.abs(Jf) * s[None, :], axis=1)
    bound_actual = eta * rho * np.sum(np.abs(floats(xdot)) / s) + SAFETY * eps * floats(explicit)
    w_hat = rho * np.abs(floats(dW))
    J_hat = Jf * s[None, :] / rho[:, None]
    beta = np.sum(eta * w_hat) + SAFETY * eps * np.abs(s * floats(grad))
    dw = (np.abs(np.linalg.inv(J_hat.T)) @ beta) / rho
    Babs = floats(cayley_brackets(E, absolute=True))
    bound_predicted = (np.maximum.outer(eta, eta) * Babs) @ np.abs(floats(dW)) + Babs @ dw
    k_bound = np.abs(floats(a_vec)) @ bound_actual[:3] / float(E.k) + dw[5]
    return {
        "elements": E,
        "actual": actual,
        "predicted": predicted,
        "k": (dot(a_vec, actual[:3]) / E.k, dW[5], k_bound),
        "bound": bound_actual + bound_predicted,
        "bound_actual": bound_actual,
        "value_error": E.error_bounds,
        "rho": rho,
        "brackets": check_brackets(E).rows[0],
    }


def _report(
    data: list[dict],
    count: int,
    nodes: int,
    weights: np.ndarray,
    n_run: int,
    eps_run: float,
    prec: Precision,
    what: str,
) -> CheckReport:
    elements = [d["elements"] for d in data]
    t_native = np.array([E.t for E in elements])
    t = floats(t_native)
    values = np.array([E.values for E in elements])
    actual = np.array([d["actual"] for d in data])
    predicted = np.array([d["predicted"] for d in data])
    bound = np.array([d["bound"] for d in data])
    bound_actual = np.array([d["bound_actual"] for d in data])
    value_error = np.array([d["value_error"] for d in data])
    rho = np.array([d["rho"] for d in data])
    rows: list[CheckRow] = []
    series: dict[str, np.ndarray] = {"t": t}
    labels = ("a", "b", "c", "h", "e", "δ")

    diff = np.abs(floats(actual - predicted))
    for i, name in enumerate(labels):
        scale = float(np.max(np.abs(floats(actual[:, i]))))
        rows.append(
            CheckRow(
                f"d{name}/dt: (62) vs actual / law bound",
                float(np.max(diff[:, i] / bound[:, i])),
                1.0,
                _relative(diff[:, i], scale, f"|d{name}/dt|"),
            )
        )
        series[f"rate_actual_{ELEMENTS[i]}"] = floats(actual[:, i])
        series[f"rate_62_{ELEMENTS[i]}"] = floats(predicted[:, i])
        series[f"difference_{ELEMENTS[i]}"] = diff[:, i]
        series[f"bound_{ELEMENTS[i]}"] = bound[:, i]
    k_actual = np.array([d["k"][0] for d in data])
    k_63 = np.array([d["k"][1] for d in data])
    k_bound = np.array([d["k"][2] for d in data])
    k_diff = np.abs(floats(k_actual - k_63))
    rows.append(
        CheckRow(
            "dk/dt: (63) vs actual / law bound",
            float(np.max(k_diff / k_bound)),
            1.0,
            _relative(k_diff, float(np.max(np.abs(floats(k_actual)))), "|dk/dt|"),
        )
    )
    series["rate_actual_k"], series["rate_63_k"] = floats(k_actual), floats(k_63)
    series["difference_k"] = k_diff

    # Interval ends sit at every (nodes + 1)-th sample, the nodes between them.
    ends = list(range(0, len(data), nodes + 1))
    n_interval = n_run / count
    changes, by_62, by_actual, bounds, bounds_actual = [], [], [], [], []
    for m in range(count):
        i0, i1 = ends[m], ends[m + 1]
        half = (t_native[i1] - t_native[i0]) / 2
        inner = slice(i0 + 1, i1)
        changes.append(values[i1] - values[i0])
        by_62.append(half * (weights @ predicted[inner]))
        by_actual.append(half * (weights @ actual[inner]))
        run_error = SAFETY * eps_run * (1 + n_interval) * 6 * np.maximum(rho[i0], rho[i1])
        base = value_error[i0] + value_error[i1] + run_error
        h = float(half)
        w = floats(weights)
        bounds.append(base + h * (w @ bound[inner]))
        bounds_actual.append(base + h * (w @ bound_actual[inner]))
    changes, by_62, by_actual = np.array(changes), np.array(by_62), np.array(by_actual)
    bounds, bounds_actual = np.array(bounds), np.array(bounds_actual)
    d62 = np.abs(floats(changes - by_62))
    for i, name in enumerate(labels):
        scale = float(np.max(np.abs(floats(changes[:, i]))))
        rows.append(
            CheckRow(
                f"Δ{name} over an interval vs ∫(62) dt / law bound",
                float(np.max(d62[:, i] / bounds[:, i])),
                1.0,
                _relative(d62[:, i], scale, f"|Δ{name}|"),
            )
        )
        series[f"change_{ELEMENTS[i]}"] = floats(changes[:, i])
        series[f"integral_62_{ELEMENTS[i]}"] = floats(by_62[:, i])
        series[f"integral_difference_{ELEMENTS[i]}"] = d62[:, i]
        series[f"integral_bound_{ELEMENTS[i]}"] = bounds[:, i]
    witness = np.abs(floats(changes - by_actual)) / bounds_actual
    rows.append(
        CheckRow(
            "Δc vs ∫ actual rates dt (quadrature witness) / law bound",
            float(np.max(witness)),
            1.0,
            f"{count} intervals × {nodes} Gauss–Legendre nodes",
        )
    )
    worst = max((d["brackets"] for d in data), key=lambda r: r.error)
    rows.append(CheckRow("(61) vs J P Jᵀ at every state / law bound", worst.error, 1.0, worst.note))
    series["t_interval_end"] = t[ends[1:]]
    for i, name in enumerate(ELEMENTS):
        series[f"element_{name}"] = floats(values[:, i])
    series["free_steps"] = np.array([E.steps for E in elements], dtype=float)
    series["turning_margin"] = np.array([E.turning_margin for E in elements])
    title = (
        f"Cayley 1846 element equations (62)–(63) against the elements' rates along {what}: "
        f"{len(data)} states over [{t[0]:g}, {t[-1]:g}]"
    )
    return CheckReport(title, tuple(rows), series)


def _relative(diff: np.ndarray, scale: float, what: str) -> str:
    worst = float(np.max(diff))
    # A conserved element (e.g. the vertical momentum of an upright top) has only rounding for
    # a rate: a relative figure would mean nothing.
    if scale > 10 * worst:
        return f"max |Δ| = {worst:.2e} = {worst / scale:.1e} of max {what} = {scale:.2e}"
    return f"max |Δ| = {worst:.2e}; max {what} = {scale:.2e}: conserved, to rounding"
