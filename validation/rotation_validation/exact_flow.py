"""What the laws need from the exact flow of one case, from the closed form and a dense run."""

from __future__ import annotations

import mpmath
import numpy as np
from rotation_cases import Case, separatrix_distance

import cayley_heyoka as ch
from cayley_heyoka.reference import FreeRigidBody

from .laws import LawConstants


def sensitivities(case: Case, dps: int = 50) -> tuple[float, float, mpmath.mpf]:
    """S_T = |∇_ω ln T|·|ω₀| and S_Ψ = |∇_ω Ψ̄|·|ω₀| by central differences of the closed form.

    The step 1e-25·|ω₀| is far inside the separatrix distance of every case (≥ 1e-14) and the
    closed form is certified to ``dps`` = 50 digits, so the differences carry ~25 digits.
    """
    with mpmath.workdps(dps + 20):
        w = [mpmath.mpf(x) for x in case.rates]
        norm = mpmath.sqrt(sum(x * x for x in w))
        h = mpmath.mpf("1e-25") * norm
        grad_T, grad_P = [], []
        for i in range(3):
            vals = []
            for sign in (1, -1):
                wp = list(w)
                wp[i] += sign * h
                body = FreeRigidBody(case.inertia, wp, attitude=(1.0, 0.0, 0.0, 0.0), dps=dps)
                vals.append((mpmath.log(body.period), body.psi_increment / body.period))
            grad_T.append((vals[0][0] - vals[1][0]) / (2 * h))
            grad_P.append((vals[0][1] - vals[1][1]) / (2 * h))
        body = FreeRigidBody(case.inertia, case.rates, attitude=(1.0, 0.0, 0.0, 0.0), dps=dps)
        period = body.period
        S_T = norm * mpmath.sqrt(sum(x * x for x in grad_T))
        S_P = norm * mpmath.sqrt(sum(x * x for x in grad_P))
        return float(S_T), float(S_P), period


def orbit_extrema(case: Case, period: float) -> tuple[float, float]:
    """max|ω̇| and max|ω| over one period, from a dense double run of Euler's equations."""
    data = case.scene("double", [0.0, 1.0], events=False, formulation="none")
    data["output"] = {"times": {"start": 0.0, "stop": period, "count": 4001}}
    res = ch.run(ch.Scene.from_dict(data))
    A, B, C = case.inertia
    p, q, r = (np.asarray(res[k], dtype=float) for k in "pqr")
    dw = np.stack([(B - C) / A * q * r, (C - A) / B * r * p, (A - B) / C * p * q])
    w = np.stack([p, q, r])
    return float(np.max(np.linalg.norm(dw, axis=0))), float(np.max(np.linalg.norm(w, axis=0)))


def law_constants(case: Case) -> LawConstants:
    """Everything the laws need for ``case``."""
    S_T, S_P, period = sensitivities(case)
    w0 = float(np.linalg.norm(case.rates))
    dw_max, w_max = orbit_extrema(case, float(period))
    return LawConstants(
        period=float(period),
        S_T=S_T,
        S_Psi=S_P,
        g=dw_max / w0,
        w_max=w_max,
        w0=w0,
        distance=float(separatrix_distance(case.inertia, case.rates)),
    )
