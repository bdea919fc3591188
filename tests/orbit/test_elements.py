"""Cartesian state ↔ Cayley's osculating-plane state ↔ classical elements (Cayley 1860, §5, §9).

Reference values: the initial Cayley states of cases R1–R4 (validation/orbit_cases.py), derived
from the exact Cartesian inputs at high precision, kept below.

Round-trip tolerances are ``SAFETY · ε · κ`` with ``κ`` a first-order error bound built from the
orbit's own sensitivities (:func:`scales`), not from this module: the plane of a nearly radial
orbit, the cancellation in ``1/a = 2/r − v²/μ``, Kepler's equation near ``e → 1`` and the element
``e`` itself, which in working precision fixes ``1 − e`` only to ``±ε``. Over 4000 random
orbits and every extreme below (double and 50 digits), the observed error/(ε·κ) stayed below 6
for each quantity checked, so ``SAFETY = 32`` leaves a margin without making κ vacuous.
"""

from __future__ import annotations

import math
from dataclasses import fields

import mpmath
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cayley_heyoka.core import vectors
from cayley_heyoka.mechanics import frames
from cayley_heyoka.mechanics.kepler import (
    CayleyState,
    Elements,
    cartesian_to_cayley,
    cartesian_to_elements,
    cayley_to_cartesian,
    cayley_to_elements,
    elements_to_cartesian,
    elements_to_cayley,
)

DOUBLE_EPS = float(np.finfo(float).eps)
SAFETY = 32

# Case: exact Cartesian inputs, gauge Σ(0), frame (θ′, σ′, φ′) at t = 0, the derived 25-digit
# initial state (r, ṙ, ρ, h, Θ, Σ, Φ) and the osculating (a, e, Φ) at t = 0 to 6 digits; μ = 1.
REFERENCE = {
    "R1": {
        "x": ("0.9", "0.2", "0.1"),
        "v": ("-0.25", "0.85", "0.45"),
        "Sigma": "0",
        "frame": ("0", "0", "0"),
        "state": (
            "0.9273618495495703752516416",
            "-0.01078327732034384157269351",
            "0.2331781790241747908290191",
            "0.9214933532044601785414051",
            "0.01162738295638387101804060",
            "0.0",
            "0.4855166956563740243917468",
        ),
        "osculating": ("0.855318", "0.0849214", "0.485517"),
    },
    "R2": {
        "x": ("1.0", "0.0", "0.0"),
        "v": ("0.0", "0.9", "0.35"),
        "Sigma": "0.5",
        "frame": ("0", "0", "0"),
        "state": (
            "1.000000000000000000000000",
            "0.0",
            "0.5000000000000000000000000",
            "0.9656603957913982919293738",
            "0.0",
            "0.5000000000000000000000000",
            "0.3708912888126623712742302",
        ),
        "osculating": ("0.936768", "0.0675", "0.370891"),
    },
    "R3": {
        "x": ("0.5", "-0.8", "0.3"),
        "v": ("0.9", "0.45", "0.2"),
        "Sigma": "0.7",
        "frame": ("0.3", "0.1", "0.2"),
        "state": (
            "0.9899494936611665341611821",
            "0.1515228816828316123716095",
            "2.086675206694648244486773",
            "1.004465031745754701361948",
            "-2.549840799929666481244030",
            "0.7000000000000000000000000",
            "0.5101293609615063615417839",
        ),
        "osculating": ("1.03327", "0.153405", "0.510129"),
    },
    "R4": {
        "x": ("0.6", "0.3", "-0.2"),
        "v": ("0.2", "-1.35", "-0.6"),
        "Sigma": "-1.0",
        "frame": ("-0.5", "0.25", "0.4"),
        "state": (
            "0.7000000000000000000000000",
            "-0.2357142857142857142857143",
            "-2.874598270662800329519206",
            "1.030436800585072272097469",
            "-0.8503402506876948245912905",
            "-1.000000000000000000000000",
            "2.501851635951231295482591",
        ),
        "osculating": ("1.57569", "0.571083", "2.50185"),
    },
}

STATE_FIELDS = [f.name for f in fields(CayleyState)]
ELEMENT_FIELDS = [f.name for f in fields(Elements)]


def norm(vector):
    return math.sqrt(sum(float(c) ** 2 for c in vector))


