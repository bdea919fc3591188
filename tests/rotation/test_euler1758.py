"""Euler's 1758 solution against 25-digit test values (below)."""

from __future__ import annotations

import mpmath
import pytest

from cayley_heyoka.core.accuracy import scaled_difference
from cayley_heyoka.rotation.euler1758 import Euler1758, ThetaPoint, quarter_sin_cos

# Inputs (A, B, C; p, q, r; P in body axes; t) and outputs at t, from the reference note.
CASES = {
    "R1": {
        "inertia": ("1", "2", "3"),
        "rates": ("0.25", "-0.15", "1.2"),
        "direction": ("0.48", "0.6", "0.64"),
        "t": "7.5",
        "period": "5.2482464783772324890",
        "U0": "0.30083007017726249010",
        "phi0": "1.3942547016872717986",
        "p": "-0.1608649947737563963620902",
        "q": "0.2431510918265417275089078",
        "r": "1.194902722197300973342109",
        "u": "0.01831122672821966364240125",
        "v": "0.7202054234712652112430807",
        "U": "18.48364550705902758485233",
        "cos_l": "-0.2438606529697564610718350",
        "cos_m": "-0.6655985531525695643164415",
        "cos_n": "0.7053442762044433275846060",
        "phi_plus_F": "1.445425409690030439568708",
    },
    "R2": {
        "inertia": ("1", "2", "3"),
        "rates": ("1.5", "0.2", "-0.25"),
        "direction": ("0", "0.6", "-0.8"),
        "t": "11",
        "period": "7.3808919762257677136",
        "U0": "-1.8724795939234759561",
        "phi0": "1.6639135463861388942",
        "p": "1.496254884153549553858816",
        "q": "-0.2263212797035400385107096",
        "r": "0.2424037117106859235218157",
        "u": "0.005610660823324002090937350",
        "v": "0.6603523450427285668920713",
        "U": "6.157202980044119863845671",
        "cos_l": "0.4280630930317795103275944",
        "cos_m": "0.6182624647777490424964158",
        "cos_n": "0.6591763899223095692515627",
        "phi_plus_F": "1.230401349613786771628141",
    },
    "R3": {
        "inertia": ("1", "2", "3"),
        "rates": ("0.5", "0.2", "0.288675"),
        "direction": ("0.6", "0", "0.8"),
        "t": "40",
        "period": "108.11016659302388788",
        "U0": "2.8279012480030082362",
        "phi0": "2.7094676292087058947",
        "p": "0.02012359778301952016081978",
        "q": "0.5381403541942076395700520",
        "r": "-0.01161501991292235002711206",
        "u": "0.1247975204061336259265905",
        "v": "0.4920362439114593384215994",
        "U": "23.32148307450118196493980",
        "cos_l": "-0.3549642488758898199245953",
        "cos_m": "0.9246194666499029030434324",
        "cos_n": "-0.1381275639111341381291243",
        "phi_plus_F": "1.583420357542856927391559",
    },
    "R4": {
        "inertia": ("2", "3", "1"),
        "rates": ("0.7", "0.4", "0.69282"),
        "direction": ("0.36", "-0.48", "0.8"),
        "t": "70",
        "period": "61.064939224198160751",
        "U0": "1.2946033187934774591",
        "phi0": "1.4447355621940751564",
        "p": "0.9848727991770291640196033",
        "q": "0.002919442937912552260971059",
        "r": "0.005012169311104965399292282",
        "u": "0.2399872152793984087882864",
        "v": "0.2388100222451376173132867",
        "U": "74.42922217166323065132739",
        "cos_l": "0.2476057691900286786295613",
        "cos_m": "-0.07093977318815715403116528",
        "cos_n": "-0.9662602815203712305229553",
        "phi_plus_F": "1.569077979277592179176730",
    },
    "R5": {
        "inertia": ("2.5", "1.3", "3.1"),
        "rates": ("0.4", "-0.9", "0.7"),
        "direction": ("0.28", "-0.96", "0"),
        "t": "45",
        "period": "17.141426740224651395",
        "U0": "1.4201136325455713864",
        "phi0": "1.4736044494249585259",
        "p": "-0.9708417829437785895231044",
        "q": "-0.5553159371547351247749680",
        "r": "-0.2632164901632142261802480",
        "u": "-0.5434262274371214584880780",
        "v": "0.8138007718236733264746946",
        "U": "45.73465034448639685633978",
        "cos_l": "-0.2745342411479176189918292",
        "cos_m": "-0.9600788999875079495741641",
        "cos_n": "-0.05366056499994874746686417",
        "phi_plus_F": "1.630661549640661992941705",
    },
}
OUTPUTS = ("p", "q", "r", "u", "v", "U", "cos_l", "cos_m", "cos_n", "phi_plus_F")


