"""The disturbing functions against independent statements of them (numpy, textbook forms)."""

from __future__ import annotations

import heyoka as hy
import mpmath
import numpy as np
import pytest
from numpy.polynomial import legendre

from cayley_heyoka.core.model import ParTable
from cayley_heyoka.core.precision import Precision
from cayley_heyoka.orbit.disturbing import Context, ThirdBody, Zonal, gradient

MU = 1.3
X = np.array([[0.9, 0.2, 0.1], [-0.3, 1.1, -0.6], [0.05, -0.4, 1.7]])


def evaluate(term, t=0.0, with_gradient=False):
    """Ω (and ∇Ω) of one term at the points X, through heyoka's compiled functions."""
    pars = ParTable()
    mu = pars.add("mu", str(MU))
    x = list(hy.make_vars("x", "y", "z"))
    omega = term.omega(x, Context(mu, pars))
    exprs = [omega, *gradient(omega, x)] if with_gradient else [omega]
    cf = hy.cfunc(exprs, x)
    values = np.array([float(v) for v in pars.values])
    return np.array([cf(p, pars=values, time=t) for p in X])


@pytest.mark.parametrize("axis", [(0, 0, 1), (0, 0, -2), (0.1, -0.2, 1.0)])
def test_zonal_harmonics_are_minus_mu_jn_rn_pn_over_r_n_plus_1(axis):
    coefficients = ((2, "1.0826e-3"), (3, "-2.5e-6"), (4, "-1.6e-6"), (7, "3e-7"))
    term = Zonal(coefficients, "0.8", tuple(str(c) for c in axis))
    k = np.array(axis, dtype=float) / np.linalg.norm(axis)
    r = np.linalg.norm(X, axis=1)
    expected = np.zeros(len(X))
    for n, J in coefficients:
        Pn = legendre.legval(X @ k / r, [0] * n + [1])
        expected += -MU * float(J) * 0.8**n * Pn / r ** (n + 1)
    np.testing.assert_allclose(evaluate(term)[:, 0], expected, rtol=1e-13)


def test_j2_gradient_is_the_closed_form():
    """∇Ω_J2 = (3μJ₂R²/2r⁵)[(5s²/r² − 1)x − 2s k̂] (Cayley 1860; docs/orbits.md)."""
    k = np.array([0.1, -0.2, 1.0]) / np.linalg.norm([0.1, -0.2, 1.0])
    term = Zonal(((2, "1e-3"),), "0.6", ("0.1", "-0.2", "1"))
    got = evaluate(term, with_gradient=True)[:, 1:]
    for p, g in zip(X, got, strict=True):
        r, s = np.linalg.norm(p), p @ k
        expected = 1.5 * MU * 1e-3 * 0.36 / r**5 * ((5 * s * s / r**2 - 1) * p - 2 * s * k)
        np.testing.assert_allclose(g, expected, rtol=1e-13, atol=1e-18)


def third_body_position(t, a, n, e, i, node, w, M0):
    """Textbook Kepler orbit: E by Newton, then R₃(node) R₁(i) R₃(ω) (a(cos E − e), b sin E)."""
    M = M0 + n * t
    E = M
    for _ in range(50):
        E -= (E - e * np.sin(E) - M) / (1 - e * np.cos(E))
    p = np.array([a * (np.cos(E) - e), a * np.sqrt(1 - e * e) * np.sin(E), 0.0])

    def rz(x):
        return np.array([[np.cos(x), -np.sin(x), 0], [np.sin(x), np.cos(x), 0], [0, 0, 1]])

    rx = np.array([[1, 0, 0], [0, np.cos(i), -np.sin(i)], [0, np.sin(i), np.cos(i)]])
    return rz(node) @ rx @ rz(w) @ p


@pytest.mark.parametrize("e", ["0", "0.3"])
def test_third_body_direct_plus_indirect_part(e):
    orbit = {"a": "3.5", "n": "0.15", "inclination": "0.4", "node": "-0.3"}
    orbit |= {"argument_of_pericentre": "0.7", "mean_anomaly0": "2.0", "eccentricity": e}
    term = ThirdBody.parse({"gm": "0.005", **orbit}, "third_body")
    t = 7.5
    x3 = third_body_position(
        t,
        *(float(orbit[k]) for k in ("a", "n", "eccentricity")),
        *(
            float(orbit[k])
            for k in ("inclination", "node", "argument_of_pericentre", "mean_anomaly0")
        ),
    )
    got = evaluate(term, t=t, with_gradient=True)
    for p, row in zip(X, got, strict=True):
        d = x3 - p
        omega = 0.005 * (1 / np.linalg.norm(d) - p @ x3 / np.linalg.norm(x3) ** 3)
        grad = 0.005 * (d / np.linalg.norm(d) ** 3 - x3 / np.linalg.norm(x3) ** 3)
        np.testing.assert_allclose(row[0], omega, rtol=1e-13)
        np.testing.assert_allclose(row[1:], grad, rtol=1e-12, atol=1e-17)


