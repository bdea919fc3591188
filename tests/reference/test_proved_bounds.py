"""Proved bounds of the free body's closed form (Arb balls, ``FreeRigidBody.enclose``).

The truth here is the independent mpmath route (Jacobi functions by mpmath's ``ellipfun``, Π by
its quadrature-free ``ellippi``; the Arb route uses theta quotients and Carlson forms) at 40
more digits than the bound claims: the bound must hold for every value, and be no looser than
the two-precision estimate by more than a few digits.
"""

from __future__ import annotations

from fractions import Fraction

import mpmath
import pytest
from test_closed_form import CASES

from cayley_heyoka.core.balls import ball, bound, exact_mid
from cayley_heyoka.reference import FreeRigidBody, PrecisionNotReached
from cayley_heyoka.rotation import enclosures
from cayley_heyoka.rotation.attitude import rodrigues_to_matrix, rodrigues_to_quaternion

NAMES = ("p", "q", "r", "phi", "psi", "qw", "qx", "qy", "qz", "lambda", "mu", "nu")
ATTITUDE = ("0.5", "0.5", "0.5", "0.5")


def body(inertia, rates, dps, **kw) -> FreeRigidBody:
    return FreeRigidBody(inertia, rates, dps=dps, require_physical=False, **kw)


def truth(state) -> dict[str, mpmath.mpf]:
    q = state.quaternion
    out = {"p": state.p, "q": state.q, "r": state.r, "phi": state.phi, "psi": state.psi}
    out.update(zip(("qw", "qx", "qy", "qz"), q, strict=True))
    out.update(zip(("lambda", "mu", "nu"), (c / q[0] for c in q[1:]), strict=True))
    return out


def check_holds(inertia, rates, times, dps, **kw) -> None:
    proved = body(inertia, rates, dps, **kw)
    exact = body(inertia, rates, dps + 40, **kw)
    for t in times:
        bounds = proved.enclose(t)
        with mpmath.workdps(dps + 60):
            want = truth(exact.at(t))
            for name in NAMES:
                gap = abs(bounds.values[name] - want[name])
                assert gap <= bounds.bounds[name], (inertia, rates, t, name, gap)
        for name in NAMES[:9]:
            assert bounds.digits(name) >= dps, (t, name, bounds.digits(name))


@pytest.mark.parametrize("name", CASES)
def test_bounds_hold_on_the_reference_cases(name):
    """The seven reference bodies (both sides of the separatrix at 1.8e-5 from it, a nearly
    symmetric body, C intermediate), at their reference time, backwards, and far out."""
    case = CASES[name]
    attitude = {"attitude": ATTITUDE} if name in ("2", "4", "6") else {}
    times = ["0", case["t"], "-7.25", "123456.789"]
    check_holds(case["inertia"], case["rates"], times, 30, **attitude)


@pytest.mark.parametrize(
    ("inertia", "rates"),
    [
        (("1", "1", "2"), ("0.3", "0.4", "0.5")),  # symmetric about z₁: Ψ at a constant rate
        (("2", "1", "1"), ("0.3", "0.4", "0.5")),  # about x₁: r oscillates
        (("1", "2", "1"), ("0.3", "-0.4", "-0.5")),
        (("1", "1.5", "2.5"), ("0", "0", "1")),  # steady rotations
        (("1", "1.5", "2.5"), ("0.7", "0", "0")),
    ],
)
def test_bounds_hold_for_symmetric_and_steady_bodies(inertia, rates):
    check_holds(inertia, rates, ["0", "3.7", "-11", "2500.25"], 25, attitude=ATTITUDE)


def test_bounds_hold_next_to_the_separatrix():
    """1e-12 from the separatrix the closed form loses 12 digits to 1 − m: the working
    precision takes them back, and the bound is still proved."""
    rates = ("0.353553390593", "1", "0.125")  # case 3's body, nudged towards p² = 1/8
    check_holds(("1", "2", "4"), rates, ["15", "400"], 25)


