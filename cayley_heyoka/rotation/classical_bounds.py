"""Proved values of Euler's 1758 and Cayley's 1846 forms, from Cayley's 1843 solution in balls.

The three memoirs describe one motion. Euler's quantities (u, v = ω·P, his angle U, the body
components of P, φ + 𝔉) and Cayley's 1846 ones (υ, Ω/k, 2 tan⁻¹(Ω/k), κ, λ, μ, ν, the
quaternion) are explicit functions of the rates and the attitude at t (symbols:
:mod:`.euler1758`, :mod:`.cayley1846`). Evaluated in Arb balls on the proved state of
:func:`.enclosures.enclose`, they carry proved bounds too — an independent route from the
quadratures in Θ that :meth:`Euler1758.at` and :meth:`Cayley1846.at` integrate.

The angles are continuous in t, so each is the value ``a`` of those routes at 10 digits (its
error is far below π) plus the principal argument of ``z e^{−ia}``, where ``z`` is the complex
number whose argument the angle is: that ball lies near the positive real axis, away from the
branch cut, and the sum is exact. Only the whole number of turns comes from the quadrature
route.
"""

from __future__ import annotations

from typing import Any

import mpmath
from flint import arb, ctx

from ..core.balls import Enclosure, ball, bound, exact_mid, to_ball
from ..core.vectors import cross, dot, matvec, transpose
from .attitude import quaternion_to_matrix

__all__ = ["cayley1846_bounds", "euler1758_bounds"]

QUATERNION = ("qw", "qx", "qy", "qz")
#: Digits of the quadrature route that counts the angles' whole turns: its value need only be
#: within π of the angle, and 10 digits cost a fraction of the requested ones.
TURN_DPS = 10


def _companions(solution: Any, coarse: Any, proved: Any) -> tuple[Any, Any]:
    """The coarse quadrature route and the 1843 solution of ``solution``, built once."""
    cached = getattr(solution, "_bounds_companions", None)
    if cached is None:
        cached = (coarse(), proved())
        solution._bounds_companions = cached
    return cached


def _state(body, t: object) -> tuple[list[arb], list[arb], int]:
    """The proved rates and quaternion of the 1843 solution, as balls, and the precision."""
    b = body.enclose(t)
    with ctx.workprec(b.bits):
        rates = [to_ball(b.values[n], b.bounds[n]) for n in "pqr"]
        q = [to_ball(b.values[n], b.bounds[n]) for n in QUATERNION]
    return rates, q, b.bits


def _angle_near(re: arb, im: arb, near: mpmath.mpf) -> arb:
    """arg(re + i im), the determination nearest ``near``: ``near`` plus the principal argument
    of the number turned back by ``near`` (near the positive real axis, off the branch cut)."""
    a = ball(near)
    c, s = a.cos(), a.sin()
    return a + arb.atan2(im * c - re * s, re * c + im * s)


def _enclosure(balls: dict[str, arb], bits: int) -> Enclosure:
    values = {n: exact_mid(x) for n, x in balls.items()}
    bounds = {n: bound(x) for n, x in balls.items()}
    return Enclosure(values, bounds, bits)


