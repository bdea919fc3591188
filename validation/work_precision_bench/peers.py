"""The peers' sweeps, in the same process as ours: scipy, REBOUND IAS15, mpmath.

Peers, in the same process: scipy's ``solve_ivp`` (DOP853; Radau once, to check stiffness) on
the same equations, their right-hand side compiled by heyoka into a ``cfunc`` (so scipy pays
only its own per-call Python overhead, not a slow numpy right-hand side); mpmath's ``odefun``
(``free_extended``); REBOUND's IAS15 with REBOUNDx's ``gravitational_harmonics`` for J2 and plain
N-body gravity for the planets. A peer that is not installed is reported as such.
"""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Callable, Sequence
from typing import Any

import heyoka as hy
import mpmath
import numpy as np
from bench_common import available

import cayley_heyoka as ch
from cayley_heyoka.core.families import FAMILIES

from . import timing
from .errors import rotation_error
from .records import Case, Point
from .timing import least_time, log


# ---------------------------------------------------------------------------- scipy
def _compiled_rhs(data: dict, jacobian: bool) -> tuple[Callable, Callable | None, np.ndarray]:
    """The scene's right-hand side (and Jacobian) as heyoka cfuncs in double, and its initial
    state: the very equations our integrator steps, callable from scipy."""
    scene = ch.Scene.from_dict(data)
    model = FAMILIES[scene.family].build(scene)
    variables = [v for v, _ in model.system]
    rhs = [r for _, r in model.system]
    y0 = np.array([float(v) for v in model.initial_state])
    n = len(y0)

    def compiled(exprs: list) -> Callable:
        f = hy.cfunc(exprs, variables)
        pars = np.array([float(v) for v in model.pars.values[: f.nparams]])
        # scipy hands over views (Radau's finite differences too): cfuncs want C order.
        return lambda t, y: f(np.ascontiguousarray(y), pars=pars, time=t)

    fun = compiled(rhs)
    if not jacobian:
        return fun, None, y0
    jac = compiled(list(np.ravel(hy.diff_tensors(rhs, diff_args=variables, diff_order=1).jacobian)))
    return fun, lambda t, y: jac(t, y).reshape(n, n), y0


def _group_scale(y0: np.ndarray, groups: Sequence[int]) -> np.ndarray:
    """Per-component scale for scipy's atol: the norm of each component's vector at t0 (a
    quaternion, a position, a momentum), so atol = rtol·scale asks for relative accuracy."""
    out, k = [], 0
    for g in groups:
        out += [np.linalg.norm(y0[k : k + g])] * g
        k += g
    return np.array(out)


def scipy_sweep(
    case: Case,
    data: dict,
    t_end: float,
    groups: Sequence[int],
    error: Callable[[np.ndarray], float],
    rtols: Sequence[float],
    method: str = "DOP853",
    label: str = "",
) -> None:
    """solve_ivp on the compiled right-hand side; also times one right-hand-side call."""
    if not available("scipy"):
        case.missing.append(f"scipy {method}: not installed")
        return
    from scipy.integrate import solve_ivp

    fun, jac, y0 = _compiled_rhs(data, jacobian=method == "Radau")
    scale = _group_scale(y0, groups)
    kwargs = {"jac": jac} if jac else {}
    for rtol in rtols:

        def go(rtol: float = rtol) -> Any:
            return solve_ivp(
                fun, (0.0, t_end), y0, method=method, rtol=rtol, atol=rtol * scale, **kwargs
            )

        w, sol = least_time(go)
        if not sol.success:
            log(f"{case.name}: scipy {method} rtol {rtol:g} failed: {sol.message}")
            continue
        err = error(sol.y[:, -1])
        steps = len(sol.t) - 1
        case.points.append(
            Point(
                label or f"scipy {method}", f"rtol {rtol:g}", steps, w, err, extra=f"{sol.nfev} f"
            )
        )
        log(
            f"{case.name}: scipy {method} rtol {rtol:g}: {steps} steps, {w * 1e3:.1f} ms, {err:.2e}"
        )
    # Where scipy's time goes: one right-hand-side call, as solve_ivp makes it.
    calls = 20000
    s = time.perf_counter()
    for _ in range(calls):
        fun(0.0, y0)
    case.rhs_call = (time.perf_counter() - s) / calls


# ---------------------------------------------------------------------------- REBOUND
def _ias15(sim: Any) -> Any:
    # REBOUND 4 exposes the IAS15 settings as sim.ri_ias15, REBOUND 5 as sim.integrator.
    return sim.ri_ias15 if hasattr(sim, "ri_ias15") else sim.integrator


def ias15_sweep(
    case: Case,
    build: Callable[[], tuple[Any, Any]],
    t_end: float,
    error: Callable[[Any], float],
    epsilons: Sequence[float | None],
    needs: Sequence[str] = ("rebound",),
) -> None:
    """IAS15 over the sweep of ``epsilon``; ``build`` returns a fresh simulation (and whatever
    must stay alive with it, e.g. REBOUNDx's extras). Only ``integrate`` is timed."""
    missing = [m for m in needs if not available(m)]
    if missing:
        case.missing.append(f"REBOUND IAS15: {', '.join(missing)} not installed")
        return
    for eps in epsilons:
        best, sim = math.inf, None
        for _ in range(timing.REPEAT):
            sim, keep = build()
            _ias15(sim).epsilon = eps if eps is not None else _ias15(sim).epsilon
            label = f"ε {_ias15(sim).epsilon:g}" + (" (default)" if eps is None else "")
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                s = time.perf_counter()
                sim.integrate(t_end, exact_finish_time=1)
                best = min(best, time.perf_counter() - s)
            del keep
            if best > timing.BUDGET:
                break
        err = error(sim)
        warned = "predictor–corrector warnings" if caught else ""
        case.points.append(
            Point("REBOUND IAS15", label, int(sim.steps_done), best, err, extra=warned)
        )
        log(f"{case.name}: IAS15 {label}: {sim.steps_done} steps, {best * 1e3:.1f} ms, {err:.2e}")


# ---------------------------------------------------------------------------- mpmath
def mpmath_point(case: Case, rc, t_end: float, dps: int, tol: float | None, ref) -> None:
    """mpmath's odefun (its Taylor method) on the quaternion equations at ``dps`` digits."""
    with mpmath.workdps(dps):
        A, B, C = (mpmath.mpf(x) for x in rc.inertia)
        e0, e1, e2 = (B - C) / A, (C - A) / B, (A - B) / C
        half = mpmath.mpf(1) / 2

        def F(t, y):
            p, q, r, w, x, yy, z = y
            return [
                e0 * q * r,
                e1 * r * p,
                e2 * p * q,
                half * (-x * p - yy * q - z * r),
                half * (w * p + yy * r - z * q),
                half * (w * q - x * r + z * p),
                half * (w * r + x * q - yy * p),
            ]

        y0 = [mpmath.mpf(x) for x in (*rc.rates, 1.0, 0.0, 0.0, 0.0)]
        s = time.perf_counter()
        solution = mpmath.odefun(F, 0, y0, tol=tol)
        y = solution(mpmath.mpf(t_end))
        elapsed = time.perf_counter() - s
    err = rotation_error(y, ref)
    setting = f"{dps} digits, tol {tol:g}" if tol else f"{dps} digits, tol ε"
    case.points.append(Point(f"mpmath odefun, {dps} digits", setting, None, elapsed, err))
    log(f"{case.name}: mpmath {setting}: {elapsed:.2f} s, {err:.2e}")
