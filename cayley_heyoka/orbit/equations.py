"""Cayley's 1860 equations of disturbed motion in the osculating orbit plane.

Symbols (Cayley 1860; docs/orbits.md; frames in :mod:`.frames`): r the radius, ṙ its rate, ρ the
departure of the body (angle in the orbit plane from the departure point x₂), h = r²ρ̇ the
angular momentum per unit mass, Θ, Σ, Φ the node longitude, node departure and inclination of
the orbit plane on the reference plane, u = ρ − Σ the argument of latitude. The reference
plane is placed in the fixed frame by θ′, σ′, φ′ (prescribed functions of time);
A, B, C are the components of its angular velocity along the orbit's node line N̂,
ẑ₁ × N̂ and ẑ₁ (§4).

The system (§6.3, with the plane equations in the reduced form of §6.4, free of the
cancelling cot Φ terms of the printed form)::

    dr/dt = ṙ,          dṙ/dt = h²/r³ − μ/r² + ∂Ω/∂r,
    dρ/dt = h/r²,       dh/dt = ∂Ω/∂ρ,
    dΘ/dt = sin u Ω_β/(h sin Φ) − cot Φ B − C,
    dΣ/dt = cos Φ sin u Ω_β/(h sin Φ) − cosec Φ B,
    dΦ/dt = cos u Ω_β/h − A,

with ``Ω_β = ∂Ω/∂β`` at zero latitude. The partials come from ``g = ∇Ω`` (symbolic, by
heyoka) through the frame tables (§7): ``∂Ω/∂r = x̂₃·g``, ``∂Ω/∂ρ = r ŷ₃·g``,
``Ω_β = r n̂·g``.

The regular alternative (§10) carries the departure-point frame of the orbit as a unit
quaternion q relative to the fixed frame: ``q̇ = ½ q ⊗ (0, w)`` with
``w = (Ω_β/h)(cos ρ, sin ρ, 0)``; no cosec Φ, no reference plane in the equations.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import heyoka as hy

from ..core import vectors
from ..mechanics import frames
from .disturbing import Gradient
from .tilt import on_reference

Expr = hy.expression
_ZERO = hy.expression(0.0)


@dataclass
class ReferencePlane:
    """θ′, σ′, φ′ of the reference plane as expressions of time, and their rates.

    A rate is None where it is identically zero, so that its terms are not compiled.
    """

    theta: Expr
    sigma: Expr
    phi: Expr
    theta_rate: Expr | None
    sigma_rate: Expr | None
    phi_rate: Expr | None
    departure_point: bool

    def matrix(self) -> frames.Matrix:
        """``M₀₁``: frame 1 in frame 0."""
        return frames.plane_matrix(self.theta, self.sigma, self.phi)

    def rates_on_node(self, Theta: Expr) -> tuple[Expr | None, Expr | None, Expr | None]:
        """A, B, C (§4), each None where it vanishes identically (C: x₁ a departure point)."""
        d = Theta - self.sigma
        A, B, C = [], [], []
        if self.theta_rate is not None:
            sp = hy.sin(self.phi)
            A.append(hy.sin(d) * sp * self.theta_rate)
            B.append(hy.cos(d) * sp * self.theta_rate)
        if self.phi_rate is not None:
            A.append(hy.cos(d) * self.phi_rate)
            B.append(-hy.sin(d) * self.phi_rate)
        if not self.departure_point:
            if self.theta_rate is not None:
                C.append(hy.cos(self.phi) * self.theta_rate)
            if self.sigma_rate is not None:
                C.append(-self.sigma_rate)
        return tuple(_total(terms) if terms else None for terms in (A, B, C))


@dataclass
class OrbitAxes:
    """Unit vectors of the body frame in frame 0: x̂₃ (radial), ŷ₃ (transverse), n̂ (normal)."""

    radial: list[Expr]
    transverse: list[Expr]
    normal: list[Expr]


def cayley_axes(
    Theta: Expr,
    Phi: Expr,
    u: Expr,
    plane: ReferencePlane | None,
    tilt: tuple[Expr, Expr] | None = None,
) -> tuple[OrbitAxes, frames.Matrix | None]:
    """The body frame from the angles (§5), mapped to frame 0 when the plane moves; with
    ``tilt`` = (cos β, sin β), the angles are on the working frame ``R₁(β)`` of frame 1
    (:mod:`.tilt`)."""
    x3, y3, n = frames.orbit_axes(Theta, Phi, u)
    if tilt is not None:
        x3, y3, n = (on_reference(v, *tilt) for v in (x3, y3, n))
    if plane is None:
        return OrbitAxes(x3, y3, n), None
    M01 = plane.matrix()
    return OrbitAxes(*(vectors.matvec(M01, v) for v in (x3, y3, n))), M01


def quaternion_matrix(q: Sequence[Expr]) -> frames.Matrix:
    """``ℛ(q)``: the table of the frame with unit quaternion q = (q₀, q₁, q₂, q₃)."""
    w, x, y, z = q
    return [
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ]


def quaternion_axes(q: Sequence[Expr], rho: Expr) -> OrbitAxes:
    """x̂₃, ŷ₃, n̂ in frame 0 from the orbit-frame quaternion and the departure ρ."""
    R = quaternion_matrix(q)
    c, s = hy.cos(rho), hy.sin(rho)
    radial = [c * R[i][0] + s * R[i][1] for i in range(3)]
    transverse = [c * R[i][1] - s * R[i][0] for i in range(3)]
    return OrbitAxes(radial, transverse, [R[0][2], R[1][2], R[2][2]])


def in_plane_rates(
    r: Expr, rdot: Expr, h: Expr, mu: Expr, Omega_r: Expr | None, Omega_rho: Expr | None
) -> list[Expr]:
    """dr/dt, dṙ/dt, dρ/dt, dh/dt (§6.3; the radial sign is the corrected one, OCR item 3)."""
    r2 = r * r
    # h²/r³ as h·h/(r²·r), not ρ̇²·r (ρ̇ = h/r² shared, two operations fewer) nor with 1/r²
    # taken once: over 10⁸ steps of Kepler those made the energy walk 3× farther, with a
    # windows slope of 0.63–0.68 (validation/bench_conservation.py), where this form walks
    # by Brouwer's law.
    radial = h * h / (r2 * r) - mu / r2
    if Omega_r is not None:
        radial = radial + Omega_r
    return [rdot, radial, h / r2, Omega_rho if Omega_rho is not None else _ZERO]


def plane_rates(
    u: Expr,
    h: Expr,
    Phi: Expr,
    Omega_beta: Expr | None,
    plane: ReferencePlane | None,
    Theta: Expr,
    tilt: tuple[Expr, Expr] | None = None,
) -> list[Expr]:
    """dΘ/dt, dΣ/dt, dΦ/dt in the reduced form (§6.4), with only the terms present; with
    ``tilt``, of the angles on the working frame ``R₁(β)`` (:func:`cayley_axes`), which turns
    with the reference plane."""
    sP, cP = hy.sin(Phi), hy.cos(Phi)
    dTheta, dSigma, dPhi = [], [], []
    A = B = C = None
    if plane is not None:
        A, B, C = plane.rates_on_node(Theta)
        if tilt is not None and any(w is not None for w in (A, B, C)):
            # Frame 1's angular velocity on its own axes is (A, B, C) at Θ = 0; on W, R₁(β)ᵀ
            # of it, taken along W's node line.
            w = [_ZERO if v is None else v for v in plane.rates_on_node(_ZERO)]
            c, s = tilt
            wy, wz = c * w[1] + s * w[2], c * w[2] - s * w[1]
            cT, sT = hy.cos(Theta), hy.sin(Theta)
            A, B, C = w[0] * cT + wy * sT, wy * cT - w[0] * sT, wz
    # One quotient each (heyoka writes a product by 1/sin Φ as a quotient, so a reciprocal
    # would not be shared): Ω_β/(h sin Φ), the orbit frame's angular velocity about x̂₃ over
    # sin Φ, and B/sin Φ.
    if Omega_beta is not None:
        lift = Omega_beta / (h * sP)
        dTheta.append(hy.sin(u) * lift)
        dSigma.append(cP * dTheta[0])
        # cos u Ω_β/h as sin Φ cos u times it: a product ∂Ω/∂ρ = r ŷ₃·∇Ω already holds
        # (ŷ₃'s third entry on frame 1), instead of a quotient by h of its own.
        dPhi.append(sP * hy.cos(u) * lift)
    if B is not None:
        over = B / sP
        dTheta.append(-cP * over)
        dSigma.append(-over)
    if A is not None:
        dPhi.append(-A)
    if C is not None:
        dTheta.append(-C)
    return [_total(terms) for terms in (dTheta, dSigma, dPhi)]


def quaternion_rates(q: Sequence[Expr], rho: Expr, h: Expr, Omega_beta: Expr | None) -> list[Expr]:
    """q̇ = ½ q ⊗ (0, w), w = (Ω_β/h)(cos ρ, sin ρ, 0): the orbit frame turns about x̂₃ only."""
    if Omega_beta is None:
        return [_ZERO] * 4
    w0, x, y, z = q
    k = Omega_beta / (2 * h)
    wx, wy = k * hy.cos(rho), k * hy.sin(rho)
    # Hamilton product with a pure quaternion (wx, wy, 0).
    return [-(x * wx + y * wy), w0 * wx - z * wy, w0 * wy + z * wx, x * wy - y * wx]


def cayley_partials(g: Gradient, r: Expr, axes: OrbitAxes) -> tuple[Expr, Expr, Expr]:
    """∂Ω/∂r, ∂Ω/∂ρ and Ω_β from the Cartesian gradient at r x̂₃ (§7).

    ``g`` is ∇Ω at r x̂₃ (:func:`.disturbing.force` with the radius given), which carries
    ∂Ω/∂r (``g.radial``); its part along x̂₃ does not enter ∂Ω/∂ρ and Ω_β, ŷ₃ and n̂ being
    perpendicular to it.
    """
    vector = [g.component(i) for i in range(3)]
    if g.radial is not None:
        Omega_r = _total(g.radial) if g.radial else None
    else:
        Omega_r = _sparse_dot(axes.radial, vector)
        if g.central:
            along = _total(g.central)
            Omega_r = -along if Omega_r is None else Omega_r - along
    if sum(c is not None for c in vector) == 1:
        # One component (a zonal field about a coordinate axis): r times it once, not twice.
        scaled = [None if c is None else r * c for c in vector]
        rho, beta = _sparse_dot(axes.transverse, scaled), _sparse_dot(axes.normal, scaled)
    else:
        rho, beta = _sparse_dot(axes.transverse, vector), _sparse_dot(axes.normal, vector)
        rho = None if rho is None else r * rho
        beta = None if beta is None else r * beta
    return tuple(c if c is not None else _ZERO for c in (Omega_r, rho, beta))


def cartesian_rates(
    x: Sequence[Expr], v: Sequence[Expr], mu: Expr, g: Gradient | None
) -> list[Expr]:
    """ẋ = v, v̇ = −(μ/r³ + c) x + g for ∇Ω = −c x + g: the part of ∇Ω along x joins the
    Kepler term, so that x is multiplied once."""
    r2 = vectors.dot(x, x)
    central = [mu * r2**-1.5, *(g.central if g is not None else [])]
    k = -_total(central)
    acc = [k * xi for xi in x]
    if g is not None:
        for i in range(3):
            gi = g.component(i)
            if gi is not None:
                acc[i] = acc[i] + gi
    return [*v, *acc]


def _sparse_dot(a: Sequence[Expr], b: Sequence[Expr | None]) -> Expr | None:
    """a · b over the components of b that are not None (None if all are)."""
    terms = [ai * bi for ai, bi in zip(a, b, strict=True) if bi is not None]
    return _total(terms) if terms else None


def _total(terms: list[Expr]) -> Expr:
    if not terms:
        return _ZERO
    return terms[0] if len(terms) == 1 else hy.sum(terms)
