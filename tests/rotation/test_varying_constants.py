"""Cayley's 1846 elements (a, b, c, h, e, δ) and the equations (61)–(63) of their variation."""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest

import cayley_heyoka as ch
from cayley_heyoka.core.errors import SceneError
from cayley_heyoka.rotation import brackets as br
from cayley_heyoka.rotation import element_check as ec
from cayley_heyoka.rotation.brackets import cayley_brackets, check_brackets, element_rates
from cayley_heyoka.rotation.cayley1846 import Cayley1846
from cayley_heyoka.rotation.element_check import check_element_equations
from cayley_heyoka.rotation.varying_constants import cayley_elements, upsilon_range

# Free motions of the brackets' check (Cayley 1846): near the axis of largest moment and
# near the axis of least moment, each with a general attitude.
MOTIONS = {
    "largest": (("1", "2", "3"), ("0.25", "-0.15", "1.2"), ("0.1", "0.2", "-0.3")),
    "least": (("1", "2", "3"), ("1.5", "0.2", "-0.25"), ("-0.3", "0.4", "0.5")),
}


def _mid(inertia, rates, rodrigues) -> float:
    lo, hi = upsilon_range(inertia, rates, rodrigues)
    return (lo + hi) / 2


def _state_at(solution: Cayley1846, t: str):
    s = solution.at(t)
    return [float(x) for x in (s.p, s.q, s.r)], [float(x) for x in s.quaternion]


def _scene(forces: dict, stop: str = "10", formulation: str = "rodrigues", **extra) -> ch.Scene:
    data = {
        "title": "weakly forced body",
        "body": {"inertia": ["1.0", "1.6", "2.3"]},
        "initial": {"rates": ["0.3", "1.0", "0.5"], "rodrigues": ["0.1", "0.2", "-0.3"]},
        "forces": forces,
        "attitude": {"formulation": formulation},
        "output": {"times": {"start": "0", "stop": stop, "count": 3}},
        **extra,
    }
    return ch.Scene.from_dict(data)


HEAVY_TOP = {
    "heavy_top": {
        "weight": "1.0",
        "center_of_mass": ["0.002", "-0.001", "0.003"],
        "up": ["0.6", "0", "0.8"],
    }
}
GRAVITY_GRADIENT = {
    "gravity_gradient": {"gm": "0.001", "distance": "1", "direction": ["0.36", "0.48", "0.8"]}
}


@pytest.mark.parametrize("name", MOTIONS)
def test_elements_are_constant_along_the_free_motion(name):
    inertia, rates, rodrigues = MOTIONS[name]
    solution = Cayley1846(inertia, rates, rodrigues, dps=20)
    ups0 = _mid(inertia, rates, rodrigues)
    first = cayley_elements(inertia, rates, rodrigues, 0.0, ups0)
    for t in ("1.7", "-4.2", "9.25", "23.5"):
        w, quat = _state_at(solution, t)
        later = cayley_elements(inertia, w, None, float(t), ups0, quaternion=quat, near=first)
        error = np.abs(later.values - first.values)
        assert np.all(error <= later.error_bounds + first.error_bounds), (t, error)


@pytest.mark.parametrize("name", MOTIONS)
@pytest.mark.parametrize("t", ["0", "5.3"])
def test_passage_time_and_angle_against_the_closed_form(name, t):
    """e is where the closed form has υ = υ₀, δ its 2 tan⁻¹(Ω/k) there (same continuation)."""
    inertia, rates, rodrigues = MOTIONS[name]
    solution = Cayley1846(inertia, rates, rodrigues, dps=30)
    ups0 = _mid(inertia, rates, rodrigues)
    w, quat = _state_at(solution, t)
    E = cayley_elements(inertia, w, None, float(t), ups0, quaternion=quat)
    assert float(E.e) <= float(t)  # the latest passage at or before t
    err = E.error_bounds
    with mpmath.workdps(40):
        at = solution.at(mpmath.mpf(float(E.e)))
        V0 = abs(float(E.V0))
        assert abs(float(at.upsilon - mpmath.mpf(ups0))) <= V0 / 2 * err[4] + 1e-15 * ups0
        # The closed form continues its angle from t = 0 and so does δ from α at t, up to 2π.
        turns = float((at.angle - mpmath.mpf(float(E.delta))) / (2 * mpmath.pi))
        assert abs(turns - round(turns)) * 2 * math.pi <= err[5] + 4 * err[4]
        # p₀, q₀, r₀: moved by the error of e, and by the integration's own (10ε per step).
        w0 = np.array([float(x) for x in E.passage_rates])
        I = np.array([float(m) for m in inertia])  # noqa: E741
        wdot = np.cross(I * w0, w0) / I
        bound = np.abs(wdot) * err[4] + 10 * np.finfo(float).eps * (1 + E.steps) * np.abs(w0)
        for mine, exact, b in zip(w0, (at.p, at.q, at.r), bound, strict=True):
            assert abs(float(mpmath.mpf(mine) - exact)) <= b


