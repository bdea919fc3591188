"""Attitude representations and Cayley's composition of rotations (Cayley 1843, §1–§2).

Symbols, as in the memoir (Cayley 1843, "On the motion of rotation of a solid body";
docs/scenes.md, "Conventions"):

* ``R`` — the direction-cosine matrix, ``R[i][j] = cos(space axis i, body axis j)``: row = space,
  column = body, ``v_space = R v_body``. Cayley names its entries α β γ / α′ β′ γ′ / α″ β″ γ″.
* ``(λ, μ, ν) = tan(θ/2) n`` — the Cayley–Rodrigues parameters of the rotation by θ about the
  unit axis n carrying the space triad into the body triad; ``κ = 1 + λ² + μ² + ν² = sec²(θ/2)``.
* ``(w, x, y, z)`` — the Hamilton unit quaternion, ``w = cos(θ/2)``, ``(x, y, z) = sin(θ/2) n``,
  so ``(λ, μ, ν) = (x, y, z)/w`` and ``κ = 1/w²``.

The functions use only arithmetic (and a square root where unavoidable), so the same code
serves floats, numpy arrays of any heyoka floating type, mpmath numbers and heyoka
expressions: the symbolic equations and the numerical checks share one formula.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

Matrix = list[list[Any]]


def _sqrt(x: Any) -> Any:
    import heyoka as hy

    if isinstance(x, hy.expression):
        return hy.sqrt(x)
    if type(x).__module__.startswith("mpmath"):
        import mpmath

        return mpmath.sqrt(x)
    return np.sqrt(x)


def kappa(rho: Sequence[Any]) -> Any:
    """``κ = 1 + λ² + μ² + ν²``."""
    lam, mu, nu = rho
    return 1 + lam * lam + mu * mu + nu * nu


def rodrigues_kappa_matrix(rho: Sequence[Any]) -> Matrix:
    """``κ R`` as polynomials in (λ, μ, ν) (Cayley 1843, §1): no division, regular everywhere."""
    lam, mu, nu = rho
    l2, m2, n2 = lam * lam, mu * mu, nu * nu
    return [
        [1 + l2 - m2 - n2, 2 * (lam * mu - nu), 2 * (nu * lam + mu)],
        [2 * (lam * mu + nu), 1 + m2 - n2 - l2, 2 * (mu * nu - lam)],
        [2 * (nu * lam - mu), 2 * (mu * nu + lam), 1 + n2 - l2 - m2],
    ]


def rodrigues_to_matrix(rho: Sequence[Any]) -> Matrix:
    """Direction cosines from the Cayley–Rodrigues parameters."""
    k = kappa(rho)
    return [[e / k for e in row] for row in rodrigues_kappa_matrix(rho)]


def quaternion_to_matrix(q: Sequence[Any]) -> Matrix:
    """Direction cosines from a unit Hamilton quaternion (w, x, y, z).

    The unit norm is assumed, not imposed: for a quaternion of norm n, this is n² times the
    rotation's matrix (the quaternion formulation divides by |q|² where it needs the rotation).
    """
    w, x, y, z = q
    ww, xx, yy, zz = w * w, x * x, y * y, z * z
    return [
        [ww + xx - yy - zz, 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), ww - xx + yy - zz, 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), ww - xx - yy + zz],
    ]


def quaternion_rotation(q: Sequence[Any]) -> tuple[Matrix, Any]:
    """The rotation a quaternion of any norm stands for, ``R(q)/|q|²``, and ``|q|²``.

    ``q`` and ``c q`` (c > 0) are one attitude. An integrated quaternion, or one normalised
    only to a rounding, is not unit: reading this matrix keeps its norm out of what is physical.
    """
    squares = [c * c for c in q]
    if _is_symbolic(q[0]):
        import heyoka as hy

        norm2 = hy.sum(squares)  # one n-ary sum, as the compiled systems were measured with
    else:
        norm2 = sum(squares)
    return [[e / norm2 for e in row] for row in quaternion_to_matrix(q)], norm2


def rodrigues_to_quaternion(rho: Sequence[Any]) -> list[Any]:
    """The unit quaternion with ``w > 0`` of the rotation (λ, μ, ν)."""
    s = _sqrt(kappa(rho))
    return [1 / s, rho[0] / s, rho[1] / s, rho[2] / s]


def quaternion_to_rodrigues(q: Sequence[Any]) -> list[Any]:
    """(λ, μ, ν) = (x, y, z)/w; infinite for a half-turn (w = 0)."""
    w, x, y, z = q
    if not _is_symbolic(w) and w == 0:
        raise ZeroDivisionError(
            "the rotation is a half-turn (w = 0): its Cayley-Rodrigues parameters are infinite"
        )
    return [x / w, y / w, z / w]


def quaternion_multiply(a: Sequence[Any], b: Sequence[Any]) -> list[Any]:
    """Hamilton product ``a ⊗ b``."""
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return [
        aw * bw - ax * bx - ay * by - az * bz,
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
    ]


def compose_rodrigues(outer: Sequence[Any], inner: Sequence[Any]) -> list[Any]:
    """Cayley's composition: parameters of ``R(outer) R(inner)`` (Cayley 1843, §2).

    With ``outer = (l, m, n)`` (frame M relative to space) and ``inner = (l₁, m₁, n₁)`` (body
    relative to M): ``Π = 1 − l l₁ − m m₁ − n n₁`` and
    ``Π λ = l + l₁ + m n₁ − n m₁``, ``Π μ = m + m₁ + n l₁ − l n₁``, ``Π ν = n + n₁ + l m₁ − m l₁``.
    """
    l, m, n = outer
    l1, m1, n1 = inner
    big_pi = 1 - l * l1 - m * m1 - n * n1
    if not _is_symbolic(big_pi) and big_pi == 0:
        raise ZeroDivisionError("the composed rotation is a half-turn (Π = 0); use quaternions")
    return [
        (l + l1 + m * n1 - n * m1) / big_pi,
        (m + m1 + n * l1 - l * n1) / big_pi,
        (n + n1 + l * m1 - m * l1) / big_pi,
    ]


def matrix_to_quaternion(R: Sequence[Sequence[Any]]) -> list[Any]:
    """Unit quaternion (w ≥ 0) of a rotation matrix by the largest-pivot rule (regular at θ = π)."""
    a, b, c = R[0]
    a1, b1, c1 = R[1]
    a2, b2, c2 = R[2]
    trace = a + b1 + c2
    cands = [trace, a - b1 - c2, b1 - a - c2, c2 - a - b1]
    k = max(range(4), key=lambda i: cands[i])
    s = 2 * _sqrt(1 + cands[k])  # s = 4 × (the pivot component)
    if k == 0:
        q = [s / 4, (b2 - c1) / s, (c - a2) / s, (a1 - b) / s]
    elif k == 1:
        q = [(b2 - c1) / s, s / 4, (a1 + b) / s, (c + a2) / s]
    elif k == 2:
        q = [(c - a2) / s, (a1 + b) / s, s / 4, (c1 + b2) / s]
    else:
        q = [(a1 - b) / s, (c + a2) / s, (c1 + b2) / s, s / 4]
    if q[0] < 0:
        q = [-e for e in q]
    return q


def matrix_to_rodrigues(R: Sequence[Sequence[Any]]) -> list[Any]:
    """Cayley's inverse formulas.

    ``υ = 1 + tr R``, ``λυ = β″ − γ′``, ``μυ = γ − α″``, ``νυ = α′ − β``.
    """
    upsilon = 1 + R[0][0] + R[1][1] + R[2][2]
    if upsilon == 0:
        raise ZeroDivisionError(
            "the rotation is a half-turn (1 + trace = 0): its Cayley-Rodrigues parameters are "
            "infinite"
        )
    return [
        (R[2][1] - R[1][2]) / upsilon,
        (R[0][2] - R[2][0]) / upsilon,
        (R[1][0] - R[0][1]) / upsilon,
    ]


def matmul(a: Matrix, b: Matrix) -> Matrix:
    """Product of two 3×3 nested lists (works on expressions too)."""
    return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def transpose(a: Matrix) -> Matrix:
    """Transpose of a 3×3 nested list."""
    return [[a[j][i] for j in range(3)] for i in range(3)]


def matvec(a: Matrix, v: Sequence[Any]) -> list[Any]:
    """``a v`` for a 3×3 nested list and a 3-vector."""
    return [sum(a[i][k] * v[k] for k in range(3)) for i in range(3)]


def _is_symbolic(x: Any) -> bool:
    import heyoka as hy

    return isinstance(x, hy.expression)
