"""Cayley's 1846 elements of the rotating body, and the equations of their variation.

From Cayley (1846), "On the rotation of a solid body round a fixed point", eqs. (1)–(63)
(docs/rotation_elements.md). Symbols of the memoir, used below:

* ``A, B, C`` principal moments; ``ω = (p, q, r)`` body rates; ``L_b = (Ap, Bq, Cr)``.
* ``ρ = (λ, μ, ν)`` — the Cayley–Rodrigues parameters of the attitude; ``R(ρ)`` (eq. (6)) maps
  body components to space components; ``κ = 1 + λ² + μ² + ν²``.
* ``a, b, c`` — space components ``R L_b`` of the angular momentum, ``k² = a² + b² + c²``;
  ``h = Ap² + Bq² + Cr²`` (twice the kinetic energy).
* ``Ω = ρ·L_b``, ``υ = (k² + aAp + bBq + cCr)/2`` (eqs. (9), (12)); ``Φ = a·ω`` and
  ``V = det[(a, b, c), L_b, ω]`` (15). Along the free motion ``dυ/dt = V/2`` (19) and the angle
  ``α = 2 tan⁻¹(Ω/k)`` turns at ``dα/dt = k(h + Φ)/(2υ)`` (§7), smooth through θ = π.
* ``W`` — the force function (forces = +grad W), the scene's ``V`` of :mod:`.forces`; the memoir
  writes it V too, which here always means eq. (15).

**The six elements** (§9.2) of any state, forced or not, are those of the free motion through it:
``a, b, c, h`` algebraically; ``e`` the time at which that free motion passes ``υ = υ₀`` (one
definite passage, followed continuously) and ``δ`` the value of ``α`` there. ``υ₀`` is a fixed
number, not an element; at a turning value of υ (``V₀ = 0``) the elements are singular.
:func:`cayley_elements` finds the passage by integrating the free motion with heyoka (a terminal
event on ``υ − υ₀``) together with its variational equations, which give the gradient of e and δ
with respect to the state through the event-time derivative ``∂τ/∂y = −(dg/dy)/ġ``.

The free motion needs no attitude: υ, Φ and dα/dt depend on the body rates and the constant
``(a, b, c)`` only. It is integrated in ``(p, q, r, α)`` with ``A, B, C, a, b, c, υ₀`` as runtime
parameters (one compiled integrator per precision); the attitude enters only through
``(a, b, c)`` and the starting value of α.

**The equations of the elements** (§9.3–9.4): ``dcᵢ/dt = Σⱼ (cᵢ, cⱼ) ∂W/∂cⱼ`` with Cayley's
brackets (61), which :func:`.brackets.cayley_brackets` writes out and
:func:`.brackets.element_rates` applies (eq. (62)); eq. (63) is ``dk/dt = ∂W/∂δ``.
:func:`.element_check.check_element_equations` measures them against the elements' actual rates
along a forced run, and :func:`.brackets.check_brackets` (61) against ``J P Jᵀ`` (J the Jacobian
of the elements in Cayley's canonical variables, P the canonical Poisson tensor in his sign).
Gradients are taken internally with respect to a body-frame rotation ``δR = R[δφ]×`` rather than
``δρ``: regular at every attitude, including θ = π, where λ, μ, ν are infinite (``dφ = (2/κ)(I −
[ρ]×) dρ`` converts)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import heyoka as hy
import mpmath
import numpy as np

from ..core.outcomes import Ended
from ..core.precision import Precision
from ..core.vectors import cross, dot
from . import attitude as att

__all__ = [
    "ELEMENTS",
    "TURNING_MARGIN",
    "CayleyElements",
    "cayley_elements",
    "upsilon_range",
]

#: Names of the elements, in the order of every vector and matrix of this module.
ELEMENTS = ("a", "b", "c", "h", "e", "delta")

#: Smallest accepted ``|V₀| / (k |L_b| |ω|)`` at the passage: below it υ₀ counts as a turning
#: value. The brackets (47), (54), (60) divide by V₀, so the elements e, δ lose about
#: log₁₀(1/margin) digits; at 1e-6 a double computation keeps about 10.
TURNING_MARGIN = 1e-6

#: The factor of the round-off law (as in the validation's ``10 ε √n``).
SAFETY = 10.0

# Search windows in periods of the rates: the passages of υ₀ are less than one period apart.
_WINDOW = 1.05
_HALF_WINDOW = 0.55


# ---------------------------------------------------------------------- small vector helpers
def cross_array(x: Any, y: Any) -> np.ndarray:
    """x × y as an array, for the numpy arithmetic it enters."""
    return np.array(cross(x, y))


def skew(x: Any) -> np.ndarray:
    """``[x]×``: ``[x]× y = x × y``."""
    zero = 0 * x[0]
    return np.array([[zero, -x[2], x[1]], [x[2], zero, -x[0]], [-x[1], x[0], zero]])


def eye(n: int, like: Any) -> np.ndarray:
    one, zero = 0 * like + 1, 0 * like
    return np.array([[one if i == j else zero for j in range(n)] for i in range(n)])


def solve(M: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """``M x = rhs`` in M's number type (numpy's LAPACK for double, elimination otherwise)."""
    if M.dtype == np.float64:
        return np.linalg.solve(M, rhs)
    n = len(M)
    A = np.array(M, copy=True)
    x = np.array(rhs, copy=True)
    for col in range(n):
        pivot = max(range(col, n), key=lambda i: abs(A[i, col]))
        if A[pivot, col] == 0:
            raise np.linalg.LinAlgError("singular matrix")
        A[[col, pivot]] = A[[pivot, col]]
        x[[col, pivot]] = x[[pivot, col]]
        for i in range(col + 1, n):
            f = A[i, col] / A[col, col]
            A[i, col:] = A[i, col:] - f * A[col, col:]
            x[i] = x[i] - f * x[col]
    for i in range(n - 1, -1, -1):
        x[i] = (x[i] - np.dot(A[i, i + 1 :], x[i + 1 :])) / A[i, i]
    return x


def floats(x: Any) -> np.ndarray:
    return np.array([float(v) for v in np.ravel(x)]).reshape(np.shape(x))


def _precision(precision: Precision | str | dict) -> Precision:
    return precision if isinstance(precision, Precision) else Precision.from_spec(precision)


# ---------------------------------------------------------------------- the free motion
class _FreeFlow:
    """The free motion in ``(p, q, r, α)`` with its variational equations, compiled once.

    Parameters (runtime): ``A, B, C, a, b, c, υ₀``. Sensitivities: with respect to the initial
    ``p, q, r, α`` and the parameters ``a, b, c`` (the ``y`` of :func:`cayley_elements`). The
    terminal event ``υ − υ₀`` stops the integrator exactly at each passage.
    """

    def __init__(self, prec: Precision) -> None:
        p, q, r, alpha = hy.make_vars("p", "q", "r", "alpha")
        A, B, C = hy.par[0], hy.par[1], hy.par[2]
        a = [hy.par[3], hy.par[4], hy.par[5]]
        L = [A * p, B * q, C * r]
        k2 = dot(a, a)
        upsilon = (k2 + dot(a, L)) / 2
        h = dot(L, [p, q, r])
        Phi = dot(a, [p, q, r])
        system = [
            (p, (B - C) / A * q * r),
            (q, (C - A) / B * r * p),
            (r, (A - B) / C * p * q),
            (alpha, hy.sqrt(k2) * (h + Phi) / (2 * upsilon)),
        ]
        variational = hy.var_ode_sys(system, [p, q, r, alpha, *a], order=1)
        kw = prec.heyoka_kwargs
        ev_kw = {"fp_type": kw["fp_type"]} if kw else {}
        zero = prec.number(0)
        # Compact mode: 6.7 s → 0.3 s of compilation for about twice the (small) step cost.
        self.ta = hy.taylor_adaptive(
            variational,
            np.array([zero] * 4),
            pars=np.array([zero] * 7),
            t_events=[hy.t_event(upsilon - hy.par[6], **ev_kw)],
            compact_mode=True,
            **kw,
        )
        self.start = np.array(self.ta.state, copy=True)  # the variational part is the identity
        self.prec = prec

    def reset(self, z0: np.ndarray, pars: np.ndarray) -> None:
        ta = self.ta
        ta.time = self.prec.number(0)
        state = np.array(self.start, copy=True)
        state[:4] = z0
        ta.state[:] = state
        ta.pars[:] = pars
        ta.reset_cooldowns()

    def next_passage(self, limit: Any) -> tuple[Any | None, int]:
        """Propagate towards ``limit``; the time of the passage reached, or None, and steps."""
        ended = Ended.of(self.ta.propagate_until(limit))
        if ended.outcome == hy.taylor_outcome.time_limit:
            return None, ended.steps
        if int(ended.outcome) == -1:
            return self.ta.time, ended.steps
        raise RuntimeError(f"free motion: integration stopped with outcome {ended.outcome}")

    def snapshot(self) -> tuple[Any, np.ndarray]:
        return self.ta.time, np.array(self.ta.state, copy=True)


_FLOWS: dict[str, _FreeFlow] = {}


def _flow(prec: Precision) -> _FreeFlow:
    if prec.name not in _FLOWS:
        _FLOWS[prec.name] = _FreeFlow(prec)
    return _FLOWS[prec.name]


def free_period(inertia: np.ndarray, rates: np.ndarray) -> float:
    """The period of (p, q, r) in the free motion, 4K(m)/n (a search window: double is enough)."""
    I = [float(x) for x in inertia]  # noqa: E741
    w = [float(x) for x in rates]
    order = sorted(range(3), key=lambda i: I[i])
    I1, I2, I3 = (I[i] for i in order)
    h = sum(I[i] * w[i] ** 2 for i in range(3))
    k2 = sum((I[i] * w[i]) ** 2 for i in range(3))
    product = I1 * I2 * I3
    if k2 >= I2 * h:
        n2 = (I3 - I2) * (k2 - I1 * h) / product
        m_num, m_den = (I2 - I1) * (I3 * h - k2), (I3 - I2) * (k2 - I1 * h)
    else:
        n2 = (I2 - I1) * (I3 * h - k2) / product
        m_num, m_den = (I3 - I2) * (k2 - I1 * h), (I2 - I1) * (I3 * h - k2)
    scale = max(abs(I1 * h), k2)
    if n2 <= 1e-14 * scale * max(I1, I2, I3) / product or (m_den != 0 and m_num >= m_den):
        raise ValueError(
            "rates: υ does not oscillate along this free motion (a steady rotation about a "
            "principal axis, a spherical body, or the separatrix); it has no passages"
        )
    m = m_num / m_den if m_den != 0 else 0.0
    with mpmath.workdps(20):
        return float(4 * mpmath.ellipk(m) / mpmath.sqrt(n2))


# ---------------------------------------------------------------------- the elements
@dataclass(frozen=True)
class CayleyElements:
    """Cayley's six elements of one state (§9.2), with what the brackets (61) need.

    Attributes
    ----------
    a, b, c, h, e, delta
        The elements, in the precision of the computation. ``delta`` is continued from
        ``near``'s when one was given (it is defined mod 2π).
    t
        The time of the state.
    upsilon0
        The fixed value υ₀ whose passage defines e and δ.
    k
        |(a, b, c)|.
    passage_rates
        (p₀, q₀, r₀): the body rates of the free motion at the passage.
    V0, Phi0
        V and Φ (eq. (15)) at the passage.
    alpha
        2 tan⁻¹(Ω/k) at the state, the value the free motion's α starts from.
    quaternion, rates, inertia
        The state (attitude as a unit quaternion (w, x, y, z), body rates) and the moments.
    steps
        Steps of the free motion from the state to the passage (the round-off law's n).
    period
        Period of (p, q, r) in the free motion (for the passage search).
    precision
        The arithmetic of the computation.
    """

    a: Any
    b: Any
    c: Any
    h: Any
    e: Any
    delta: Any
    t: Any
    upsilon0: Any
    k: Any
    passage_rates: tuple[Any, Any, Any]
    V0: Any
    Phi0: Any
    alpha: Any
    quaternion: np.ndarray = field(repr=False)
    rates: np.ndarray = field(repr=False)
    inertia: np.ndarray = field(repr=False)
    steps: int = 0
    period: float = math.nan
    precision: Precision = field(default_factory=Precision, repr=False)
    rotation_jacobian: np.ndarray = field(default=None, repr=False)

    @property
    def values(self) -> np.ndarray:
        """``(a, b, c, h, e, δ)``."""
        return np.array([self.a, self.b, self.c, self.h, self.e, self.delta])

    @property
    def turning_margin(self) -> float:
        """``|V₀| / (k |L_b| |ω|)`` at the passage: 0 at a turning value of υ, at most 1."""
        L0 = self.inertia * np.array(self.passage_rates)
        w0 = np.array(self.passage_rates)
        scale = float(self.k) * math.sqrt(float(dot(L0, L0)) * float(dot(w0, w0)))
        return abs(float(self.V0)) / scale

    @property
    def error_bounds(self) -> np.ndarray:
        """The round-off law's bound on the error of each element (floats; see
        :func:`.element_check.check_element_equations`): as under a state error of relative size ηᵢ,
        ``ηᵢ(6ρᵢ + |cᵢ|)``."""
        J = floats(self.rotation_jacobian)
        rho = np.max(np.abs(J) * column_scales(self)[None, :], axis=1)
        return row_errors(self) * (6 * rho + np.abs(floats(self.values)))

    def jacobian(self, coordinates: str = "rodrigues") -> np.ndarray:
        """∂(a, b, c, h, e, δ)/∂x at fixed t, a 6×6 array (rows: the elements).

        Parameters
        ----------
        coordinates
            ``"rodrigues"``: x = (λ, μ, ν, p, q, r); ``"canonical"``: x = (λ, μ, ν, u, v, w),
            the momenta of eq. (29); ``"rotation"``: x = (φ₁, φ₂, φ₃, p, q, r) with the body
            rotation ``δR = R[δφ]×`` (regular at every attitude).

        Notes
        -----
        e also depends on t explicitly: ``∂e/∂t = 1`` (e = t + the time to the passage).
        """
        J = self.rotation_jacobian
        if coordinates == "rotation":
            return J.copy()
        w, v = self.quaternion[0], self.quaternion[1:]
        if w == 0:
            raise ZeroDivisionError(
                "the attitude is a half-turn: its Cayley-Rodrigues parameters are infinite; "
                "use coordinates='rotation'"
            )
        # dφ = (2/κ)(I − [ρ]×) dρ with ρ = v/w, κ = 1/w².
        dphi_drho = 2 * w * w * eye(3, w) - 2 * w * skew(v)
        if coordinates == "rodrigues":
            out = J.copy()
            out[:, :3] = J[:, :3] @ dphi_drho
            return out
        if coordinates == "canonical":
            return J @ self._canonical_map(dphi_drho)
        raise ValueError(
            f"coordinates: must be 'rodrigues', 'canonical' or 'rotation', got {coordinates!r}"
        )

    def canonical_state(self) -> np.ndarray:
        """(λ, μ, ν, u, v, w) of the state, eq. (29): ``(u, v, w) = (2/κ)(L_b + ρ × L_b)``."""
        w, v = self.quaternion[0], self.quaternion[1:]
        rho = v / w
        L = self.inertia * self.rates
        momenta = 2 * w * w * (L + cross_array(rho, L))
        return np.concatenate([rho, momenta])

    def _canonical_map(self, dphi_drho: np.ndarray) -> np.ndarray:
        """∂(φ, ω)/∂(ρ, u⃗): 2L_b = (I − [ρ]× + ρρᵀ) u⃗ (eq. (30))."""
        x = self.canonical_state()
        rho, u = x[:3], x[3:]
        one = eye(3, rho[0])
        outer = np.array([[rho[i] * u[j] for j in range(3)] for i in range(3)])
        dL_drho = (skew(u) + dot(rho, u) * one + outer) / 2
        rr = np.array([[rho[i] * rho[j] for j in range(3)] for i in range(3)])
        dL_du = (one - skew(rho) + rr) / 2
        inv = np.array([1 / m for m in self.inertia])
        K = np.empty((6, 6), dtype=dphi_drho.dtype)
        K[:3, :3] = dphi_drho
        K[:3, 3:] = 0 * dphi_drho
        K[3:, :3] = inv[:, None] * dL_drho
        K[3:, 3:] = inv[:, None] * dL_du
        return K


def _quaternion_of(rodrigues: Any, quaternion: Any, prec: Precision) -> np.ndarray:
    if (rodrigues is None) == (quaternion is None):
        raise ValueError("rodrigues: give the attitude once, as rodrigues or as quaternion")
    if rodrigues is not None:
        rho = prec.array(rodrigues)
        if len(rho) != 3:
            raise ValueError(f"rodrigues: needs 3 numbers, got {len(rho)}")
        return np.array(att.rodrigues_to_quaternion(list(rho)))
    quat = prec.array(quaternion)
    if len(quat) != 4:
        raise ValueError(f"quaternion: needs 4 numbers (w, x, y, z), got {len(quat)}")
    norm = np.sqrt(dot(quat[1:], quat[1:]) + quat[0] * quat[0])
    if not float(norm) > 0:
        raise ValueError("quaternion: must not be zero")
    return quat / norm


def _state(inertia: Any, rates: Any, rodrigues: Any, quaternion: Any, prec: Precision):
    I = prec.array(inertia)  # noqa: E741
    w = prec.array(rates)
    if len(I) != 3 or not all(float(x) > 0 for x in I):
        raise ValueError(f"inertia: needs three positive moments, got {list(inertia)}")
    if len(w) != 3:
        raise ValueError(f"rates: needs 3 numbers, got {len(w)}")
    if float(dot(w, w)) == 0:
        raise ValueError("rates: the body is at rest; its elements are undefined")
    return I, w, _quaternion_of(rodrigues, quaternion, prec)


def _alpha_and_gradient(quat: np.ndarray, inertia: np.ndarray, rates: np.ndarray):
    """α = 2 tan⁻¹(Ω/k) from the quaternion (regular at θ = π), and ∂α/∂(φ, ω)."""
    w, v = quat[0], quat[1:]
    L = inertia * rates
    k = np.sqrt(dot(L, L))
    vL = dot(v, L)
    alpha = 2 * np.arctan2(vL, w * k)
    denominator = w * w * k * k + vL * vL
    d_phi = k * (w * w * L - w * cross_array(v, L) + vL * v) / denominator
    d_rates = 2 * w * (k * v - vL * L / k) * inertia / denominator
    return alpha, np.concatenate([d_phi, d_rates])


def cayley_elements(
    inertia: Sequence[Any],
    rates: Sequence[Any],
    rodrigues: Sequence[Any] | None,
    t: Any,
    upsilon0: Any,
    *,
    quaternion: Sequence[Any] | None = None,
    near: float | CayleyElements | None = None,
    precision: Precision | str | dict = "double",
) -> CayleyElements:
    """Cayley's elements (a, b, c, h, e, δ) of a state, with their Jacobian (§9.2).

    Parameters
    ----------
    inertia
        Principal moments (A, B, C).
    rates
        Body rates (p, q, r) of the state.
    rodrigues
        (λ, μ, ν) of the attitude (body → space, eq. (6)); or None and ``quaternion``.
    t
        Time of the state.
    upsilon0
        The fixed υ₀ whose passage defines e and δ; inside the range of υ over the free motion
        through the state and not a turning value (see :func:`upsilon_range`).
    quaternion
        The attitude as a unit quaternion (w, x, y, z) instead of ``rodrigues``; regular at
        θ = π.
    near
        A previous e (or previous elements): the passage nearest to it is taken, so that a run
        follows one passage; previous elements also continue δ across 2π. Without it, the
        latest passage at or before t is taken, or the next one if none lies within a period.
    precision
        ``"double"``, ``"quad"`` or ``{"bits": N}``: the arithmetic of the free motion.

    Returns
    -------
    CayleyElements

    Raises
    ------
    ValueError
        For bad input (the message names the parameter), a υ₀ that the free motion never
        passes, or a υ₀ at a turning value (margin below :data:`TURNING_MARGIN`).
    """
    prec = _precision(precision)
    I, w, quat = _state(inertia, rates, rodrigues, quaternion, prec)  # noqa: E741
    t, ups0 = prec.number(t), prec.number(upsilon0)
    L = I * w
    R = np.array(att.quaternion_to_matrix(list(quat)))
    a_vec = R @ L
    k = np.sqrt(dot(a_vec, a_vec))
    h = dot(L, w)
    alpha0, d_alpha = _alpha_and_gradient(quat, I, w)
    period = free_period(I, w)

    flow = _flow(prec)
    z0 = np.array([w[0], w[1], w[2], alpha0])
    pars = np.array([I[0], I[1], I[2], a_vec[0], a_vec[1], a_vec[2], ups0])
    near_e = near.e if isinstance(near, CayleyElements) else near
    tau, state, steps = _find_passage(flow, z0, pars, near_e, t, period, prec)

    # At the passage: the state z* = (ω*, α*) and S = ∂z*/∂y, y = (p, q, r, α, a, b, c).
    w0 = state[:3]
    alpha_p = state[3]
    S = np.array([state[flow.ta.get_vslice(order=1, component=i)] for i in range(4)])
    L0 = I * w0
    wdot0 = cross_array(L0, w0) / I
    V0 = dot(a_vec, cross_array(L0, w0))
    Phi0 = dot(a_vec, w0)
    h0 = dot(L0, w0)
    ups = (k * k + dot(a_vec, L0)) / 2
    alpha_rate = k * (h0 + Phi0) / (2 * ups)
    # g = (k² + a·L_b)/2 − υ₀ with k² = a·a: its gradient in z* and its explicit a-dependence.
    g_z = np.concatenate([a_vec * I / 2, [0 * k]])
    g_a = a_vec + L0 / 2
    g_dot = V0 / 2
    margin = abs(float(V0)) / (float(k) * math.sqrt(float(dot(L0, L0)) * float(dot(w0, w0))))
    if margin < TURNING_MARGIN:
        raise ValueError(
            f"upsilon0: {float(ups0):.17g} is a turning value of υ for this motion "
            f"(|V₀|/(k|L||ω|) = {margin:.2e} < {TURNING_MARGIN:g}): the brackets (47), (54), "
            "(60) divide by V₀; choose a value inside the range of υ"
        )
    # One Newton step absorbs the event's residual g(z*) ≈ ε.
    shift = -((k * k + dot(a_vec, L0)) / 2 - ups0) / g_dot
    tau, alpha_p, w0 = tau + shift, alpha_p + alpha_rate * shift, w0 + wdot0 * shift
    L0 = I * w0
    dg_dy = g_z @ S
    dg_dy[4:] = dg_dy[4:] + g_a
    dtau_dy = -dg_dy / g_dot
    dalpha_dy = S[3] + alpha_rate * dtau_dy

    # y = (p, q, r, α₀, a, b, c) as functions of x = (φ, ω).
    Y = np.empty((7, 6), dtype=S.dtype)
    Y[:3, :3] = 0 * S[:3, :3]
    Y[:3, 3:] = eye(3, k)
    Y[3] = d_alpha
    da_dphi = -R @ skew(L)
    da_drates = R * I[None, :]
    Y[4:, :3] = da_dphi
    Y[4:, 3:] = da_drates
    J = np.empty((6, 6), dtype=S.dtype)
    J[:3, :3], J[:3, 3:] = da_dphi, da_drates
    J[3, :3], J[3, 3:] = 0 * L, 2 * L
    J[4] = dtau_dy @ Y
    J[5] = dalpha_dy @ Y

    delta = alpha_p
    if isinstance(near, CayleyElements):
        with mpmath.workdps(prec.dps + 10):
            two_pi = prec.number(mpmath.nstr(2 * mpmath.pi, prec.dps + 5))
        turns = round(float((near.delta - delta) / two_pi))
        delta = delta + turns * two_pi
    return CayleyElements(
        a=a_vec[0],
        b=a_vec[1],
        c=a_vec[2],
        h=h,
        e=t + tau,
        delta=delta,
        t=t,
        upsilon0=ups0,
        k=k,
        passage_rates=(w0[0], w0[1], w0[2]),
        V0=dot(a_vec, cross_array(L0, w0)),
        Phi0=dot(a_vec, w0),
        alpha=alpha0,
        quaternion=quat,
        rates=w,
        inertia=I,
        steps=steps,
        period=period,
        precision=prec,
        rotation_jacobian=J,
    )


def _find_passage(flow: _FreeFlow, z0, pars, near_e, t, period: float, prec: Precision):
    """(τ, full state at the passage, steps to it), the passage chosen as documented in
    :func:`cayley_elements`."""

    def walk(direction: int, limit: float, until: float) -> list[tuple[Any, np.ndarray, int]]:
        """Passages from τ = 0 towards ``limit``, up to the first one at or beyond ``until``."""
        flow.reset(z0, pars)
        found, steps = [], 0
        while True:
            hit, n = flow.next_passage(prec.number(limit))
            steps += n
            if hit is None:
                return found
            found.append((*flow.snapshot(), steps))
            if direction * (float(hit) - until) >= 0:
                return found

    if near_e is None:
        found = walk(-1, -_WINDOW * period, 0.0)
        if not found:
            found = walk(1, _WINDOW * period, 0.0)
    else:
        # Passages are less than a period apart: one lies within half a period of any time.
        target = float(near_e - t)
        direction = 1 if target > 0 else -1
        reach = _HALF_WINDOW * period
        found = walk(direction, target + direction * reach, target)
        behind = target - direction * reach
        if direction * behind < 0 and not any(
            direction * (float(x[0]) - target) < 0 for x in found
        ):
            found += walk(-direction, behind, 0.0)
        found = [x for x in found if abs(float(x[0]) - target) <= reach]
        found = sorted(found, key=lambda x: abs(float(x[0]) - target))[:1]
    if not found:
        lo, hi = _upsilon_range_of(z0, pars, period, prec)
        ups0 = pars[6]
        if min(abs(float(ups0 - lo)), abs(float(ups0 - hi))) <= 1e-9 * float(hi):
            raise ValueError(
                f"upsilon0: {float(ups0):.17g} is a turning value of υ for this motion (its "
                f"{'least' if abs(float(ups0 - lo)) < abs(float(ups0 - hi)) else 'greatest'} "
                "value, where V₀ = 0): the brackets (47), (54), (60) divide by V₀; choose a "
                f"value inside ({float(lo):.17g}, {float(hi):.17g})"
            )
        where = "" if near_e is None else f" within half a period of e = {float(near_e):.17g}"
        raise ValueError(
            f"upsilon0: the free motion through this state never passes υ₀ = "
            f"{float(ups0):.17g}{where}; υ ranges over [{float(lo):.17g}, {float(hi):.17g}]"
        )
    tau, state, steps = found[0]
    return tau, state, steps


class _TurningFlow:
    """The free rates with an event on V = det[a, L_b, ω]: the turning instants of υ."""

    def __init__(self, prec: Precision) -> None:
        p, q, r = hy.make_vars("p", "q", "r")
        A, B, C = hy.par[0], hy.par[1], hy.par[2]
        a = [hy.par[3], hy.par[4], hy.par[5]]
        L = [A * p, B * q, C * r]
        system = [(p, (B - C) / A * q * r), (q, (C - A) / B * r * p), (r, (A - B) / C * p * q)]
        kw = prec.heyoka_kwargs
        ev_kw = {"fp_type": kw["fp_type"]} if kw else {}
        self.values: list[Any] = []

        def record(ta: Any, t: Any, d_sgn: int) -> None:
            ta.update_d_output(t)
            rates = ta.d_output[:3]
            Lt = np.array(ta.pars[:3]) * rates
            a_vec = np.array(ta.pars[3:6])
            self.values.append((dot(a_vec, a_vec) + dot(a_vec, Lt)) / 2)

        zero = prec.number(0)
        self.ta = hy.taylor_adaptive(
            system,
            np.array([zero] * 3),
            pars=np.array([zero] * 6),
            nt_events=[hy.nt_event(dot(a, cross_array(L, [p, q, r])), record, **ev_kw)],
            compact_mode=True,
            **kw,
        )
        self.prec = prec

    def turning_values(self, rates: np.ndarray, pars: np.ndarray, period: float) -> list[Any]:
        ta = self.ta
        ta.time = self.prec.number(0)
        ta.state[:] = rates
        ta.pars[:] = pars
        ta.reset_cooldowns()
        self.values = []
        ta.propagate_until(self.prec.number(_WINDOW * period))
        return sorted(self.values)


_TURNING: dict[str, _TurningFlow] = {}


def _upsilon_range_of(z0, pars, period: float, prec: Precision) -> tuple[Any, Any]:
    """Least and greatest υ over a period of the free motion: its extreme turning values."""
    if prec.name not in _TURNING:
        _TURNING[prec.name] = _TurningFlow(prec)
    values = _TURNING[prec.name].turning_values(np.array(z0[:3]), np.array(pars[:6]), period)
    if not values:
        raise ValueError("rates: υ has no turning value along this free motion; it is constant")
    return values[0], values[-1]


def upsilon_range(
    inertia: Sequence[Any],
    rates: Sequence[Any],
    rodrigues: Sequence[Any] | None = None,
    *,
    quaternion: Sequence[Any] | None = None,
    precision: Precision | str | dict = "double",
) -> tuple[Any, Any]:
    """The least and greatest υ over the free motion through a state.

    They are turning values of υ (V = 0), located by heyoka's event detection over a period
    of the rates; υ₀ must lie strictly between them, away from every turning value.
    """
    prec = _precision(precision)
    I, w, quat = _state(inertia, rates, rodrigues, quaternion, prec)  # noqa: E741
    a_vec = np.array(att.quaternion_to_matrix(list(quat))) @ (I * w)
    pars = np.array([I[0], I[1], I[2], a_vec[0], a_vec[1], a_vec[2]])
    return _upsilon_range_of(w, pars, free_period(I, w), prec)


# ---------------------------------------------------------------------- the round-off law
def row_errors(E: CayleyElements) -> np.ndarray:
    """η: relative error level of each element's row of the Jacobian (see the check's law)."""
    eps = E.precision.epsilon
    integrated = SAFETY * eps * (1 + E.steps) / E.turning_margin
    return np.array([SAFETY * eps] * 4 + [integrated] * 2)


def column_scales(E: CayleyElements) -> np.ndarray:
    wn = math.sqrt(float(dot(E.rates, E.rates)))
    return np.array([1.0, 1.0, 1.0, wn, wn, wn])