def distance(a, b):
    return norm([p - q for p, q in zip(a, b, strict=True)])


def angle_difference(a, b):
    """|a − b| modulo 2π, in float (the differences compared are tiny)."""
    d = float(a) - float(b)
    return abs(d - 2 * math.pi * round(d / (2 * math.pi)))


def scales(a, e, E, mu):
    """Sensitivities of the osculating state at eccentric anomaly ``E``, from the textbook
    orbit-plane formulas ``x = a(cos E − e, b sin E)``, ``v = (na/D)(−sin E, b cos E)`` with
    ``b = √(1 − e²)``, ``D = 1 − e cos E`` (independent of the module under test).

    ``q = r|v|/h`` conditions the orbit plane (``n̂ = x × v / h``); ``energy = a(2/r + v²/μ)``
    the cancellation in ``1/a``; ``dx_de``, ``dv_de`` the response to the element ``e`` at fixed
    ``M``; ``dx_dM = |v|/n``, ``dv_dM = μ/(r²n)`` to the mean anomaly, whose rounding noise is
    ``ε(|E| + |M|)``; ``dfdE = b/D`` carries an error of ``E`` to the true anomaly.
    """
    a, e, E, mu = float(a), float(e), float(E), float(mu)
    n = math.sqrt(mu / a**3)
    b = math.sqrt((1 - e) * (1 + e))
    s, c = math.sin(E), math.cos(E)
    D = (1 - e) + 2 * e * math.sin(E / 2) ** 2
    r = a * D
    speed = n * a * math.sqrt(s * s + b * b * c * c) / D
    dE = s / D
    dD = -c + e * s * dE
    dx_de = a * math.hypot(-s * dE - 1, -e / b * s + b * c * dE)
    dv_de = (
        n
        * a
        * math.hypot(
            -c * dE / D + s * dD / D**2, -e / b * c / D - b * s * dE / D - b * c * dD / D**2
        )
    )
    return {
        "r": r,
        "speed": speed,
        "D": D,
        "q": r * speed / (n * a * a * b),
        "energy": a * (2 / r + speed**2 / mu),
        "dx_de": dx_de,
        "dv_de": dv_de,
        "dx_dM": speed / n,
        "dv_dM": mu / (r * r * n),
        "dfdE": b / D,
    }


def cartesian_tolerances(s, E, M, eps):
    """Bounds on |Δx| and |Δv| after Cartesian → elements → Cartesian."""
    kepler = abs(float(E)) + abs(float(M))
    dx = s["r"] * (s["q"] + s["energy"]) + s["dx_de"] + s["dx_dM"] * kepler
    dv = s["speed"] * (s["q"] + s["energy"]) + s["dv_de"] + s["dv_dM"] * kepler
    return SAFETY * eps * dx, SAFETY * eps * dv


def assert_cartesian_round_trips(elements, mu, frame, E, eps):
    """x, v from the elements; back through Cayley's state and through the elements."""
    s = scales(elements.a, elements.e, E, mu)
    x, v = elements_to_cartesian(elements, mu, frame)

    # The plane alone: only the orbit normal's conditioning q enters.
    x1, v1 = cayley_to_cartesian(cartesian_to_cayley(x, v, "0.375", frame), frame)
    assert distance(x1, x) <= SAFETY * eps * s["q"] * norm(x)
    assert distance(v1, v) <= SAFETY * eps * s["q"] * norm(v)

    x2, v2 = elements_to_cartesian(cartesian_to_elements(x, v, mu, frame), mu, frame)
    tol_x, tol_v = cartesian_tolerances(s, E, elements.mean_anomaly, eps)
    assert distance(x2, x) <= tol_x
    assert distance(v2, v) <= tol_v
    return x, v