def test_inputs_enter_exactly():
    """A decimal string is one tenth at any precision, a float its binary value: different
    numbers, and each ball holds its own."""
    tenth, binary = ball("0.1"), ball(0.1)
    assert binary.rad() == 0 and binary.mid() == ball(Fraction(0.1))
    with mpmath.workdps(60):
        gap = abs(exact_mid(tenth) - mpmath.mpf(1) / 10)
        assert gap <= bound(tenth)
        assert abs(exact_mid(binary) - mpmath.mpf(1) / 10) > bound(binary)
    # Signs survive every kind of number (mpmath's man_exp drops them), and each is exact.
    for x, exact in ((-0.3, mpmath.mpf(-0.3)), (-3, -3), ("-2.5", -2.5), (Fraction(-3, 4), -0.75)):
        b = ball(x)
        assert b.rad() == 0 and exact_mid(b) == exact, x


def test_float_and_text_inputs_give_their_own_motion():
    """Negative float rates and a negative float time: the same state as their text where the
    float is that decimal exactly (−0.375, −2.5), to within the bounds."""
    text = body(("1", "1.5", "2.5"), ("-0.375", "0.25", "-1"), 30).enclose("-2.5")
    floats = body((1.0, 1.5, 2.5), (-0.375, 0.25, -1.0), 30).enclose(-2.5)
    for name in NAMES:
        gap = abs(text.values[name] - floats.values[name])
        assert gap <= text.bounds[name] + floats.bounds[name], name


@pytest.mark.parametrize("given", ["rodrigues", "matrix"])
def test_the_attitude_as_a_scene_states_it(given):
    """Rodrigues parameters enter as the quaternion (1, λ, μ, ν), a matrix by its largest pivot,
    both exactly: the same motion as the unit quaternion they stand for (the matrix written to
    70 digits, so within 1e-69 of it)."""
    rho = ("0.1", "0.2", "-0.3")
    inertia, rates = ("1", "1.5", "2.5"), ("0.125", "0.25", "1")
    with mpmath.workdps(80):
        q = [mpmath.nstr(x, 75) for x in rodrigues_to_quaternion([mpmath.mpf(x) for x in rho])]
        R = rodrigues_to_matrix([mpmath.mpf(x) for x in rho])
        matrix = [[mpmath.nstr(x, 70) for x in row] for row in R]
    plain = body(inertia, rates, 30, attitude=q)
    kw = {"rodrigues": rho} if given == "rodrigues" else {"matrix": matrix}
    other = body(inertia, rates, 30, **kw)
    a, b = plain.enclose("3"), other.enclose("3")
    for name in ("qw", "qx", "qy", "qz", "p", "psi"):
        assert abs(a.values[name] - b.values[name]) <= a.bounds[name] + b.bounds[name] + 1e-60


def test_a_matrix_that_is_no_rotation_is_refused():
    inertia, rates = ("1", "1.5", "2.5"), ("0.1", "0.2", "1")
    with pytest.raises(ValueError, match="matrix: not a rotation"):
        body(inertia, rates, 30, matrix=[[1, 0, 0], [0, 1, 0], [0, 0, -1]])
    with pytest.raises(ValueError, match="matrix: expected 3 rows"):
        body(inertia, rates, 30, matrix=[[1, 0, 0]])
    with pytest.raises(ValueError, match="at most one of"):
        body(inertia, rates, 30, rodrigues=(0, 0, 0), matrix=[[1, 0, 0]] * 3)


def test_crossing_times_are_proved():
    case = CASES["1"]
    proved = body(case["inertia"], case["rates"], 30)
    exact = body(case["inertia"], case["rates"], 70)
    for axis in ("x1", "y1"):
        mine = proved.crossing_times(axis, "-10", "60", proved=True)
        theirs = exact.crossing_times(axis, "-10", "60")
        assert len(mine) == len(theirs) > 3
        for a, b in zip(mine, theirs, strict=True):
            assert a.proved and a.direction == b.direction
            with mpmath.workdps(90):
                assert abs(a.time - b.time) / max(1, abs(a.time)) <= a.error
        assert "bound" in repr(mine[0])


def test_a_bound_that_cannot_be_proved_is_reported(monkeypatch):
    """Working precisions too low for the digits asked: the bound reached is named, not
    returned as if it were enough."""
    monkeypatch.setattr(enclosures, "_attempts", lambda dps, extra: [40])
    case = CASES["1"]
    with pytest.raises(PrecisionNotReached, match="30"):
        body(case["inertia"], case["rates"], 30).enclose("10")
