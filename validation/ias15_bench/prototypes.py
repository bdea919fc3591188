"""Two prototypes, written here and not in the library, that test the explanation of the gap
to IAS15:

* *compensated state*: heyoka takes the Taylor steps (``ta.step``), the state is accumulated in
  80-bit long double in Python from each step's Taylor coefficients, as IAS15 accumulates its
  state by compensated summation; optionally with the acceleration (the first coefficient of
  the velocity) evaluated in long double too;
* *extended precision*: our Cartesian equations compiled by heyoka in x87 long double (64-bit
  significand): what a ``precision = "extended"`` scene option would run.
"""

from __future__ import annotations

from typing import Any

import heyoka as hy
import numpy as np

from cayley_heyoka.orbit.model import build_model

from .case import LD, MU, START, State, exact_text, grid, k2, scene


def cartesian_integrator(fp_type: Any = float, tol: float | None = None) -> Any:
    """Our Cartesian J2 equations (the model's heyoka expressions) in ``fp_type``."""
    model = build_model(scene("cartesian", grid(1)))
    pars = model.pars.values[: model.integrator_parameters()]
    kw: dict[str, Any] = {} if tol is None else {"tol": fp_type(tol)}
    if fp_type is not float:
        kw["fp_type"] = fp_type
    return hy.taylor_adaptive(
        model.system,
        np.zeros(6, dtype=fp_type),
        pars=np.array([fp_type(str(p)) for p in pars], dtype=fp_type),
        **kw,
    )


# ------------------------------------------------------------- prototype: compensated state
def _acceleration(X: np.ndarray) -> np.ndarray:
    """−μx/r³ + ∇Ω of J2 about z, in long double."""
    x = X[:3]
    r2 = x @ x
    r = np.sqrt(r2)
    g = k2() / (2 * r2 * r2 * r)
    f = 15 * x[2] ** 2 / r2
    grad = np.array([g * x[0] * (f - 3), g * x[1] * (f - 3), g * x[2] * (f - 9)])
    return -LD(MU) * x / (r2 * r) + grad


def compensated(
    times: np.ndarray, ta: Any, start: State = START, exact_acceleration: bool = False
) -> tuple[np.ndarray, int]:
    """heyoka's Taylor steps from the double state; the state itself accumulated in long double.

    Each step, ``ta.step(write_tc=True)`` leaves the Taylor coefficients c_k of the step (taken
    at the double state). The long-double state X advances by Σ_{k≥1} c_k h^k — the position's
    first-order term with X's own velocity, so the kinematic coupling of the low part is exact —
    and heyoka restarts from X rounded to double. With ``exact_acceleration`` the acceleration
    (c₁ of v, 2c₂ of x) is evaluated at X in long double as well.
    """
    ta.time = 0.0
    ta.state[:] = start[0] + start[1]
    X = np.array(start[0] + start[1], dtype=LD)
    t = LD(0)
    state = ta.state
    out = np.empty((6, len(times)), dtype=LD)
    out[:, 0] = X
    steps = 0
    k = np.arange(1, ta.order + 1)
    for i in range(1, len(times)):
        target = LD(times[i])
        while t < target:
            remaining = float(target - t)
            ta.step(max_delta_t=remaining, write_tc=True)
            steps += 1
            h = ta.last_h
            tc = ta.tc
            powers = h**k
            higher = tc[:, 2:] @ powers[1:]  # Σ_{k≥2} c_k h^k in double: ~ε (ωh)² |x|
            H = LD(h)
            if exact_acceleration:
                a = _acceleration(X)
                X[:3] += X[3:] * H + a * H * H / 2 + tc[:3, 3:] @ powers[2:]
                X[3:] += a * H + higher[3:]
            else:
                X[:3] += X[3:] * H + higher[:3]
                X[3:] += tc[3:, 1].astype(LD) * H + higher[3:]
            state[:] = X.astype(float)
            t = target if h == remaining else t + H
        out[:, i] = X
    return out, steps


# ------------------------------------------------------------- prototype: extended precision
def extended(times: np.ndarray, ta: Any, start: State = START) -> tuple[np.ndarray, int]:
    """Our Cartesian equations (the same heyoka expressions) in x87 long double."""
    ta.time = LD(0)
    ta.state[:] = np.array([LD(exact_text(c)) for c in start[0] + start[1]])
    res = ta.propagate_grid(np.array(times, dtype=LD))
    return res[-1].T, int(res[3])