def assert_elements_round_trip(elements, mu, frame, E, eps):
    """Elements → Cartesian → elements, for the angles that the orbit defines."""
    a, e, i = float(elements.a), float(elements.e), float(elements.inclination)
    s = scales(a, e, E, mu)
    x, v = elements_to_cartesian(elements, mu, frame)
    back = cartesian_to_elements(x, v, mu, frame)
    tol = SAFETY * eps
    assert abs(float(back.a) / a - 1) <= tol * s["energy"]
    assert abs(float(back.e) - e) <= tol * s["energy"]
    assert abs(float(back.inclination) - i) <= tol * s["q"]
    # Θ ± (ω + M) places the body in a prograde (retrograde) plane even where Θ and ω do not exist.
    sign = 1 if i < math.pi / 2 else -1
    longitude = [
        el.node + sign * (el.argument_of_pericentre + el.mean_anomaly) for el in (back, elements)
    ]
    kepler = (abs(float(E)) + abs(float(elements.mean_anomaly))) / s["D"]
    lon_tol = s["q"] + (s["energy"] + kepler) * (1 + s["dfdE"])
    assert angle_difference(*longitude) <= tol * lon_tol
    # sin i in the working arithmetic: sin(π) is ε-small, not zero, and so the plane is defined.
    sin_i = float(abs(mpmath.sin(elements.inclination)))
    if sin_i > 0:
        assert angle_difference(back.node, elements.node) <= tol * s["q"] / sin_i
        if e > 0:
            omega_tol = s["q"] / sin_i + s["energy"] * s["dfdE"] / e
            M_tol = s["energy"] * s["D"] / e + kepler
            assert (
                angle_difference(back.argument_of_pericentre, elements.argument_of_pericentre)
                <= tol * omega_tol
            )
            assert angle_difference(back.mean_anomaly, elements.mean_anomaly) <= tol * M_tol


# ---------------------------------------------------------------------------------------------
# Reference values


def assert_digits(value, printed, tolerance):
    """``value`` agrees with the decimal string ``printed``: relative, or absolute at zero."""
    expected = mpmath.mpf(printed)
    error = abs(value - expected) / (abs(expected) if expected else 1)
    assert error <= tolerance, (value, printed)


@pytest.mark.parametrize("case", sorted(REFERENCE))
def test_initial_cayley_state_matches_reference(case):
    ref = REFERENCE[case]
    with mpmath.workdps(40):
        state = cartesian_to_cayley(ref["x"], ref["v"], ref["Sigma"], ref["frame"])
        for name, printed in zip(STATE_FIELDS, ref["state"], strict=True):
            assert isinstance(getattr(state, name), mpmath.mpf)
            assert_digits(getattr(state, name), printed, mpmath.mpf("1e-24"))


@pytest.mark.parametrize("case", sorted(REFERENCE))
def test_osculating_elements_match_reference(case):
    ref = REFERENCE[case]
    with mpmath.workdps(40):
        el = cartesian_to_elements(ref["x"], ref["v"], 1, ref["frame"])
        for value, printed in zip((el.a, el.e, el.inclination), ref["osculating"], strict=True):
            # Half a unit in the last printed (6th significant) digit.
            expected = mpmath.mpf(printed)
            assert abs(value - expected) <= 5 * mpmath.mpf(10) ** (
                mpmath.floor(mpmath.log10(expected)) - 6
            )


# ---------------------------------------------------------------------------------------------
# Against the textbook formulas (independent of Cayley's tables)


@pytest.mark.parametrize(
    "e, i, E",
    [
        ("0", "0.4", "1.1"),
        ("0.3", "2.9", "-2.0"),
        ("0.999999", "1e-8", "1e-4"),
        ("0.7", "3.1", "3.0"),
    ],
)
def test_elements_to_cartesian_matches_textbook(e, i, E):
    """x = M₀₁ R₃(Ω) R₁(i) R₃(ω) (a(cos E − e), b sin E, 0), v likewise; Kepler's M from E."""
    with mpmath.workdps(50):
        a, mu, node, omega = (
            mpmath.mpf("2.5"),
            mpmath.mpf("0.8"),
            mpmath.mpf("-1.3"),
            mpmath.mpf("4.0"),
        )
        e, i, E = mpmath.mpf(e), mpmath.mpf(i), mpmath.mpf(E)
        frame = [mpmath.mpf(c) for c in ("0.3", "-0.7", "1.2")]
        M = E - e * mpmath.sin(E)
        x, v = elements_to_cartesian(Elements(a, e, i, node, omega, M), mu, frame)

        n, b = mpmath.sqrt(mu / a**3), mpmath.sqrt(1 - e * e)
        D = 1 - e * mpmath.cos(E)
        plane_x = [a * (mpmath.cos(E) - e), a * b * mpmath.sin(E), 0]
        plane_v = [-n * a * mpmath.sin(E) / D, n * a * b * mpmath.cos(E) / D, 0]
        R = vectors.matmul(
            frames.plane_matrix(*frame),
            vectors.matmul(
                frames.rotation_z(node),
                vectors.matmul(frames.rotation_x(i), frames.rotation_z(omega)),
            ),
        )
        tol = mpmath.mpf(10) ** -45
        assert distance(x, vectors.matvec(R, plane_x)) <= tol
        assert distance(v, vectors.matvec(R, plane_v)) <= tol / D
        # Two-body invariants: energy −μ/2a and angular momentum √(μa(1 − e²)).
        r, speed2 = mpmath.sqrt(vectors.dot(x, x)), vectors.dot(v, v)
        assert abs(speed2 / 2 - mu / r + mu / (2 * a)) <= tol / D
        assert abs(norm(vectors.cross(x, v)) - float(mpmath.sqrt(mu * a * (1 - e * e)))) <= 1e-15