def close(value, reference: str, tol: str) -> bool:
    with mpmath.workdps(50):
        return scaled_difference(mpmath.mpf(value), mpmath.mpf(reference)) < mpmath.mpf(tol)


@pytest.fixture(scope="module")
def solutions() -> dict[str, Euler1758]:
    return {
        name: Euler1758(case["inertia"], case["rates"], case["direction"], dps=30)
        for name, case in CASES.items()
    }


@pytest.fixture(scope="module")
def states(solutions):
    return {name: solutions[name].at(CASES[name]["t"]) for name in CASES}


@pytest.mark.parametrize("name", CASES)
def test_reference_values(states, name):
    state, case = states[name], CASES[name]
    assert state.t == mpmath.mpf(case["t"])
    for quantity in OUTPUTS:
        assert close(getattr(state, quantity), case[quantity], "1e-24"), quantity
        assert state.errors[quantity] < mpmath.mpf("1e-30"), quantity
    assert state.error == max(state.errors.values())


@pytest.mark.parametrize("name", CASES)
def test_additive_constants_and_period(solutions, name):
    solution, case = solutions[name], CASES[name]
    start = solution.at(0)
    assert close(start.U, case["U0"], "1e-19")
    assert close(start.phi_plus_F, case["phi0"], "1e-19")
    for quantity, initial in zip(("p", "q", "r"), case["rates"], strict=True):
        assert close(getattr(start, quantity), initial, "1e-30")
    assert abs(start.u) < mpmath.mpf("1e-30")
    assert close(solution.period, case["period"], "1e-19")
    with mpmath.workdps(50):
        assert close(4 * solution.quarter_period, case["period"], "1e-19")


def test_sixty_digits():
    case = CASES["R2"]
    fine = Euler1758(case["inertia"], case["rates"], case["direction"], dps=60).at(case["t"])
    coarse = Euler1758(case["inertia"], case["rates"], case["direction"], dps=30).at(case["t"])
    for quantity in OUTPUTS:
        assert fine.errors[quantity] < mpmath.mpf("1e-60"), quantity
        assert close(getattr(fine, quantity), getattr(coarse, quantity), "1e-29"), quantity
        assert close(getattr(fine, quantity), case[quantity], "1e-24"), quantity


def test_backwards_in_time_returns_to_the_start(solutions):
    """From the state at t = −τ, the motion reaches the t = 0 state after τ; U advances alike."""
    case, tau = CASES["R5"], mpmath.mpf("23.75")
    solution = solutions["R5"]
    past = solution.at(-tau)
    with mpmath.workdps(40):
        direction = (past.cos_l, past.cos_m, past.cos_n)
        replay = Euler1758(case["inertia"], (past.p, past.q, past.r), direction, dps=30)
        end = replay.at(tau)
        for quantity, initial in zip(("p", "q", "r"), case["rates"], strict=True):
            assert close(getattr(end, quantity), initial, "1e-25")
        for quantity, initial in zip(("cos_l", "cos_m", "cos_n"), case["direction"], strict=True):
            assert close(getattr(end, quantity), initial, "1e-25")
        # U − π/2 is the azimuth of ω about L from the half-plane holding P: its increments
        # do not depend on where the motion is started.
        assert close(end.U - replay.at(0).U, solution.at(0).U - past.U, "1e-25")


def test_many_periods_against_quarter_by_quarter_quadrature(solutions):
    """The whole-period shortcut of U against integrating dU/dΘ over every quarter."""
    solution = solutions["R5"]
    t = 3.3 * mpmath.mpf(CASES["R5"]["period"])
    state = solution.at(t)
    with mpmath.workdps(42):
        k = solution.constants(42)
        motion = k.motion
        end = motion.theta_at(mpmath.mpf(state.t))
        start = motion.theta0
        total = -k.U.partial(start.quarter, start.offset)
        for quarter in range(start.quarter, end.quarter):
            total += mpmath.quad(
                lambda x, j=quarter: k.dU_dtheta(*quarter_sin_cos(j, x)), [0, mpmath.pi / 2]
            )
        total += k.U.partial(end.quarter, end.offset)
        assert end.quarter - start.quarter > 12
        assert close(state.U, k.U0 + total, "1e-30")


