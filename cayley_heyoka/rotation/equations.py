"""Euler's equations, the kinematics of the attitude, and torques from a force function.

Symbols (Cayley 1843, "On the motion of rotation of a solid body": the kinematics, the forced
motion and the integrals of the free motion; docs/scenes.md, "Conventions"):

* ``A, B, C`` — principal moments of inertia; ``p, q, r`` — body-frame angular velocity.
* ``λ, μ, ν`` — Cayley–Rodrigues parameters, ``κ = 1 + λ² + μ² + ν²``; ``w, x, y, z`` — quaternion.
* ``V`` — the *force function* (work function), minus the potential energy; the conserved
  energy is ``T − V`` with ``T = ½(Ap² + Bq² + Cr²)``.
* ``N`` — the body-frame torque. Cayley's formula gives it from ``∂V/∂λ, ∂V/∂μ, ∂V/∂ν``:
  ``N = ½ Mᵀ ∇V`` with ``M = I + [ρ]× + ρρᵀ``.

Every function returns heyoka expressions (or lists of them) built from the arguments, like
``heyoka.model``: a user can take them and build an integrator directly.
"""

from __future__ import annotations

from collections.abc import Sequence
from fractions import Fraction

import heyoka as hy

from .attitude import Matrix, quaternion_multiply

Expr = hy.expression


def euler_rates(
    differences: Sequence[Expr],
    rates: Sequence[Expr],
    inertia: Sequence[Expr],
    torque: Sequence[Expr] | None = None,
) -> list[Expr]:
    """Right-hand sides of Euler's equations ``A ṗ = (B − C) q r + N₁`` and cyclically.

    ``differences`` are ``(B − C, C − A, A − B)`` (computed once from the moments, exactly,
    then rounded in the target precision) and ``inertia`` ``(A, B, C)``: each rate's
    derivative is ``((B − C) q r + N₁) / A``, the division done in the compiled code.

    Not ``((B − C)/A) q r`` with the quotient rounded once: that is cheaper (a product instead
    of a division in every Taylor order) but its rounded constant makes the round-off of
    ``T`` and ``|L|²`` lean one way step after step. On the generic body of
    validation/rotation_cases.py (moments 1, 2, 3: the quotient −1/3 is rounded) 84–91 % of
    the energy and |L|² drift over 10⁷ steps was shared by every member of an ensemble 1e-9
    apart — a drift faster than Brouwer's √N — against 1–11 % (independent walks) with the
    division (issue 20; validation/DRIFT_BIAS.md, ``python validation/drift_bias.py``).
    """
    p, q, r = rates
    # The difference multiplies the product of the two rates, not one rate first: near a
    # symmetric body r hardly changes, and (C − A)·r would round the same way at every step
    # (a product of two nearly fixed numbers), a drift every run shares (issue 20; 3.7–13 ε√N
    # at 3·10⁶ steps for A − B = 2⁻²⁶, against a random walk once reordered).
    products = [differences[0] * (q * r), differences[1] * (r * p), differences[2] * (p * q)]
    if torque is not None:
        products = [products[i] + torque[i] for i in range(3)]
    return [products[i] / inertia[i] for i in range(3)]


def euler_differences(A: Fraction, B: Fraction, C: Fraction) -> tuple[Fraction, ...]:
    """``(B − C, C − A, A − B)``, exactly."""
    return (B - C, C - A, A - B)


def rodrigues_kinematics(rho: Sequence[Expr], rates: Sequence[Expr]) -> list[Expr]:
    """Cayley's kinematic equations ``2λ′ = (1 + λ²) p + (λμ − ν) q + (νλ + μ) r`` etc."""
    lam, mu, nu = rho
    p, q, r = rates
    return [
        0.5 * ((1 + lam * lam) * p + (lam * mu - nu) * q + (nu * lam + mu) * r),
        0.5 * ((lam * mu + nu) * p + (1 + mu * mu) * q + (mu * nu - lam) * r),
        0.5 * ((nu * lam - mu) * p + (mu * nu + lam) * q + (1 + nu * nu) * r),
    ]


def quaternion_kinematics(quat: Sequence[Expr], rates: Sequence[Expr]) -> list[Expr]:
    """``q̇ = ½ q ⊗ (0, ω)`` with ω in body axes."""
    return [0.5 * e for e in quaternion_multiply(quat, [0, *rates])]


def cayley_torque(potential: Expr, rho: Sequence[Expr]) -> list[Expr]:
    """Body torque from the force function by Cayley's formula (1843, §4).

    ``N₁ = ½{(1 + λ²) V_λ + (λμ + ν) V_μ + (νλ − μ) V_ν}``,
    ``N₂ = ½{(λμ − ν) V_λ + (1 + μ²) V_μ + (μν + λ) V_ν}``,
    ``N₃ = ½{(νλ + μ) V_λ + (μν − λ) V_μ + (1 + ν²) V_ν}``, the partials taken symbolically.
    """
    lam, mu, nu = rho
    Vl, Vm, Vn = (hy.diff(potential, v) for v in rho)
    return [
        0.5 * ((1 + lam * lam) * Vl + (lam * mu + nu) * Vm + (nu * lam - mu) * Vn),
        0.5 * ((lam * mu - nu) * Vl + (1 + mu * mu) * Vm + (mu * nu + lam) * Vn),
        0.5 * ((nu * lam + mu) * Vl + (mu * nu - lam) * Vm + (1 + nu * nu) * Vn),
    ]


def matrix_torque(
    potential: Expr, placeholders: Matrix, R: Matrix, scaled: tuple[Matrix, Expr] | None = None
) -> list[Expr]:
    """Body torque from a force function of the direction cosines.

    ``potential`` is V written in the nine variables ``placeholders`` standing for the entries
    of ``R``. A virtual body rotation ``δR = R [δφ]×`` changes V by ``δφ · N``, so
    ``N = Σᵢ (∂V/∂Rᵢ.) × Rᵢ.`` over the rows of the gradient and of ``R``. This needs no chart
    and is regular at every attitude: it is the quaternion formulation's route to the torque
    and an independent check of Cayley's formula.

    ``scaled = (F, s)`` states ``R = F / s`` (the quaternion's ``R(q)/|q|²``): the crosses then
    take ``F``'s rows and the sum is divided once, three divisions instead of nine (a gradient
    that does not depend on R, as a uniform field's, needs no other).
    """
    subs = {str(placeholders[i][j]): R[i][j] for i in range(3) for j in range(3)}
    grad = [
        [hy.subs(hy.diff(potential, placeholders[i][j]), subs) for j in range(3)] for i in range(3)
    ]
    rows = scaled[0] if scaled else R
    torque = [0, 0, 0]
    for i in range(3):
        gx, gy, gz = grad[i]
        rx, ry, rz = rows[i]
        torque = [
            torque[0] + gy * rz - gz * ry,
            torque[1] + gz * rx - gx * rz,
            torque[2] + gx * ry - gy * rx,
        ]
    return [n / scaled[1] for n in torque] if scaled else torque


def kinetic_energy(inertia: Sequence[Expr], rates: Sequence[Expr]) -> Expr:
    """``T = ½(Ap² + Bq² + Cr²)``."""
    A, B, C = inertia
    p, q, r = rates
    return 0.5 * (A * p * p + B * q * q + C * r * r)


def body_momentum(inertia: Sequence[Expr], rates: Sequence[Expr]) -> list[Expr]:
    """Angular momentum in body axes, ``(Ap, Bq, Cr)``."""
    return [inertia[i] * rates[i] for i in range(3)]