@pytest.mark.parametrize("precision", ["quad", {"bits": 120}], ids=["quad", "real120"])
def test_passage_in_extended_precision(precision):
    inertia, rates, rodrigues = MOTIONS["largest"]
    solution = Cayley1846(inertia, rates, rodrigues, dps=38)
    lo, hi = upsilon_range(inertia, rates, rodrigues, precision=precision)
    E = cayley_elements(inertia, rates, rodrigues, "0", (lo + hi) / 2, precision=precision)
    err = E.error_bounds
    assert err[4] < 1e-26
    with mpmath.workdps(40):
        at = solution.at(mpmath.mpf(str(E.e)))
        ups0 = mpmath.mpf(str(E.upsilon0))
        assert abs(at.upsilon - ups0) <= abs(float(E.V0)) / 2 * err[4]
        assert abs(at.angle - mpmath.mpf(str(E.delta))) <= err[5] + 4 * err[4]
    assert check_brackets(E).passed


@pytest.mark.parametrize("name", MOTIONS)
def test_brackets_61_equal_J_P_Jt_away_from_the_passage(name):
    inertia, rates, rodrigues = MOTIONS[name]
    ups0 = _mid(inertia, rates, rodrigues)
    E = cayley_elements(inertia, rates, rodrigues, 0.0, ups0, near=-12.0)
    assert abs(float(E.t - E.e)) > 5
    report = check_brackets(E)
    assert report.passed, report.text()
    # Cayley's constants and values on their own: (h, e) = −2, (k, ·) through a, b, c.
    B = cayley_brackets(E)
    assert B[3, 4] == -2 and np.allclose(B, -B.T, rtol=0, atol=0)


def test_jacobian_against_finite_differences():
    inertia, rates, rodrigues = MOTIONS["largest"]
    ups0 = _mid(inertia, rates, rodrigues)
    x = np.array([float(v) for v in rodrigues + rates])
    E = cayley_elements(inertia, x[3:], x[:3], 0.0, ups0, near=-3.0)
    J = E.jacobian("rodrigues")
    step = 1e-6
    for j in range(6):
        cols = []
        for sign in (1, -1):
            y = x.copy()
            y[j] += sign * step
            cols.append(cayley_elements(inertia, y[3:], y[:3], 0.0, ups0, near=E).values)
        fd = (cols[0] - cols[1]) / (2 * step)
        assert np.allclose(J[:, j], fd, rtol=1e-6, atol=1e-6 * np.max(np.abs(J))), j


def test_canonical_momenta_agree_with_eq_36():
    inertia, rates, rodrigues = MOTIONS["least"]
    E = cayley_elements(inertia, rates, rodrigues, 0.0, _mid(inertia, rates, rodrigues))
    lam, mu, nu, u, v, w = E.canonical_state()
    a, b, c = E.a, E.b, E.c
    kappa = 1 + lam**2 + mu**2 + nu**2
    eq36 = 2 / kappa * np.array([a + nu * b - mu * c, -nu * a + b + lam * c, mu * a - lam * b + c])
    assert np.allclose([u, v, w], eq36, rtol=0, atol=1e-14)


def test_element_rates_are_eq_62_written_out():
    inertia, rates, rodrigues = MOTIONS["largest"]
    E = cayley_elements(inertia, rates, rodrigues, 0.0, _mid(inertia, rates, rodrigues))
    Wa, Wb, Wc, Wh, We, Wd = np.random.default_rng(1846).normal(size=6)
    a, b, c, h, k, ups0, V0 = E.a, E.b, E.c, E.h, E.k, E.upsilon0, E.V0
    Ap, Bq, Cr = (float(m) * r for m, r in zip(inertia, E.passage_rates, strict=True))
    Phi0 = E.Phi0
    X, Y, Z = b * Cr - c * Bq, c * Ap - a * Cr, a * Bq - b * Ap
    F = (h + Phi0) / V0
    ka, kb, kc = (
        k / (2 * ups0) * (s + L - F * x) for s, L, x in ((a, Ap, X), (b, Bq, Y), (c, Cr, Z))
    )
    expected = [
        -c * Wb + b * Wc - X / V0 * We + ka * Wd,
        -a * Wc + c * Wa - Y / V0 * We + kb * Wd,
        -b * Wa + a * Wb - Z / V0 * We + kc * Wd,
        -2 * We,
        (X * Wa + Y * Wb + Z * Wc) / V0 + 2 * Wh - 4 * k / V0 * Wd,
        -(ka * Wa + kb * Wb + kc * Wc) + 4 * k / V0 * We,
    ]
    got = element_rates(E, [Wa, Wb, Wc, Wh, We, Wd])
    assert np.allclose(got, expected, rtol=1e-14, atol=1e-14)