def test_symmetric_body_against_the_elementary_solution():
    """A = B: r constant, p + iq turns at n = (C − A)r/A, and P_b(t) = R_z(nt) R_L(−kt/A) P(0)."""
    solution = Euler1758(("1", "1", "2"), ("0.3", "0.4", "1"), ("0.6", "0", "0.8"))
    with mpmath.workdps(40):
        A, C = mpmath.mpf(1), mpmath.mpf(2)
        p0, q0, r0 = mpmath.mpf("0.3"), mpmath.mpf("0.4"), mpmath.mpf(1)
        momentum = [A * p0, A * q0, C * r0]
        k = mpmath.sqrt(sum(x * x for x in momentum))
        axis = [x / k for x in momentum]
        for t in ("2.5", "-4", "40"):
            state = solution.at(t)
            t = mpmath.mpf(t)
            turn = (C - A) * r0 / A * t
            rates = (p0 + 1j * q0) * mpmath.expj(turn)
            assert close(state.p, rates.real, "1e-30")
            assert close(state.q, rates.imag, "1e-30")
            assert close(state.r, r0, "1e-30")
            P = [mpmath.mpf("0.6"), mpmath.mpf(0), mpmath.mpf("0.8")]
            P = _rotate(P, axis, -k * t / A)
            P = _rotate(P, [0, 0, 1], turn)
            for quantity, value in zip(("cos_l", "cos_m", "cos_n"), P, strict=True):
                assert close(getattr(state, quantity), value, "1e-29"), quantity


def _rotate(v, axis, angle):
    """Rodrigues' rotation of v by ``angle`` about the unit ``axis``."""
    c, s = mpmath.cos(angle), mpmath.sin(angle)
    dot = sum(a * b for a, b in zip(axis, v, strict=True))
    cross = [
        axis[1] * v[2] - axis[2] * v[1],
        axis[2] * v[0] - axis[0] * v[2],
        axis[0] * v[1] - axis[1] * v[0],
    ]
    return [v[i] * c + cross[i] * s + axis[i] * dot * (1 - c) for i in range(3)]


def _unwrapped_on_a_grid(solution: Euler1758, end: mpmath.mpf, per_quarter: int):
    """φ + 𝔉 by unwrapping Euler's principal atan2 along a fine grid in Θ (Euler's recipe),
    next to the value the solution returns at each grid point."""
    with mpmath.workdps(24):
        k = solution.constants(24)
        start = k.motion.theta0.value
        theta_end = k.motion.theta_at(end).value
        count = int(abs(theta_end - start) / (mpmath.pi / 2) * per_quarter) + 1
        unwrapped, returned, steps = [], [], []
        for i in range(count + 1):
            point = ThetaPoint.of(start + (theta_end - start) * i / count)
            U = k.U_at(point)
            s = mpmath.sqrt(k.s_squared(k.motion.at(*quarter_sin_cos(*point)).rates))
            principal = k.phi_principal(U, s)
            if unwrapped:
                step = principal - unwrapped[-1]
                step -= 2 * mpmath.pi * mpmath.nint(step / (2 * mpmath.pi))
                steps.append(abs(step))
                principal = unwrapped[-1] + step
            unwrapped.append(principal)
            returned.append(k.phi_at(point, U, s))
        return unwrapped, returned, max(steps)


@pytest.mark.parametrize(
    ("inputs", "regime", "end"),
    [
        # P 8.8° from L, ω 15°–18° from it: ω circles P and φ + 𝔉 winds.
        ((("1", "2", "3"), ("1.5", "0.2", "-0.25"), ("0.8", "0.36", "-0.48")), "lift", "-20"),
        # R3: ω swings between 0.03° and 30° from L, P at 23°: ω passes P on either side.
        ((CASES["R3"]["inertia"], CASES["R3"]["rates"], CASES["R3"]["direction"]), "mixed", "130"),
    ],
)
def test_phi_branch_against_unwrapping_on_a_grid(inputs, regime, end):
    solution = Euler1758(*inputs, dps=12)
    assert solution.constants(24).phi_regime == regime
    unwrapped, returned, largest_step = _unwrapped_on_a_grid(solution, mpmath.mpf(end), 16)
    assert largest_step < 1  # the grid resolves φ + 𝔉 (a wrong branch is a 2π step)
    assert abs(unwrapped[-1] - unwrapped[0]) > 2 * mpmath.pi  # it winds or crosses ±π
    for a, b in zip(unwrapped, returned, strict=True):
        assert abs(a - b) < mpmath.mpf("1e-20")