# ---------------------------------------------------------------------------------------------
# Round trips at the extremes

ECCENTRICITIES = ["0", "1e-12", "0.3", "0.99", "0.999999"]
INCLINATIONS = ["0", "1e-8", "1.0", "pi-1e-8", "pi"]
ECCENTRIC_ANOMALIES = ["0", "1e-6", "-0.05", "0.5", "-2.0", "pi"]
FRAMES = [("0", "0", "0"), ("0.3", "0.1", "0.2")]


def inclination_value(text, number):
    """``pi`` and ``pi-1e-8`` in the arithmetic at hand (``number`` converts decimal text)."""
    pi = mpmath.pi if number is mpmath.mpf else math.pi
    if text == "pi":
        return +pi
    if text == "pi-1e-8":
        return pi - number("1e-8")
    return number(text)


def extreme_cases(number, sin):
    for e_text in ECCENTRICITIES:
        for i_text in INCLINATIONS:
            for E_text in ECCENTRIC_ANOMALIES:
                for frame in FRAMES:
                    e = number(e_text)
                    E = inclination_value(E_text, number)  # "pi" means π here as well
                    M = E - e * sin(E)
                    elements = Elements(
                        number("1.3"),
                        e,
                        inclination_value(i_text, number),
                        number("2.0"),
                        number("-1.0"),
                        M,
                    )
                    yield elements, [number(c) for c in frame], E


def test_round_trips_at_the_extremes_in_double():
    for elements, frame, E in extreme_cases(float, math.sin):
        assert_cartesian_round_trips(elements, 0.7, frame, E, DOUBLE_EPS)
        assert_elements_round_trip(elements, 0.7, frame, E, DOUBLE_EPS)


def test_round_trips_at_the_extremes_in_mpmath():
    with mpmath.workdps(50):
        eps = float(mpmath.mp.eps)
        mu = mpmath.mpf("0.7")
        for elements, frame, E in extreme_cases(mpmath.mpf, mpmath.sin):
            x, v = assert_cartesian_round_trips(elements, mu, frame, E, eps)
            assert all(isinstance(c, mpmath.mpf) for c in x + v)
            assert_elements_round_trip(elements, mu, frame, E, eps)


def test_conventions_where_node_and_pericentre_do_not_exist():
    # Circular orbits, chosen so that every intermediate quantity is exact in binary.
    in_plane = cartesian_to_elements((0.0, 2.0, 0.0), (-1.0, 0.0, 0.0), 2.0)
    assert (in_plane.e, in_plane.inclination, in_plane.node, in_plane.argument_of_pericentre) == (
        0,
        0,
        0,
        0,
    )
    assert in_plane.mean_anomaly == pytest.approx(math.pi / 2, abs=DOUBLE_EPS)  # f = u

    retrograde = cartesian_to_cayley((1.0, 0.0, 0.0), (0.0, -1.0, 0.0))
    assert retrograde.Phi == math.pi
    assert retrograde.Theta == 0  # atan2(0, −0) would give π

    polar = cartesian_to_elements((0.0, 0.0, 2.0), (-1.0, 0.0, 0.0), 2.0)
    assert (polar.e, polar.node, polar.argument_of_pericentre) == (0, 0, 0)
    assert polar.inclination == pytest.approx(math.pi / 2, abs=DOUBLE_EPS)
    assert polar.mean_anomaly == pytest.approx(math.pi / 2, abs=DOUBLE_EPS)

    with mpmath.workdps(50):
        exact = cartesian_to_elements(("0", "2", "0"), ("-1", "0", "0"), "2")
        assert (exact.e, exact.inclination, exact.node, exact.argument_of_pericentre) == (
            0,
            0,
            0,
            0,
        )
        assert abs(exact.mean_anomaly - mpmath.pi / 2) <= mpmath.mp.eps


