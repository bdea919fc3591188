"""Conversions between attitude representations and Cayley's composition (1843, §1-§2)."""

from __future__ import annotations

import mpmath
import numpy as np
import pytest

from cayley_heyoka.rotation import attitude as att

mpmath.mp.dps = 40
TOL = mpmath.mpf(10) ** -36


def random_rodrigues(rng, scale=1.0):
    return [mpmath.mpf(float(x)) for x in rng.normal(scale=scale, size=3)]


def axis_angle_matrix(n, theta):
    """Cayley's trigonometric table (1843, §1): an independent route to R."""
    cf, cg, ch = n
    c, s = mpmath.cos(theta), mpmath.sin(theta)
    return [
        [cf**2 + (1 - cf**2) * c, cg * cf * (1 - c) - ch * s, ch * cf * (1 - c) + cg * s],
        [cf * cg * (1 - c) + ch * s, cg**2 + (1 - cg**2) * c, ch * cg * (1 - c) - cf * s],
        [cf * ch * (1 - c) - cg * s, cg * ch * (1 - c) + cf * s, ch**2 + (1 - ch**2) * c],
    ]


def maxdiff(a, b):
    return max(abs(x - y) for ra, rb in zip(a, b, strict=True) for x, y in zip(ra, rb, strict=True))


@pytest.mark.parametrize("seed", range(5))
def test_rodrigues_matrix_matches_axis_angle_table(seed):
    rng = np.random.default_rng(seed)
    n = [mpmath.mpf(float(x)) for x in rng.normal(size=3)]
    norm = mpmath.sqrt(sum(x * x for x in n))
    n = [x / norm for x in n]
    theta = mpmath.mpf(float(rng.uniform(-3, 3)))
    rho = [mpmath.tan(theta / 2) * x for x in n]
    assert maxdiff(att.rodrigues_to_matrix(rho), axis_angle_matrix(n, theta)) < TOL


@pytest.mark.parametrize("seed", range(5))
def test_round_trips(seed):
    rng = np.random.default_rng(seed)
    rho = random_rodrigues(rng, scale=2.0)
    R = att.rodrigues_to_matrix(rho)
    q = att.rodrigues_to_quaternion(rho)
    assert maxdiff(att.quaternion_to_matrix(q), R) < TOL
    assert max(abs(a - b) for a, b in zip(att.matrix_to_rodrigues(R), rho, strict=True)) < TOL
    assert max(abs(a - b) for a, b in zip(att.quaternion_to_rodrigues(q), rho, strict=True)) < TOL
    q2 = att.matrix_to_quaternion(R)
    assert max(abs(a - b) for a, b in zip(q2, q, strict=True)) < TOL
    RtR = att.matmul(att.transpose(R), R)
    assert maxdiff(RtR, [[1 if i == j else 0 for j in range(3)] for i in range(3)]) < TOL


def test_matrix_to_quaternion_is_regular_at_a_half_turn():
    n = [mpmath.mpf(2) / 3, mpmath.mpf(-1) / 3, mpmath.mpf(2) / 3]
    R = axis_angle_matrix(n, mpmath.pi)
    q = att.matrix_to_quaternion(R)
    assert abs(q[0]) < TOL
    assert maxdiff(att.quaternion_to_matrix(q), R) < TOL
    with pytest.raises(ZeroDivisionError, match="half-turn"):
        att.matrix_to_rodrigues(
            [[float(x) for x in row] for row in [[1, 0, 0], [0, -1, 0], [0, 0, -1]]]
        )


@pytest.mark.parametrize("seed", range(5))
def test_composition_is_the_matrix_product(seed):
    rng = np.random.default_rng(seed)
    outer, inner = random_rodrigues(rng), random_rodrigues(rng)
    composed = att.compose_rodrigues(outer, inner)
    product = att.matmul(att.rodrigues_to_matrix(outer), att.rodrigues_to_matrix(inner))
    assert maxdiff(att.rodrigues_to_matrix(composed), product) < TOL
    # the order matters: R(inner) R(outer) is another rotation
    other = att.matmul(att.rodrigues_to_matrix(inner), att.rodrigues_to_matrix(outer))
    assert maxdiff(att.rodrigues_to_matrix(composed), other) > 1e-3
    # and it is the vector over the scalar part of the quaternion product
    qp = att.quaternion_multiply(
        att.rodrigues_to_quaternion(outer), att.rodrigues_to_quaternion(inner)
    )
    assert max(abs(qp[i + 1] / qp[0] - composed[i]) for i in range(3)) < TOL


def test_kappa_identity_of_the_composition():
    # κ = k k₁ / Π² (Cayley 1843, §2)
    rng = np.random.default_rng(7)
    a, b = random_rodrigues(rng), random_rodrigues(rng)
    big_pi = 1 - sum(x * y for x, y in zip(a, b, strict=True))
    assert (
        abs(att.kappa(att.compose_rodrigues(a, b)) - att.kappa(a) * att.kappa(b) / big_pi**2)
        < TOL * 1e3
    )