def test_third_body_legendre_series_converges_to_the_exact_function():
    """Σ_{l=2..N}: the remainder falls like (r/r₃)^(N+1) (here r/r₃ ≤ 0.53).

    The series leaves out l = 0, the constant Gm₃/r₃ (no force); l = 1 cancels the indirect part.
    """
    body = {"gm": "0.005", "a": "3.5", "n": "0.15", "inclination": "0.4", "node": "-0.3"}
    exact = evaluate(ThirdBody.parse(body, "tb"), t=1.0)[:, 0] - 0.005 / 3.5
    previous = np.inf
    for degree in (2, 4, 8, 16):
        series = evaluate(ThirdBody.parse({**body, "degree": degree}, "tb"), t=1.0)[:, 0]
        error = np.max(np.abs(series - exact))
        assert error < 0.005 / 3.5 * 0.53 ** (degree + 1) / (1 - 0.53)  # |Pₗ| ≤ 1
        assert error < previous
        previous = error


def test_zonal_and_series_carry_no_double_constant_into_quad():
    """In real128 the J_n terms and the perturber's series agree with mpmath to ~1e-32.

    Every literal of heyoka's equations is a double: a coefficient like 1/3 in the Legendre
    recurrence would cap a quad run at ~1e-17 relative. Reference: mpmath's Legendre functions
    at 40 digits.
    """
    prec = Precision("quad")
    point = ["0.9", "0.2", "-0.35"]
    pars = ParTable()
    mu = pars.add("mu", "1.3")
    x = list(hy.make_vars("x", "y", "z"))
    coefficients = ((2, "1.0826e-3"), (3, "-2.5e-6"), (5, "-2.3e-7"), (7, "3e-7"))
    zonal = Zonal(coefficients, "0.8", ("0.1", "-0.2", "1"))
    body = ThirdBody.parse({"gm": "0.005", "a": "3.5", "n": "0", "degree": 9}, "tb")
    ctx = Context(mu, pars, dps=50)
    exprs = [zonal.omega(x, ctx), body.omega(x, ctx)]
    cf = hy.cfunc(exprs, x, fp_type=hy.real128)
    got = cf(prec.array(point), pars=prec.array(pars.values), time=prec.number(0))
    with mpmath.workdps(40):
        p = [mpmath.mpf(c) for c in point]
        r = mpmath.norm(p)
        k = [mpmath.mpf(c) for c in ("0.1", "-0.2", "1")]
        cos_k = sum(a * b for a, b in zip(k, p, strict=True)) / (r * mpmath.norm(k))
        expected_zonal = sum(
            -mpmath.mpf("1.3")
            * mpmath.mpf(J)
            * mpmath.mpf("0.8") ** n
            * mpmath.legendre(n, cos_k)
            / r ** (n + 1)
            for n, J in coefficients
        )
        r3 = mpmath.mpf("3.5")  # at t = 0 with node = 0, i = 0: x₃ = (a, 0, 0)
        cos_3 = p[0] / r
        expected_series = sum(
            mpmath.mpf("0.005") / r3 * (r / r3) ** l * mpmath.legendre(l, cos_3)
            for l in range(2, 10)
        )
        for value, expected in zip(got, (expected_zonal, expected_series), strict=True):
            assert abs(mpmath.mpf(str(value)) / expected - 1) < 1e-31


@pytest.mark.parametrize("axis", [(0, 0, 1), (0, -3, 0), (0.1, -0.2, 1.0)])
@pytest.mark.parametrize("on_sphere", [False, True])
def test_closed_form_zonal_gradient_is_the_symbolic_one(axis, on_sphere):
    """The closed form the equations compile (one power of r per term; :meth:`Zonal.gradient`),
    in Cartesian form and on the unit sphere with ∂Ω/∂r apart (Cayley's), against heyoka's
    derivative of Ω, degrees 2 to 12 with gaps."""
    coefficients = ((2, "1.0826e-3"), (3, "-2.5e-6"), (4, "-1.6e-6"), (7, "3e-7"), (12, "2e-8"))
    term = Zonal(coefficients, "0.8", tuple(str(c) for c in axis))
    pars = ParTable()
    mu = pars.add("mu", str(MU))
    ctx = Context(mu, pars)
    x = list(hy.make_vars("x", "y", "z"))
    omega = term.omega(x, ctx)
    if on_sphere:
        # ∂Ω/∂r given apart; the vector part counts only across x̂:
        # ∇Ω = x̂ ∂Ω/∂r + g − x̂ (x̂·g).
        r = hy.sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2])
        unit = [c / r for c in x]
        g = term.gradient(unit, None, ctx, radius=r)
        vec = [g.component(i) if g.component(i) is not None else 0.0 for i in range(3)]
        across = hy.sum(g.radial) - hy.sum([unit[i] * vec[i] for i in range(3)])
        closed = [unit[i] * across + vec[i] for i in range(3)]
    else:
        g = term.gradient(x, x[0] * x[0] + x[1] * x[1] + x[2] * x[2], ctx)
        central = hy.sum(g.central)
        closed = [
            -central * x[i] + (g.component(i) if g.component(i) is not None else 0.0)
            for i in range(3)
        ]
    cf = hy.cfunc([*closed, *gradient(omega, x)], x)
    values = np.array([float(v) for v in pars.values])
    for p in X:
        row = cf(p, pars=values)
        scale = np.abs(row[3:]).max()
        np.testing.assert_allclose(row[:3], row[3:], rtol=0, atol=1e-14 * scale)