def test_angles_are_reduced_except_rho():
    el = Elements(1.0, 0.4, 1.0, node=13.0, argument_of_pericentre=-20.0, mean_anomaly=100.0)
    state = elements_to_cayley(el, 1.0, sigma=50.0)
    assert -math.pi < state.Theta <= math.pi and state.Sigma == 50.0
    assert -math.pi < state.rho - state.Sigma <= math.pi
    back = cayley_to_elements(state, 1.0)
    for name in ("node", "argument_of_pericentre", "mean_anomaly"):
        assert -math.pi < getattr(back, name) <= math.pi
        assert angle_difference(getattr(back, name), getattr(el, name)) <= 1e-13


def test_half_turn_is_plus_pi():
    # −π and π are the same angle; the interval (−π, π] keeps the positive one.
    assert elements_to_cayley(Elements(1.0, 0.4, 1.0, -math.pi, 0.0, 0.0), 1.0).Theta == math.pi
    with mpmath.workdps(30):
        state = elements_to_cayley(Elements(1, 0, 1, -mpmath.pi, 0, 0), 1)
        assert state.Theta == +mpmath.pi
    # x₂ v₃ = −0.0 makes H₁ = −0.0, and atan2(−0.0, −1) = −π: the node here is at +π.
    state = cartesian_to_cayley((-1.0, -0.0, 0.0), (0.0, 1.0, 1.0))
    assert state.Theta == math.pi


@pytest.mark.parametrize("number", [float, mpmath.mpf])
def test_circular_orbit_has_true_anomaly_equal_to_argument_of_latitude(number):
    # r = 2, ṙ = 0, h = 2, μ = 2: p = r and 1/a = 1/r exactly, so e = 0 exactly; then ω = 0
    # and M = E = f = u to the last digit, for any u (not 2 atan2(sin(u/2), cos(u/2)) ≈ u).
    with mpmath.workdps(30):
        for u in np.linspace(-3.1, 3.1, 23):
            state = CayleyState(
                number(2), number(0), number(u) + number(1), number(2), 0, number(1), 1
            )
            el = cayley_to_elements(state, number(2))
            assert el.e == 0 and el.argument_of_pericentre == 0
            assert el.mean_anomaly == state.rho - state.Sigma


# ---------------------------------------------------------------------------------------------
# Property-based round trips (double precision)

angles = st.floats(-20, 20)


@st.composite
def orbits(draw):
    e = draw(st.floats(0, 0.999))
    E = draw(st.floats(-math.pi, math.pi))
    turns = draw(st.integers(-3, 3))
    elements = Elements(
        draw(st.floats(0.1, 10)),
        e,
        draw(st.floats(0, math.pi)),
        draw(angles),
        draw(angles),
        E - e * math.sin(E) + 2 * math.pi * turns,
    )
    frame = (draw(angles), draw(angles), draw(st.floats(0, math.pi)))
    return elements, draw(st.floats(0.1, 10)), frame, E


@settings(max_examples=200, deadline=None)
@given(orbits())
def test_cartesian_round_trips_property(orbit):
    elements, mu, frame, E = orbit
    reduced = Elements(**{**elements.__dict__, "mean_anomaly": E - elements.e * math.sin(E)})
    x, v = assert_cartesian_round_trips(reduced, mu, frame, E, DOUBLE_EPS)
    # Whole turns of M only add the rounding of the reduction, ε|M| in M.
    x_turns, v_turns = elements_to_cartesian(elements, mu, frame)
    s = scales(elements.a, elements.e, E, mu)
    slack = SAFETY * DOUBLE_EPS * (abs(elements.mean_anomaly) + 1)
    assert distance(x_turns, x) <= slack * (s["dx_dM"] + s["r"])
    assert distance(v_turns, v) <= slack * (s["dv_dM"] + s["speed"])