def test_phi_rate_is_eulers_equation():
    """A central difference of φ + 𝔉 against Euler's dφ/dt (§8), in the winding case."""
    solution = Euler1758(("1", "2", "3"), ("1.5", "0.2", "-0.25"), ("0.8", "0.36", "-0.48"), dps=12)
    with mpmath.workdps(24):
        k = solution.constants(24)
        L, M, N = k.motion.c
        fA, fB, fC = k.motion.frak
        h = mpmath.mpf("1e-6")
        for t in ("1.3", "7.7", "-1.1", "300.2"):
            t = mpmath.mpf(t)
            s = solution.at(t)
            rate = (
                s.p * (M * fC - N * fB) * s.cos_l
                + s.q * (N * fA - L * fC) * s.cos_m
                + s.r * (L * fB - M * fA) * s.cos_n
            ) / (k.E - 2 * k.LMN * s.u - s.v**2)
            difference = (solution.at(t + h).phi_plus_F - solution.at(t - h).phi_plus_F) / (2 * h)
            assert abs(difference - rate) < mpmath.mpf("1e-9")


def test_theta_point_arithmetic():
    with mpmath.workdps(30):
        for theta in (mpmath.mpf("-2.5"), mpmath.mpf("0"), mpmath.mpf("7.9")):
            point = ThetaPoint.of(theta)
            assert 0 <= point.offset <= mpmath.pi / 2
            assert abs(point.value - theta) < mpmath.mpf("1e-28")
            s, c = quarter_sin_cos(*point)
            assert abs(s - mpmath.sin(theta)) < mpmath.mpf("1e-28")
            assert abs(c - mpmath.cos(theta)) < mpmath.mpf("1e-28")


GOOD = {
    "inertia": ("1", "2", "3"),
    "rates": ("0.25", "-0.15", "1.2"),
    "direction": (0.48, 0.6, 0.64),
}
BAD_INPUTS = [
    ("inertia", {"inertia": ("0", "2", "3")}),
    ("inertia", {"inertia": ("-1", "2", "3")}),
    ("inertia", {"inertia": ("1", "2", "3.5")}),
    ("inertia", {"inertia": ("1", "inf", "3")}),
    ("inertia", {"inertia": ("1", "2")}),
    ("rates", {"rates": ("0", "0", "0")}),
    ("rates", {"rates": ("nan", "0", "1")}),
    ("rates", {"rates": ("0", "0", "1")}),  # steady rotation about a principal axis
    ("rates", {"inertia": ("1", "2", "2.25"), "rates": ("0.75", "0.5", "1")}),  # separatrix
    ("direction", {"direction": ("0.5", "0.6", "0.64")}),
    ("direction", {"direction": ("0.48", "0.6", "inf")}),
    ("direction", {"direction": ("1", "0")}),
    ("direction", {"rates": ("1", "0.375", "0"), "direction": ("0.8", "0.6", "0")}),  # ∥ L
    ("direction", {"rates": ("1", "0.375", "0"), "direction": ("-0.8", "-0.6", "0")}),  # anti-∥
]


@pytest.mark.parametrize(("parameter", "change"), BAD_INPUTS)
def test_bad_input_names_the_parameter(parameter, change):
    with pytest.raises(ValueError, match=parameter):
        Euler1758(**{**GOOD, **change})


@pytest.mark.parametrize("dps", [4, 3.5, True, "30"])
def test_bad_dps(dps):
    with pytest.raises(ValueError, match="dps"):
        Euler1758(**GOOD, dps=dps)


@pytest.mark.parametrize("t", ["inf", float("nan"), "-inf"])
def test_bad_time(solutions, t):
    with pytest.raises(ValueError, match=r"^t\b"):
        solutions["R1"].at(t)
