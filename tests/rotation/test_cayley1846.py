"""Cayley's 1846 solution against 25-digit test values (below), and against Euler's."""

from __future__ import annotations

import mpmath
import pytest

from cayley_heyoka.core.accuracy import scaled_difference
from cayley_heyoka.rotation.attitude import matvec, quaternion_to_matrix, rodrigues_to_matrix
from cayley_heyoka.rotation.cayley1846 import Cayley1846
from cayley_heyoka.rotation.euler1758 import Euler1758

# Inputs (A, B, C; p, q, r; λ₀, μ₀, ν₀; P in body axes for the cross-check with Euler; t),
# derived constants and outputs at t, from the reference note.
CASES = {
    "R1": {
        "inertia": ("1", "2", "3"),
        "rates": ("0.25", "-0.15", "1.2"),
        "rodrigues": ("0.1", "0.2", "-0.3"),
        "direction": ("0.48", "0.6", "0.64"),
        "t": "7.5",
        "abc": ("1.0982456140350877193", "-1.3807017543859649123", "3.1622807017543859649"),
        "k": "3.6211186116999813073",
        "h": "4.4275000000000000000",
        "upsilon0": "12.592741228070175439",
        "angle0": "-0.59740634853596186376",
        "turning_points": 3,
        "p": "-0.1608649947737563963620902",
        "q": "0.2431510918265417275089078",
        "r": "1.194902722197300973342109",
        "upsilon": "11.80012295177066388607523",
        "omega_over_k": "2.075173499164030029258066",
        "angle": "8.526672295085886095340878",
    },
    "R2": {
        "inertia": ("1", "2", "3"),
        "rates": ("1.5", "0.2", "-0.25"),
        "rodrigues": ("-0.3", "0.4", "0.5"),
        "direction": ("0", "0.6", "-0.8"),
        "t": "11",
        "abc": ("0.099333333333333333333", "0.47866666666666666667", "-1.6533333333333333333"),
        "k": "1.7240939649566667397",
        "h": "2.5175000000000000000",
        "upsilon0": "2.2764833333333333333",
        "angle0": "-0.73625379527988455672",
        "turning_points": 3,
        "p": "1.496254884153549553858816",
        "q": "-0.2263212797035400385107096",
        "r": "0.2424037117106859235218157",
        "upsilon": "0.8510703349856973724070920",
        "omega_over_k": "-2.765689525764923823712073",
        "angle": "16.40185894617779633482811",
    },
    "R3": {
        "inertia": ("1", "2", "3"),
        "rates": ("0.5", "0.2", "0.288675"),
        "rodrigues": ("0.6", "-0.2", "0.4"),
        "direction": ("0.6", "0", "0.8"),
        "t": "40",
        "abc": ("0.14953974358974358974", "-0.44217564102564102564", "0.97062756410256410256"),
        "k": "1.0770326367501590246",
        "h": "0.57999976687500000000",
        "upsilon0": "0.94924332610576923077",
        "angle0": "0.96830242431359932053",
        "turning_points": 0,
        "p": "0.02012359778301952016081978",
        "q": "0.5381403541942076395700520",
        "r": "-0.01161501991292235002711206",
        "upsilon": "0.3266409453335747684352179",
        "omega_over_k": "-11.37103137915003291775041",
        "angle": "22.16658277926419191403246",
    },
    "R4": {
        "inertia": ("2", "3", "1"),
        "rates": ("0.7", "0.4", "0.69282"),
        "rodrigues": ("0.9", "-0.6", "1.1"),
        "direction": ("0.36", "-0.48", "0.8"),
        "t": "70",
        "abc": ("-0.90520721893491124260", "-0.40994035502958579882", "1.7007493491124260355"),
        "k": "1.9697714467419817892",
        "h": "1.9399995524000000000",
        "upsilon0": "1.6495470919538461538",
        "angle0": "1.1681972190696962744",
        "turning_points": 2,
        "p": "0.9848727991770291640196033",
        "q": "0.002919442937912552260971059",
        "r": "0.005012169311104965399292282",
        "upsilon": "1.050952834287386878770777",
        "omega_over_k": "-0.05548687087582176820402564",
        "angle": "69.00417831568927629181208",
    },
    "R5": {
        "inertia": ("2.5", "1.3", "3.1"),
        "rates": ("0.4", "-0.9", "0.7"),
        "rodrigues": ("1.5", "-2.0", "0.8"),
        "direction": ("0.28", "-0.96", "0"),
        "t": "45",
        "abc": ("0.51077313054499366286", "-2.5757541191381495564", "-0.42708491761723700887"),
        "k": "2.6604135016948023300",
        "h": "2.9720000000000000000",
        "upsilon0": "4.8377155893536121673",
        "angle0": "2.2512415906038587751",
        "turning_points": 11,
        "p": "-0.9708417829437785895231044",
        "q": "-0.5553159371547351247749680",
        "r": "-0.2632164901632142261802480",
        "upsilon": "4.023026861410619399149109",
        "omega_over_k": "-0.07175829686520279171192204",
        "angle": "62.68858205421554598726502",
    },
}
OUTPUTS = ("p", "q", "r", "upsilon", "omega_over_k", "angle")
FIELDS = OUTPUTS + ("kappa", "lambda_", "mu", "nu")
QUATERNION = ("quaternion_w", "quaternion_x", "quaternion_y", "quaternion_z")
# Times for the structural checks: both signs, several periods, and Ω/k ≈ 7400 (R1 passes the
# half-turn θ = π at t = 3.0922281).
TIMES = ("0", "-3.7", "3.092", "7.5", "90.25")