@settings(max_examples=200, deadline=None)
@given(orbits(), st.floats(-20, 20))
def test_cayley_state_consistency_property(orbit, gauge):
    elements, mu, frame, _ = orbit
    x, v = elements_to_cartesian(elements, mu, frame)
    state = cartesian_to_cayley(x, v, gauge, frame)
    # Cayley's state from the elements directly agrees with the one through Cartesian.
    direct = elements_to_cayley(elements, mu, sigma=gauge)
    x_direct, v_direct = cayley_to_cartesian(direct, frame)
    x_state, v_state = cayley_to_cartesian(state, frame)
    q = norm(x) * norm(v) / state.h
    assert distance(x_direct, x_state) <= SAFETY * DOUBLE_EPS * q * norm(x)
    assert distance(v_direct, v_state) <= SAFETY * DOUBLE_EPS * q * norm(v)
    assert abs(direct.h / state.h - 1) <= SAFETY * DOUBLE_EPS * q


# ---------------------------------------------------------------------------------------------
# Consistency of Cayley's state with the tables of frames.py


@pytest.mark.parametrize("frame", [("0", "0", "0"), ("0.3", "0.1", "0.2"), ("-2.0", "1.5", "2.9")])
def test_state_agrees_with_the_tables(frame):
    with mpmath.workdps(50):
        tol = mpmath.mpf(10) ** -45
        x_in, v_in = ("0.5", "-0.8", "0.3"), ("0.9", "0.45", "0.2")
        state = cartesian_to_cayley(x_in, v_in, "0.7", frame)
        x0, v0 = [mpmath.mpf(c) for c in x_in], [mpmath.mpf(c) for c in v_in]
        M01 = frames.plane_matrix(*[mpmath.mpf(c) for c in frame])
        M02 = vectors.matmul(M01, frames.plane_matrix(state.Theta, state.Sigma, state.Phi))
        # x = r M₀₁ M₁₂ (cos ρ, sin ρ, 0): the boxed formula of §5, not the orbit axes.
        boxed = vectors.matvec(
            M02, [state.r * mpmath.cos(state.rho), state.r * mpmath.sin(state.rho), 0]
        )
        assert distance(boxed, x0) <= tol
        # x × v = h n̂, n̂ the third column of M₀₁ M₁₂.
        H = vectors.cross(x0, v0)
        assert abs(state.h - mpmath.sqrt(vectors.dot(H, H))) <= tol
        assert distance(H, [state.h * row[2] for row in M02]) <= tol
        # ṙ = x·v/r; the body's departure from x₂ (first column of M₀₂) is ρ.
        assert abs(state.rdot - vectors.dot(x0, v0) / state.r) <= tol
        d = [row[0] for row in M02]
        assert abs(vectors.dot(x0, d) - state.r * mpmath.cos(state.rho)) <= tol


def test_gauge_moves_departure_point_not_the_body():
    x, v = (0.5, -0.8, 0.3), (0.9, 0.45, 0.2)
    frame = (0.3, 0.1, 0.2)
    reference = cartesian_to_cayley(x, v, 0.0, frame)
    for gauge in (-7.0, 0.7, 3.0, 100.0):
        state = cartesian_to_cayley(x, v, gauge, frame)
        assert state.Sigma == gauge
        assert abs((state.rho - state.Sigma) - reference.rho) <= 4 * DOUBLE_EPS * (1 + abs(gauge))
        for name in ("r", "rdot", "h", "Theta", "Phi"):
            assert getattr(state, name) == getattr(reference, name)
        x2, v2 = cayley_to_cartesian(state, frame)
        assert distance(x2, x) <= 8 * DOUBLE_EPS * (1 + abs(gauge)) * norm(x)


# ---------------------------------------------------------------------------------------------
# Vectorised input


