"""Cayley's 1846 brackets of the free body's elements, their rates under a disturbing function,
and the check of the brackets against J P Jᵀ (the elements and their round-off law:
:mod:`.varying_constants`)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ..core.consistency import CheckReport, CheckRow
from .varying_constants import (
    ELEMENTS,
    CayleyElements,
    column_scales,
    cross_array,
    eye,
    floats,
    row_errors,
    skew,
)

__all__ = ["cayley_brackets", "check_brackets", "element_rates", "poisson_brackets"]


def cayley_brackets(elements: CayleyElements, absolute: bool = False) -> np.ndarray:
    """Cayley's brackets ``(cᵢ, cⱼ)`` of the elements, eq. (61), as a 6×6 antisymmetric array.

    Rows and columns in the order :data:`ELEMENTS`. With ``absolute`` every entry is instead the
    sum of the absolute values of its terms (the scale of its rounding, for error bounds).
    """
    E = elements
    avec = np.array([E.a, E.b, E.c])
    L0 = E.inertia * np.array(E.passage_rates)
    k, V0, ups0, h, Phi0 = E.k, E.V0, E.upsilon0, E.h, E.Phi0
    if absolute:
        avec, L0 = np.abs(avec), np.abs(L0)
        V0, ups0, h, Phi0 = abs(V0), abs(ups0), abs(h), abs(Phi0)
        # (bCr₀ − cBq₀, …) with both products counted positive.
        a_cross_L = np.array([avec[(i + 1) % 3] * L0[(i + 2) % 3] for i in range(3)]) + np.array(
            [avec[(i + 2) % 3] * L0[(i + 1) % 3] for i in range(3)]
        )
        sign = 1
    else:
        a_cross_L = cross_array(avec, L0)  # (bCr₀ − cBq₀, cAp₀ − aCr₀, aBq₀ − bAp₀)
        sign = -1
    zero = 0 * k
    B = np.array([[zero] * 6 for _ in range(6)])
    # (40): (a, b) = −c, (b, c) = −a, (c, a) = −b; the upper triangle holds (a, c) = +b.
    B[0, 1], B[1, 2], B[0, 2] = sign * avec[2], sign * avec[0], (1 if absolute else -sign) * avec[1]
    for i in range(3):
        B[i, 4] = sign * a_cross_L[i] / V0  # (47)
        B[i, 5] = k / (2 * ups0) * (avec[i] + L0[i] + sign * (h + Phi0) / V0 * a_cross_L[i])  # (54)
    B[3, 4] = zero + 2 * sign  # (52)
    B[4, 5] = 4 * sign * k / V0  # (60)
    for i in range(6):
        for j in range(i):
            B[i, j] = B[j, i] if absolute else -B[j, i]
    return B


def element_rates(elements: CayleyElements, dW_dc: Sequence[Any]) -> np.ndarray:
    """The right-hand sides of (62): ``dcᵢ/dt = Σⱼ (cᵢ, cⱼ) ∂W/∂cⱼ``.

    Parameters
    ----------
    elements
        The elements (their passage quantities p₀, q₀, r₀, V₀, Φ₀ enter the brackets).
    dW_dc
        ∂W/∂(a, b, c, h, e, δ), W the force function as a function of the elements and t.

    Returns
    -------
    numpy.ndarray
        ``d(a, b, c, h, e, δ)/dt``. Eq. (63), ``dk/dt``, is ``dW_dc[5]``.
    """
    return cayley_brackets(elements) @ np.asarray(dW_dc)


def poisson_brackets(elements: CayleyElements) -> np.ndarray:
    """``J P Jᵀ``: the brackets of the elements from their Jacobian J in canonical variables.

    P is the canonical Poisson tensor in Cayley's sign (§9.3),
    ``(f, g) = Σ ∂f/∂u ∂g/∂λ − ∂f/∂λ ∂g/∂u``, i.e. ``P = [[0, −I], [I, 0]]`` over
    (λ, μ, ν, u, v, w). Equal to :func:`cayley_brackets` where the elements are right.
    """
    J = elements.jacobian("canonical")
    return J @ _canonical_tensor(J) @ J.T


def _canonical_tensor(like: np.ndarray) -> np.ndarray:
    zero = 0 * like[0, 0]
    P = np.array([[zero] * 6 for _ in range(6)])
    for i in range(3):
        P[i, 3 + i] = zero - 1
        P[3 + i, i] = zero + 1
    return P


def check_brackets(elements: CayleyElements) -> CheckReport:
    """Measure Cayley's brackets (61) against ``J P Jᵀ`` at the state of ``elements``.

    Away from the passage (t ≠ e) this tests the brackets' constancy as well as their values.
    Bound per entry, from the round-off law of
    :func:`.element_check.check_element_equations`: row i of J, its columns scaled by
    (1, 1, 1, |ω|, |ω|, |ω|), errs by ``ηᵢ ρᵢ`` (ρᵢ its largest scaled entry);
    it propagates to ``(J P Jᵀ)ᵢₗ`` through the conversion K to canonical variables,
    and (61) errs by ``max(ηᵢ, ηₗ)`` times the absolute sum of its terms.
    """
    E = elements
    Jc = E.jacobian("canonical")
    P = _canonical_tensor(Jc)
    native_mine, native_cayley = Jc @ P @ Jc.T, cayley_brackets(E)
    mine, cayley = floats(native_mine), floats(native_cayley)
    bound = _bracket_bounds(E)
    ratio = np.abs(floats(native_mine - native_cayley)) / bound
    i, j = np.unravel_index(np.argmax(np.triu(ratio, 1)), ratio.shape)
    rows = [
        CheckRow(
            "(61) vs J P Jᵀ, 15 brackets / law bound",
            float(np.max(np.triu(ratio, 1))),
            1.0,
            f"worst ({ELEMENTS[i]}, {ELEMENTS[j]}): {mine[i, j]:.6e} vs {cayley[i, j]:.6e}; "
            f"t − e = {float(E.t - E.e):.3g}",
        )
    ]
    return CheckReport(
        "Cayley 1846 brackets (61) against J P Jᵀ",
        tuple(rows),
        {"J_P_Jt": mine, "brackets_61": cayley, "bound": bound},
    )


def _bracket_bounds(E: CayleyElements) -> np.ndarray:
    J = floats(E.rotation_jacobian)
    s = column_scales(E)
    eta = row_errors(E)
    rho = np.max(np.abs(J) * s[None, :], axis=1)
    w, v = E.quaternion[0], E.quaternion[1:]
    dphi_drho = 2 * w * w * eye(3, w) - 2 * w * skew(v)
    K = floats(E._canonical_map(dphi_drho))
    Jc = np.abs(floats(E.jacobian("canonical")))
    P = np.abs(floats(_canonical_tensor(E.rotation_jacobian)))
    kappa_cols = np.sum(np.abs(K) / s[:, None], axis=0)  # error of J_can per unit row error
    spread = (kappa_cols[None, :] @ P @ Jc.T)[0]  # (κ|P||J_can|ᵀ)_l
    prop = np.outer(eta * rho, spread)
    Babs = floats(cayley_brackets(E, absolute=True))
    tiny = np.finfo(float).tiny
    return prop + prop.T + np.maximum.outer(eta, eta) * Babs + tiny