@pytest.mark.parametrize(
    "forces, formulation",
    [(HEAVY_TOP, "rodrigues"), (GRAVITY_GRADIENT, "quaternion")],
    ids=["heavy_top", "gravity_gradient"],
)
def test_element_equations_along_a_weakly_forced_run(forces, formulation):
    report = check_element_equations(_scene(forces, formulation=formulation))
    assert report.passed, report.text()
    assert len(report.rows) == 15
    # The elements do move: the check is not comparing zeros.
    assert np.max(np.abs(report.series["change_e"])) > 1e-3
    assert np.max(np.abs(report.series["rate_actual_delta"])) > 1e-3


def test_a_wrong_bracket_sign_is_caught(monkeypatch):
    right = br.cayley_brackets

    def wrong(elements, absolute=False):
        B = right(elements, absolute)
        if not absolute:
            B[3, 4], B[4, 3] = -B[3, 4], -B[4, 3]  # (h, e) = +2
        return B

    for module in (br, ec):
        monkeypatch.setattr(module, "cayley_brackets", wrong)
    report = check_element_equations(_scene(HEAVY_TOP, stop="4"))
    failed = {row.quantity.split(":")[0].split(" ")[0] for row in report.rows if not row.passed}
    assert not report.passed
    assert {"dh/dt", "de/dt", "Δh", "Δe", "(61)"} <= failed


def test_a_small_error_in_V0_is_caught(monkeypatch):
    """The law's bounds are tight enough to see (e, δ) = −4k/V₀ off by 1e-7 relative."""
    right = br.cayley_brackets

    def slightly_off(elements, absolute=False):
        B = right(elements, absolute)
        if not absolute:
            B[4, 5], B[5, 4] = B[4, 5] * (1 + 1e-7), B[5, 4] * (1 + 1e-7)
        return B

    for module in (br, ec):
        monkeypatch.setattr(module, "cayley_brackets", slightly_off)
    report = check_element_equations(_scene(GRAVITY_GRADIENT, stop="4"))
    assert not report.passed


def test_upsilon0_outside_the_range_or_at_a_turning_value_is_refused():
    inertia, rates, rodrigues = MOTIONS["largest"]
    lo, hi = upsilon_range(inertia, rates, rodrigues)
    with pytest.raises(ValueError, match="upsilon0: .* never passes"):
        cayley_elements(inertia, rates, rodrigues, 0.0, hi + 0.1)
    for turning in (lo, hi):
        with pytest.raises(ValueError, match="upsilon0: .* turning value"):
            cayley_elements(inertia, rates, rodrigues, 0.0, turning)
    scene = _scene(HEAVY_TOP, stop="2")
    with pytest.raises(ValueError, match="upsilon0"):
        check_element_equations(scene, upsilon0=1e3)


def test_scenes_the_check_cannot_judge_are_refused():
    free = ch.Scene.from_dict(
        {
            "body": {"inertia": ["1", "2", "3"]},
            "initial": {"rates": ["0.3", "1", "0.5"], "rodrigues": ["0", "0", "0"]},
            "output": {"times": {"start": "0", "stop": "1", "count": 2}},
        }
    )
    with pytest.raises(SceneError, match="forces: the scene has no force function"):
        check_element_equations(free)
    moving = _scene({"potential": {"V": "0.001 * R13 * cos(t)"}})
    with pytest.raises(SceneError, match="forces: W depends explicitly on t"):
        check_element_equations(moving)
    orbit = ch.load_scene("examples/orbit_j2_third_body.toml")
    with pytest.raises(ValueError, match="scene: the elements are those of a rotating body"):
        check_element_equations(orbit)
    with pytest.raises(ValueError, match="rodrigues: give the attitude once"):
        cayley_elements(
            ("1", "2", "3"), ("1", "0", "0.2"), (0, 0, 0), 0.0, 1.0, quaternion=(1, 0, 0, 0)
        )


@pytest.mark.slow
def test_element_equations_in_quad():
    report = check_element_equations(
        _scene(GRAVITY_GRADIENT, stop="3", integrator={"precision": "quad"})
    )
    assert report.passed, report.text()
    worst = max(float(r.note.split(" = ")[2].split(" ")[0]) for r in report.rows[:7])
    assert worst < 1e-29