def test_vectorised_matches_elementwise():
    rng = np.random.default_rng(7)
    n = 64
    e = np.concatenate([[0.0, 1e-12, 0.999999, 0.99], rng.uniform(0, 0.999, n - 4)])
    elements = Elements(
        rng.uniform(0.1, 10, n),
        e,
        np.concatenate([[0.0, np.pi, 1e-8, np.pi - 1e-8], rng.uniform(0, np.pi, n - 4)]),
        rng.uniform(-10, 10, n),
        rng.uniform(-10, 10, n),
        np.concatenate([[np.pi, -np.pi, 0.0, 1e-10], rng.uniform(-10, 10, n - 4)]),
    )
    mu = rng.uniform(0.1, 10, n)
    frame = [rng.uniform(-4, 4, n), rng.uniform(-4, 4, n), 0.25]  # a scalar broadcasts
    x, v = elements_to_cartesian(elements, mu, frame)
    back = cartesian_to_elements(x, v, mu, frame)
    state = cartesian_to_cayley(x, v, 0.5, frame)
    assert all(np.shape(c) == (n,) for c in x + v)
    for j in range(n):
        el_j = Elements(*[float(getattr(elements, f)[j]) for f in ELEMENT_FIELDS])
        frame_j = [float(frame[0][j]), float(frame[1][j]), 0.25]
        x_j, v_j = elements_to_cartesian(el_j, float(mu[j]), frame_j)
        # Same operations elementwise, and Kepler's iteration freezes converged entries, so
        # the digits are identical, not merely close.
        assert [c[j] for c in x + v] == x_j + v_j
        back_j = cartesian_to_elements(x_j, v_j, float(mu[j]), frame_j)
        assert [getattr(back, f)[j] for f in ELEMENT_FIELDS] == [
            getattr(back_j, f) for f in ELEMENT_FIELDS
        ]
        state_j = cartesian_to_cayley(x_j, v_j, 0.5, frame_j)
        assert [getattr(state, f)[j] for f in STATE_FIELDS] == [
            getattr(state_j, f) for f in STATE_FIELDS
        ]


def test_scalars_in_scalars_out():
    state = cartesian_to_cayley([0.9, 0.2, 0.1], [-0.25, 0.85, 0.45])
    assert all(
        isinstance(getattr(state, f), float) and np.ndim(getattr(state, f)) == 0
        for f in STATE_FIELDS
    )


def test_any_string_or_mpf_input_selects_mpmath():
    with mpmath.workdps(30):
        for mu in ("1", mpmath.mpf(1)):
            el = cartesian_to_elements((0.9, 0.2, 0.1), (-0.25, 0.85, 0.45), mu)
            assert all(isinstance(getattr(el, f), mpmath.mpf) for f in ELEMENT_FIELDS)
        # Floats are taken at their exact binary value, not as decimal text.
        from_float = cartesian_to_cayley((0.1, 0.0, 0.0), (0.0, 1.0, 0.0), "0")
        from_text = cartesian_to_cayley(("0.1", "0", "0"), ("0", "1", "0"), "0")
        assert from_float.r == mpmath.mpf(0.1) != from_text.r


# ---------------------------------------------------------------------------------------------
# Errors

GOOD = Elements(1.0, 0.5, 1.0, 0.1, 0.2, 0.3)
GOOD_STATE = elements_to_cayley(GOOD, 1.0)


@pytest.mark.parametrize(
    "change, match",
    [
        ({"e": 1.2}, r"eccentricity: must be in \[0, 1\).*got 1\.2"),
        ({"e": 1.0}, "eccentricity"),
        ({"e": -0.1}, "eccentricity"),
        ({"a": 0.0}, "semi-major axis"),
        ({"a": -1.0}, "semi-major axis"),
        ({"inclination": -1e-9}, r"inclination: must be in \[0, pi\]"),
        ({"inclination": 3.15}, "inclination"),
        ({"node": math.nan}, "node: must be finite"),
        ({"mean_anomaly": math.inf}, "mean_anomaly: must be finite"),
        ({"e": np.array([0.1, 1.5])}, "eccentricity.*got 1.5"),
    ],
)
def test_invalid_elements(change, match):
    with pytest.raises(ValueError, match=match):
        elements_to_cayley(Elements(**{**GOOD.__dict__, **change}), 1.0)
    with pytest.raises(ValueError, match=match):
        elements_to_cartesian(Elements(**{**GOOD.__dict__, **change}), 1.0)


@pytest.mark.parametrize("mu", [0.0, -1.0, "-2", np.array([1.0, 0.0])])
def test_invalid_mu(mu):
    with pytest.raises(ValueError, match="mu"):
        elements_to_cayley(GOOD, mu)
    with pytest.raises(ValueError, match="mu"):
        cayley_to_elements(GOOD_STATE, mu)
    with pytest.raises(ValueError, match="mu"):
        cartesian_to_elements((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), mu)