def close(value, reference, tol: str) -> bool:
    with mpmath.workdps(50):
        return scaled_difference(mpmath.mpf(value), mpmath.mpf(reference)) < mpmath.mpf(tol)


@pytest.fixture(scope="module")
def solutions() -> dict[str, Cayley1846]:
    return {
        name: Cayley1846(case["inertia"], case["rates"], case["rodrigues"], dps=30)
        for name, case in CASES.items()
    }


@pytest.fixture(scope="module")
def states(solutions):
    return {name: solutions[name].at(CASES[name]["t"]) for name in CASES}


@pytest.mark.parametrize("name", CASES)
def test_reference_values(states, name):
    state, case = states[name], CASES[name]
    for quantity in OUTPUTS:
        assert close(getattr(state, quantity), case[quantity], "1e-24"), quantity
    for quantity in FIELDS + QUATERNION:
        assert state.errors[quantity] < mpmath.mpf("1e-30"), quantity
    assert state.error == max(state.errors.values())


@pytest.mark.parametrize("name", CASES)
def test_constants_and_initial_values(solutions, name):
    solution, case = solutions[name], CASES[name]
    for value, reference in zip((solution.a, solution.b, solution.c), case["abc"], strict=True):
        assert close(value, reference, "1e-19")
    assert close(solution.k, case["k"], "1e-19")
    assert close(solution.h, case["h"], "1e-19")
    start = solution.at(0)
    assert close(start.upsilon, case["upsilon0"], "1e-19")
    assert close(start.angle, case["angle0"], "1e-19")
    for value, reference in zip(start.rodrigues, case["rodrigues"], strict=True):
        assert close(value, reference, "1e-30")


def test_sixty_digits():
    case = CASES["R1"]
    args = (case["inertia"], case["rates"], case["rodrigues"])
    fine = Cayley1846(*args, dps=60).at(case["t"])
    coarse = Cayley1846(*args, dps=30).at(case["t"])
    for quantity in FIELDS + QUATERNION:
        assert fine.errors[quantity] < mpmath.mpf("1e-60"), quantity
    for quantity in FIELDS:
        assert close(getattr(fine, quantity), getattr(coarse, quantity), "1e-29"), quantity
    for quantity in OUTPUTS:
        assert close(getattr(fine, quantity), case[quantity], "1e-24"), quantity


def _check_upsilon_quadratures(solution, name):
    case = CASES[name]
    result = solution.quadratures_in_upsilon(case["t"])
    with mpmath.workdps(50):
        increment = solution.at(case["t"]).angle - solution.at(0).angle
    assert result.turning_points == case["turning_points"]
    assert close(result.t, case["t"], "1e-25")
    assert close(result.angle_increment, increment, "1e-25")
    assert result.error < mpmath.mpf("1e-30")


@pytest.mark.parametrize("name", ["R1", "R2"])
def test_upsilon_quadratures(solutions, name):
    _check_upsilon_quadratures(solutions[name], name)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["R3", "R4", "R5"])
def test_upsilon_quadratures_slow(solutions, name):
    _check_upsilon_quadratures(solutions[name], name)


def test_upsilon_quadratures_backwards(solutions):
    solution = solutions["R2"]
    result = solution.quadratures_in_upsilon("-4.5")
    with mpmath.workdps(50):
        increment = solution.at("-4.5").angle - solution.at(0).angle
    assert close(result.t, "-4.5", "1e-25")
    assert close(result.angle_increment, increment, "1e-25")


@pytest.mark.parametrize("name", ["R1", "R2", "R5"])
def test_attitude_carries_body_momentum_to_the_constant_space_momentum(solutions, name):
    solution = solutions[name]
    with mpmath.workdps(45):
        A, B, C = (mpmath.mpf(x) for x in CASES[name]["inertia"])
        for t in TIMES:
            s = solution.at(t)
            momentum = (A * s.p, B * s.q, C * s.r)
            space = matvec(rodrigues_to_matrix(s.rodrigues), momentum)
            for value, constant in zip(space, (solution.a, solution.b, solution.c), strict=True):
                assert close(value, constant, "1e-28")
            space = matvec(quaternion_to_matrix(s.quaternion), momentum)
            for value, constant in zip(space, (solution.a, solution.b, solution.c), strict=True):
                assert close(value, constant, "1e-28")
            # (13) against the definition of κ, and the quaternion against (14)
            assert close(s.kappa, 1 + s.lambda_**2 + s.mu**2 + s.nu**2, "1e-28")
            w, x, y, z = s.quaternion
            assert close(w * w + x * x + y * y + z * z, 1, "1e-30")
            for component, parameter in zip((x, y, z), s.rodrigues, strict=True):
                assert close(component / w, parameter, "1e-28")


