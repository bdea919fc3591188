"""Torques from force functions: Cayley's formula, the matrix gradient, the closed forms."""

from __future__ import annotations

import heyoka as hy
import numpy as np
import pytest

from cayley_heyoka.core.model import ParTable
from cayley_heyoka.rotation import attitude as att
from cayley_heyoka.rotation import equations as eq
from cayley_heyoka.rotation.forces import ForceContext, GravityGradient, HeavyTop, Potential

INERTIA = [1.0, 1.6, 2.3]


def _cross(a, b):
    return np.array(
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    )


def torques(force, rho_value):
    """Body torque at attitude ``rho_value`` by Cayley's formula and by the matrix gradient."""
    rho = list(hy.make_vars("lambda", "mu", "nu"))
    pars = ParTable()
    inertia = [pars.add(n, v) for n, v in zip("ABC", INERTIA, strict=True)]
    R = att.rodrigues_to_matrix(rho)
    values = force.values(pars.precision)
    V = force.potential(ForceContext(R, rho, inertia, pars, values))
    cayley = eq.cayley_torque(V, rho)

    names = [[hy.expression(f"R{i}{j}__") for j in range(3)] for i in range(3)]
    pars2 = ParTable()
    inertia2 = [pars2.add(n, v) for n, v in zip("ABC", INERTIA, strict=True)]
    V2 = force.potential(ForceContext(names, rho, inertia2, pars2, values))
    gradient = eq.matrix_torque(V2, names, R)

    f = hy.cfunc(cayley + gradient, rho)
    out = f(np.array(rho_value, dtype=float), pars=np.array(pars.values, dtype=float))
    return (
        out[:3],
        out[3:],
        np.array([[float(x) for x in row] for row in att.rodrigues_to_matrix(rho_value)]),
    )


@pytest.mark.parametrize("seed", range(4))
def test_heavy_top_torque_is_c_cross_weight(seed):
    rng = np.random.default_rng(seed)
    rho = list(rng.normal(size=3))
    top = HeavyTop(weight=1.3, center_of_mass=(0.1, -0.05, 0.3), up=(0.0, 0.6, 0.8))
    cayley, gradient, R = torques(top, rho)
    force_body = -1.3 * R.T @ np.array([0.0, 0.6, 0.8])
    expected = _cross(np.array([0.1, -0.05, 0.3]), force_body)
    assert np.allclose(cayley, expected, rtol=0, atol=1e-14)
    assert np.allclose(gradient, expected, rtol=0, atol=1e-14)


@pytest.mark.parametrize("seed", range(4))
def test_gravity_gradient_torque(seed):
    rng = np.random.default_rng(seed)
    rho = list(rng.normal(size=3))
    gg = GravityGradient(gm=2.0, distance=1.5, direction=(0.0, 0.6, -0.8))
    cayley, gradient, R = torques(gg, rho)
    ub = R.T @ np.array([0.0, 0.6, -0.8])
    expected = 3 * 2.0 / 1.5**3 * _cross(ub, np.array(INERTIA) * ub)
    assert np.allclose(cayley, expected, rtol=0, atol=1e-13)
    assert np.allclose(gradient, expected, rtol=0, atol=1e-13)


def test_user_potential_in_cosines_equals_heavy_top():
    rho = [0.3, -0.7, 0.2]
    user = Potential.parse({"V": "-1.3 * (0.1 * R31 - 0.05 * R32 + 0.3 * R33)"}, "forces.potential")
    top = HeavyTop(weight=1.3, center_of_mass=(0.1, -0.05, 0.3))
    a, b, _ = torques(user, rho)
    c, _, _ = torques(top, rho)
    assert np.allclose(a, c, rtol=0, atol=1e-14) and np.allclose(b, c, rtol=0, atol=1e-14)