def euler1758_bounds(euler: Any, t: object) -> Enclosure:
    """Euler's state at ``t`` with proved bounds: ``p, q, r, u, v, U, cos_l, cos_m, cos_n,
    phi_plus_F`` (the fields of :class:`.euler1758.EulerState`). ``euler`` is an
    :class:`.euler1758.Euler1758` (not imported here: it calls this module)."""
    from .closed_form import FreeRigidBody

    inertia, rates, direction = euler._inputs
    coarse, body = _companions(
        euler,
        lambda: type(euler)(inertia, rates, direction, dps=TURN_DPS),
        # The space frame of the 1843 solution is the body frame at t = 0: P's space
        # components are its body components then, and stay.
        lambda: FreeRigidBody(inertia, rates, attitude=(1, 0, 0, 0), dps=euler.dps),
    )
    estimate = coarse.at(t)  # the angles' whole turns
    w, q, bits = _state(body, t)
    with ctx.workprec(bits):
        I = [ball(x, "inertia") for x in inertia]  # noqa: E741 - the inertia triple
        w0 = [ball(x, "rates") for x in rates]
        P0 = [ball(x, "direction") for x in direction]
        norm = dot(P0, P0).sqrt()
        P0 = [x / norm for x in P0]
        P = matvec(transpose(quaternion_to_matrix(q)), P0)  # Rᵀ P (q is unit: R(q) is R)
        Lb = [I[i] * w[i] for i in range(3)]
        G = dot(Lb, Lb)
        F = dot(Lb, w)
        L0 = [I[i] * w0[i] for i in range(3)]
        D = dot(L0, P0)  # L·P: constant, from t = 0 exactly
        LxP, Lxw = cross(L0, P0), cross(Lb, w)
        f, s = dot(LxP, LxP).sqrt(), dot(Lxw, Lxw).sqrt()
        v = dot(w, P)
        root_G = G.sqrt()
        R_det = dot(P, Lxw)
        U = _angle_near(root_G * R_det, G * v - D * F, estimate.U)
        phi = _angle_near(root_G * s * U.cos(), F * f - D * s * U.sin(), estimate.phi_plus_F)
        # u from the axis whose coefficient is largest: p² = 𝔄 + 2Lu, with L = (B − C)/A …
        coeff = [(I[1] - I[2]) / I[0], (I[2] - I[0]) / I[1], (I[0] - I[1]) / I[2]]
        i = max(range(3), key=lambda k: abs(float(coeff[k].mid())))
        u = (w[i] * w[i] - w0[i] * w0[i]) / (2 * coeff[i])
        balls = dict(zip("pqr", w, strict=True))
        balls.update(u=u, v=v, U=U, phi_plus_F=phi)
        balls.update(zip(("cos_l", "cos_m", "cos_n"), P, strict=True))
        return _enclosure(balls, bits)


def cayley1846_bounds(cayley: Any, t: object) -> Enclosure:
    """Cayley's 1846 state at ``t`` with proved bounds: ``p, q, r, upsilon, omega_over_k,
    angle, kappa, lambda_, mu, nu`` and ``quaternion_w … quaternion_z`` (the fields of
    :class:`.cayley1846.Cayley1846State`). ``cayley`` is a :class:`.cayley1846.Cayley1846`."""
    from .closed_form import FreeRigidBody

    inertia, rates, rodrigues = cayley._inputs
    coarse, body = _companions(
        cayley,
        lambda: type(cayley)(inertia, rates, rodrigues, dps=TURN_DPS),
        lambda: FreeRigidBody(inertia, rates, rodrigues=rodrigues, dps=cayley.dps),
    )
    estimate = coarse.at(t)  # the angle's whole turns
    w, q, bits = _state(body, t)
    with ctx.workprec(bits):
        I = [ball(x, "inertia") for x in inertia]  # noqa: E741 - the inertia triple
        Lb = [I[i] * w[i] for i in range(3)]
        k = dot(Lb, Lb).sqrt()
        a = matvec(quaternion_to_matrix(q), Lb)  # R L_b: the space momentum
        upsilon = (k * k + dot(a, Lb)) / 2
        # tan(angle/2) = Ω/k, Ω = ρ·L_b = (x, y, z)·L_b / w: the angle is arg((k w + i v·L_b)²),
        # whatever the quaternion's sign.
        re, im = k * q[0], dot(q[1:], Lb)
        angle = _angle_near(re * re - im * im, 2 * re * im, estimate.angle)
        half_cos, half_sin = (angle / 2).cos(), (angle / 2).sin()
        balls = dict(zip("pqr", w, strict=True))
        balls.update(upsilon=upsilon, angle=angle, omega_over_k=half_sin / half_cos)
        balls["kappa"] = 1 / (q[0] * q[0])
        balls.update(zip(("lambda_", "mu", "nu"), (c / q[0] for c in q[1:]), strict=True))
        # Cayley's quaternion has w > 0 at t = 0 and is continuous, as the 1843 one is.
        balls.update(
            zip(("quaternion_w", "quaternion_x", "quaternion_y", "quaternion_z"), q, strict=True)
        )
        return _enclosure(balls, bits)