def test_quaternion_is_continuous_through_a_half_turn(solutions):
    """R1 near t = 3.0922: Ω/k passes through ∞ (the angle through π); w changes sign."""
    solution = solutions["R1"]
    states = [solution.at(mpmath.mpf("3.035") + mpmath.mpf("0.01") * i) for i in range(12)]
    angles = [s.angle for s in states]
    assert angles[0] < mpmath.pi < angles[-1]
    assert max(abs(s.omega_over_k) for s in states) > 100
    for a, b in zip(states, states[1:], strict=False):
        assert max(abs(x - y) for x, y in zip(a.quaternion, b.quaternion, strict=True)) < 0.02
    signs = {s.quaternion[0] > 0 for s in states}
    assert signs == {True, False}


@pytest.mark.parametrize("name", ["R1", "R2", "R4", "R5"])
def test_euler_cosines_equal_the_rotated_fixed_direction(solutions, name):
    """Cross-check of the two solutions: (cos l, cos m, cos n)(t) = R(t)ᵀ R(0) P(0)."""
    case, solution = CASES[name], solutions[name]
    euler = Euler1758(case["inertia"], case["rates"], case["direction"], dps=30)
    with mpmath.workdps(45):
        norm = mpmath.sqrt(sum(mpmath.mpf(x) ** 2 for x in case["direction"]))
        P = [mpmath.mpf(x) / norm for x in case["direction"]]
        P_space = matvec(rodrigues_to_matrix([mpmath.mpf(x) for x in case["rodrigues"]]), P)
        times = TIMES if name != "R4" else ("70",)
        for t in times:
            s, e = solution.at(t), euler.at(t)
            R = quaternion_to_matrix(s.quaternion)
            body = [sum(R[i][j] * P_space[i] for i in range(3)) for j in range(3)]
            for quantity, value in zip(("cos_l", "cos_m", "cos_n"), body, strict=True):
                assert close(getattr(e, quantity), value, "1e-25"), (t, quantity)
            for quantity in ("p", "q", "r"):
                assert close(getattr(e, quantity), getattr(s, quantity), "1e-30")


def test_symmetric_body():
    """A = B: the motion is elementary, and R(t)·L_b(t) stays (a, b, c)."""
    solution = Cayley1846(("2", "2", "1"), ("0.3", "-0.4", "1"), ("0.2", "0.1", "-0.5"))
    with mpmath.workdps(45):
        p0, q0 = mpmath.mpf("0.3"), mpmath.mpf("-0.4")
        n = (mpmath.mpf(1) - 2) / 2  # (C − A) r / A
        for t in ("3", "-11"):
            s = solution.at(t)
            rates = (p0 + 1j * q0) * mpmath.expj(n * mpmath.mpf(t))
            assert close(s.p, rates.real, "1e-30")
            assert close(s.q, rates.imag, "1e-30")
            assert close(s.r, 1, "1e-30")
            space = matvec(quaternion_to_matrix(s.quaternion), (2 * s.p, 2 * s.q, s.r))
            for value, constant in zip(space, (solution.a, solution.b, solution.c), strict=True):
                assert close(value, constant, "1e-28")


GOOD = {
    "inertia": ("1", "2", "3"),
    "rates": ("0.25", "-0.15", "1.2"),
    "rodrigues": (0.1, 0.2, -0.3),
}
BAD_INPUTS = [
    ("inertia", {"inertia": ("1", "0", "3")}),
    ("inertia", {"inertia": ("1", "5", "3")}),
    ("inertia", {"inertia": "123"}),
    ("rates", {"rates": (0.0, 0.0, 0.0)}),
    ("rates", {"rates": ("1", "inf", "0")}),
    ("rates", {"rates": ("0", "2", "0")}),  # steady rotation about the middle axis
    ("rodrigues", {"rodrigues": ("0.1", "nan", "0")}),
    ("rodrigues", {"rodrigues": ("0.1", "0.2")}),
]


@pytest.mark.parametrize(("parameter", "change"), BAD_INPUTS)
def test_bad_input_names_the_parameter(parameter, change):
    with pytest.raises(ValueError, match=parameter):
        Cayley1846(**{**GOOD, **change})


@pytest.mark.parametrize("dps", [0, 4, 30.0])
def test_bad_dps(dps):
    with pytest.raises(ValueError, match="dps"):
        Cayley1846(**GOOD, dps=dps)


def test_bad_time(solutions):
    with pytest.raises(ValueError, match=r"^t\b"):
        solutions["R1"].at("nan")
    with pytest.raises(ValueError, match=r"^t\b"):
        solutions["R1"].quadratures_in_upsilon(float("inf"))