@pytest.mark.parametrize(
    "position, velocity, match",
    [
        ((0.0, 0.0, 0.0), (1.0, 0.0, 0.0), "position: r"),
        (("0", "0", "0"), (1.0, 0.0, 0.0), "position: r"),
        ((1.0, 2.0, 3.0), (2.0, 4.0, 6.0), "h = |x × v|: must be nonzero"),
        ((1.0, 0.0, 0.0), (0.0, 0.0, 0.0), "rectilinear"),
        ((1.0, math.nan, 0.0), (0.0, 1.0, 0.0), "position: must be finite"),
        ((1.0, 0.0, 0.0), (0.0, "inf", 0.0), "velocity must be finite"),
        ((1.0, 0.0), (0.0, 1.0, 0.0), "position: must have 3 components"),
        (
            (np.array([1.0, 1.0]), 0.0, 0.0),
            (np.array([0.0, 2.0]), np.array([1.0, 0.0]), 0.0),
            r"h = \|x × v\|.*got 0\.0",
        ),
    ],
)
def test_invalid_cartesian(position, velocity, match):
    with pytest.raises(ValueError, match=match):
        cartesian_to_cayley(position, velocity)
    with pytest.raises(ValueError, match=match):
        cartesian_to_elements(position, velocity, 1.0)


def test_invalid_frame_and_gauge():
    with pytest.raises(ValueError, match="frame: must be finite"):
        cartesian_to_cayley((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), frame=(0.0, math.inf, 0.0))
    with pytest.raises(ValueError, match="sigma: must be finite"):
        cartesian_to_cayley((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), sigma=math.nan)
    with pytest.raises(ValueError, match="frame: must be finite"):
        cayley_to_cartesian(GOOD_STATE, frame=(0.0, 0.0, math.nan))


@pytest.mark.parametrize(
    "velocity, e",
    [((0.0, 2.0, 0.0), "1.0"), ((0.0, 2.5, 0.0), "2.125"), ((0.0, 2.0, 2.0), "3.0")],
)
def test_unbound_orbit_has_no_elliptic_elements(velocity, e):
    # μ = 2, r = 1: parabolic at |v| = 2, hyperbolic beyond; e = |v|²r/μ − 1 for v ⊥ x.
    message = (
        rf"the osculating orbit is not an ellipse \(e = {e}\d*\); "
        "classical elliptic elements do not exist"
    )
    with pytest.raises(ValueError, match=message):
        cartesian_to_elements((1.0, 0.0, 0.0), velocity, 2.0)
    with pytest.raises(ValueError, match="not an ellipse"):
        cayley_to_elements(cartesian_to_cayley((1.0, 0.0, 0.0), velocity), 2.0)


@pytest.mark.parametrize(
    "change, match",
    [
        ({"r": 0.0}, "r: must be positive"),
        ({"h": 0.0}, "h: must be positive"),
        ({"Phi": -0.5}, r"Phi: must be in \[0, pi\]"),
        ({"Phi": 4.0}, "Phi"),
        ({"rho": math.inf}, "rho: must be finite"),
    ],
)
def test_invalid_cayley_state(change, match):
    with pytest.raises(ValueError, match=match):
        cayley_to_elements(CayleyState(**{**GOOD_STATE.__dict__, **change}), 1.0)


@pytest.mark.parametrize("change", [{"r": 0.0}, {"r": -1.0}, {"Theta": math.nan}])
def test_invalid_cayley_state_for_cartesian(change):
    name = next(iter(change))
    with pytest.raises(ValueError, match=name):
        cayley_to_cartesian(CayleyState(**{**GOOD_STATE.__dict__, **change}))


@pytest.mark.parametrize("M", [5.9103524366e-314, 5e-324, -3e-320, 2.5e-308])
@pytest.mark.parametrize("e", [0.0, 0.734375, 0.999999])
def test_a_subnormal_mean_anomaly_converges_at_pericentre(M, e):
    """Found by the property above: with E and M subnormal the noise bound of Kepler's
    equation underflowed to 0 and Newton alternated between two neighbours of the root."""
    elements = Elements(
        a=1.0, e=e, inclination=0.3, node=0.0, argument_of_pericentre=0.0, mean_anomaly=M
    )
    x, v = elements_to_cartesian(elements, 1.0)
    assert np.all(np.isfinite(np.asarray(x, dtype=float)))
    assert abs(float(x[0]) - (1 - e)) <= 4 * DOUBLE_EPS
    assert abs(float(x[1])) + abs(float(x[2])) <= 4 * DOUBLE_EPS
