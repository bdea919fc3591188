"""Hamilton's projectile (1835, §24–27) in closed form: reference values, S and its derivatives.

Values: 20 significant digits of the closed form evaluated at 40 digits and cross-checked by an
independent 40-digit ODE solution, kept below. The other checks
are independent of the module's formulas: an mpmath Taylor ODE solution of the canonical
equations with S as an extra component, Hamilton's own arrangement of (120.) evaluated as
printed, finite differences of S, the Hamilton–Jacobi pair (121.) and the parabola of §5.4.
"""

from __future__ import annotations

import math

import mpmath
import pytest

from cayley_heyoka.core.accuracy import scaled_difference
from cayley_heyoka.hamilton.projectile import (
    PrincipalFunction,
    ProjectileSolution,
    principal_function,
    projectile_solution,
)

CASES = {
    "R1": {
        "g": "1",
        "mu": "0.3",
        "nu": "0.45",
        "t": "2.5",
        "e": ("0.2", "-0.4", "1.5"),
        "p": ("0.7", "0.3", "2.1"),
        "eta": ("1.7368282138292105663", "0.38896321247380581221", "2.0483420256785479340"),
        "varpi": ("0.47128388261027457041", "0.30130331186494636590", "-1.7085990387376795151"),
        "S": "-6.0981388215878366413",
    },
    "R2": {
        "g": "9.80665",
        "mu": "0.05",
        "nu": "0.08",
        "t": "4.75",
        "e": ("1", "2", "0"),
        "p": ("10", "-3", "25"),
        "eta": ("48.026637435211290111", "-12.172554081213560219", "6.6062480159921221683"),
        "varpi": ("9.7075282766349387433", "-2.9393149402283906581", "-22.251974377697575248"),
        "S": "-338.11481545921755076",
    },
    "R3": {
        "g": "0.5",
        "mu": "1.3",
        "nu": "0.7",
        "t": "7.1",
        "e": ("-1.1", "0.6", "0.25"),
        "p": ("-0.4", "1.9", "0.8"),
        "eta": ("1.0196462901693942404", "-0.30577553354116324342", "-1.8018892697133725910"),
        "varpi": ("0.66921090739393033682", "-2.0150402566743108742", "1.0637574201679436020"),
        "S": "0.74666227596551578993",
    },
    "R4": {
        "g": "2",
        "mu": "0.01",
        "nu": "0.02",
        "t": "11",
        "e": ("0", "0", "0"),
        "p": ("3", "4", "12"),
        "eta": ("32.933490251152442599", "43.911320334869923466", "10.425020501549039001"),
        "varpi": ("2.9818682938700905511", "3.9758243918267874014", "-10.112192916119666122"),
        "S": "-196.79868510670522129",
    },
}

# Beyond the table: a frequency that vanishes, a tiny one, t < 0, μt just short of π (a
# conjugate point), a long span and a float input at its binary value.
EXTRA = {
    "parabola": {**CASES["R1"], "mu": "0", "nu": "0"},
    "flat": {**CASES["R2"], "mu": "0", "nu": "1e-20"},
    "backwards": {**CASES["R3"], "t": "-3.7"},
    "near_conjugate": {**CASES["R1"], "mu": "3.1415926", "t": "1"},
    "long": {**CASES["R3"], "t": "250"},
    "float": {**CASES["R1"], "g": 9.81, "mu": 0.3, "t": 2.5},
}
ALL = {**CASES, **EXTRA}

SOLUTION_KEYS = ("eta1", "eta2", "eta3", "varpi1", "varpi2", "varpi3", "S")
PRINCIPAL_KEYS = ("S", "d_eta1", "d_eta2", "d_eta3", "d_e1", "d_e2", "d_e3", "d_t")


def solve(case: dict, dps: int = 30) -> ProjectileSolution:
    c = case
    return projectile_solution(c["g"], c["mu"], c["nu"], c["e"], c["p"], c["t"], dps=dps)


def principal_at_solution(
    case: dict, dps: int = 30
) -> tuple[ProjectileSolution, PrincipalFunction]:
    c = case
    sol = solve(case, dps)
    return sol, principal_function(sol.eta, c["e"], c["t"], c["g"], c["mu"], c["nu"], dps=dps)


def solution_values(sol: ProjectileSolution) -> list:
    return [*sol.eta, *sol.varpi, sol.S]


def principal_values(pf: PrincipalFunction) -> list:
    return [pf.S, *pf.d_eta, *pf.d_e, pf.d_t]


def mp(x) -> mpmath.mpf:
    return mpmath.mpf(x)


def hamiltonian(eta, varpi, g, mu, nu) -> mpmath.mpf:
    """H = ½|ϖ|² + gη₃ + ½{μ²(η₁² + η₂²) + ν²η₃²} (the convention of the values below)."""
    g, mu, nu = mp(g), mp(mu), mp(nu)
    return (
        sum(x * x for x in varpi) / 2
        + g * eta[2]
        + (mu**2 * (eta[0] ** 2 + eta[1] ** 2) + nu**2 * eta[2] ** 2) / 2
    )


# -- the reference values -----------------------------------------------------------------------


@pytest.mark.parametrize("dps", [30, 50])
@pytest.mark.parametrize("name", sorted(CASES))
def test_reference_values(name: str, dps: int) -> None:
    case = CASES[name]
    sol = solve(case, dps)
    expected = [*case["eta"], *case["varpi"], case["S"]]
    with mpmath.workdps(dps + 10):
        for key, got, want in zip(SOLUTION_KEYS, solution_values(sol), expected, strict=True):
            assert abs(got - mp(want)) <= mp("1e-19") * abs(mp(want)), key
    assert sol.error <= mpmath.mpf(10) ** -dps


# -- S is the principal function: its derivatives are ϖ, −p and −H ------------------------------


@pytest.mark.parametrize("name", sorted(ALL))
def test_derivatives_are_momenta_and_energy(name: str) -> None:
    case = ALL[name]
    sol, pf = principal_at_solution(case)
    tol = mp("1e-28")
    with mpmath.workdps(40):
        assert scaled_difference(pf.S, sol.S) <= tol  # (120.) at η(t) is ∫(T + U)dt
        for i in range(3):
            assert scaled_difference(pf.d_eta[i], sol.varpi[i]) <= tol, f"dS/deta{i + 1}"
            assert scaled_difference(-pf.d_e[i], mp(case["p"][i])) <= tol, f"dS/de{i + 1}"
        energy = hamiltonian(sol.eta, sol.varpi, case["g"], case["mu"], case["nu"])
        assert scaled_difference(-pf.d_t, energy) <= tol


def test_action_against_an_ode_solution() -> None:
    """mpmath's Taylor ODE solver for the canonical equations, with dS/dt = T + U."""
    case = CASES["R1"]
    sol = solve(case)
    with mpmath.workdps(30):
        g, mu, nu = mp(case["g"]), mp(case["mu"]), mp(case["nu"])

        def rhs(_t, y):
            x1, x2, x3, w1, w2, w3, _S = y
            kinetic = (w1 * w1 + w2 * w2 + w3 * w3) / 2
            force = -g * x3 - (mu**2 * (x1 * x1 + x2 * x2) + nu**2 * x3 * x3) / 2
            return [w1, w2, w3, -(mu**2) * x1, -(mu**2) * x2, -g - nu**2 * x3, kinetic + force]

        start = [mp(x) for x in (*case["e"], *case["p"])] + [mp(0)]
        y = mpmath.odefun(rhs, 0, start)(mp(case["t"]))
        for key, a, b in zip(SOLUTION_KEYS, y, solution_values(sol), strict=True):
            assert scaled_difference(a, b) <= mp("1e-25"), key


# -- S(η, e, t) and its derivatives ------------------------------------------------------------


@pytest.mark.parametrize("name", sorted(CASES))
def test_principal_function_as_printed(name: str) -> None:
    """Hamilton's arrangement of (120.) and (122.)–(123.), evaluated verbatim at 60 digits."""
    case = CASES[name]
    eta = ("1.25", "-0.75", "0.5")
    pf = principal_function(eta, case["e"], case["t"], case["g"], case["mu"], case["nu"])
    with mpmath.workdps(60):
        g, mu, nu, t = (mp(case[k]) for k in ("g", "mu", "nu", "t"))
        y, e = [mp(x) for x in eta], [mp(x) for x in case["e"]]
        a = g / nu**2
        S = (
            mu / 2 * ((y[0] - e[0]) ** 2 + (y[1] - e[1]) ** 2) * mpmath.cot(mu * t)
            + nu / 2 * (y[2] - e[2]) ** 2 * mpmath.cot(nu * t)
            - mu * (y[0] * e[0] + y[1] * e[1]) * mpmath.tan(mu * t / 2)
            - nu * (y[2] + a) * (e[2] + a) * mpmath.tan(nu * t / 2)
            + g**2 * t / (2 * nu**2)
        )
        varpi = [
            mu * (y[i] - e[i]) * mpmath.cot(mu * t) - mu * e[i] * mpmath.tan(mu * t / 2)
            for i in (0, 1)
        ]
        p = [
            mu * (y[i] - e[i]) * mpmath.cot(mu * t) + mu * y[i] * mpmath.tan(mu * t / 2)
            for i in (0, 1)
        ]
        varpi.append(
            nu * (y[2] - e[2]) * mpmath.cot(nu * t) - nu * (e[2] + a) * mpmath.tan(nu * t / 2)
        )
        p.append(nu * (y[2] - e[2]) * mpmath.cot(nu * t) + nu * (y[2] + a) * mpmath.tan(nu * t / 2))
        tol = mp("1e-29")
        assert scaled_difference(pf.S, S) <= tol
        for i in range(3):
            assert scaled_difference(pf.d_eta[i], varpi[i]) <= tol
            assert scaled_difference(-pf.d_e[i], p[i]) <= tol


@pytest.mark.parametrize("name", ["R1", "R3", "flat", "backwards"])
def test_derivatives_by_finite_differences(name: str) -> None:
    case = ALL[name]
    eta, e, t = ["0.9", "-1.3", "2.2"], list(case["e"]), case["t"]
    args = (case["g"], case["mu"], case["nu"])
    pf = principal_function(eta, e, t, *args)
    h = mp("1e-15")

    def S(eta_, e_, t_):
        return principal_function(eta_, e_, t_, *args, dps=60).S

    with mpmath.workdps(60):

        def shifted(vector, i, step):
            out = [mp(x) for x in vector]
            out[i] += step
            return out

        for i in range(3):
            d_eta = (S(shifted(eta, i, h), e, t) - S(shifted(eta, i, -h), e, t)) / (2 * h)
            d_e = (S(eta, shifted(e, i, h), t) - S(eta, shifted(e, i, -h), t)) / (2 * h)
            assert scaled_difference(pf.d_eta[i], d_eta) <= mp("1e-25"), f"d_eta{i + 1}"
            assert scaled_difference(pf.d_e[i], d_e) <= mp("1e-25"), f"d_e{i + 1}"
        d_t = (S(eta, e, mp(t) + h) - S(eta, e, mp(t) - h)) / (2 * h)
        assert scaled_difference(pf.d_t, d_t) <= mp("1e-25")


@pytest.mark.parametrize(
    ("g", "mu", "nu", "t"),
    [
        ("1", "0.3", "0.45", "2.5"),
        ("9.80665", "0", "0.08", "4.75"),
        ("-0.5", "1.3", "0", "-7.1"),
        ("2", "0", "0", "11"),
        ("1", "3.1415926", "0.45", "1"),  # near a conjugate point: S ~ 1e7
    ],
)
def test_hamilton_jacobi_pair(g: str, mu: str, nu: str, t: str) -> None:
    """(121.): ∂S/∂t + H(η, ∂S/∂η) = 0 and ∂S/∂t + H(e, −∂S/∂e) = 0, at arbitrary end points."""
    eta, e = ("1.7", "-0.2", "3.1"), ("-0.6", "0.9", "0.4")
    pf = principal_function(eta, e, t, g, mu, nu)
    with mpmath.workdps(40):
        final = pf.d_t + hamiltonian([mp(x) for x in eta], pf.d_eta, g, mu, nu)
        initial = pf.d_t + hamiltonian([mp(x) for x in e], [-x for x in pf.d_e], g, mu, nu)
        scale = max(mp(1), abs(pf.d_t))
        assert abs(final) <= mp("1e-28") * scale
        assert abs(initial) <= mp("1e-28") * scale


# -- the parabola (§5.4) and continuity at μ, ν → 0 ----------------------------------------------


def test_parabolic_limit() -> None:
    """μ = ν = 0: the motion (127.)–(128.), S₁ (129.) and (130.), the integrals (132.)–(133.)."""
    case = EXTRA["parabola"]
    sol, pf = principal_at_solution(case)
    with mpmath.workdps(40):
        g, t = mp(case["g"]), mp(case["t"])
        e, p = [mp(x) for x in case["e"]], [mp(x) for x in case["p"]]
        eta = [e[0] + p[0] * t, e[1] + p[1] * t, e[2] + p[2] * t - g * t * t / 2]
        varpi = [p[0], p[1], p[2] - g * t]
        S1 = t * sum(x * x for x in p) / 2 - g * e[2] * t - g * p[2] * t**2 + g**2 * t**3 / 3
        dist2 = sum((eta[i] - e[i]) ** 2 for i in range(3))
        S130 = dist2 / (2 * t) - g * t * (eta[2] + e[2]) / 2 - g**2 * t**3 / 24
        tol = mp("1e-29")
        for i in range(3):
            assert scaled_difference(sol.eta[i], eta[i]) <= tol
            assert scaled_difference(sol.varpi[i], varpi[i]) <= tol
        assert scaled_difference(sol.S, S1) <= tol
        assert scaled_difference(pf.S, S130) <= tol
        shift = [0, 0, g * t / 2]
        for i in range(3):
            assert scaled_difference(pf.d_eta[i], (eta[i] - e[i]) / t - shift[i]) <= tol
            assert scaled_difference(-pf.d_e[i], (eta[i] - e[i]) / t + shift[i]) <= tol


@pytest.mark.parametrize("which", ["mu", "nu", "both"])
def test_continuity_at_zero_frequency(which: str) -> None:
    """S and its derivatives differ from their μ = 0 (ν = 0) values by O(μ²): 1e-40 at 1e-20.

    At 1e-4 and 1e-5 the differences must fall by 100 (order 2), not be 0 or O(1).
    """
    base = CASES["R1"]
    names = ("mu", "nu") if which == "both" else (which,)

    def evaluate(value: str) -> list:
        case = {**base, **dict.fromkeys(names, value)}
        sol, pf = principal_at_solution(case)
        return solution_values(sol) + principal_values(pf)

    zero = evaluate("0")
    with mpmath.workdps(40):
        for tiny in ("1e-20", "1e-200"):  # the second below the working precision
            for a, b in zip(evaluate(tiny), zero, strict=True):
                assert scaled_difference(a, b) <= mp("1e-30")
        big = [scaled_difference(a, b) for a, b in zip(evaluate("1e-4"), zero, strict=True)]
        small = [scaled_difference(a, b) for a, b in zip(evaluate("1e-5"), zero, strict=True)]
        for x, y in zip(big, small, strict=True):
            if x > mp("1e-25"):  # a quantity that moves at second order
                assert 99 < x / y < 101
        assert max(big) > mp("1e-9")


def test_second_order_term_137() -> None:
    """S − S₁ − S₂ = O(ε⁴) for μ, ν ∝ ε, with S₂ of (137.) (measured order 4.00)."""
    case = CASES["R1"]
    eta, e, t, g = ("1.7", "-0.2", "3.1"), case["e"], case["t"], case["g"]

    def residual(eps: str) -> mpmath.mpf:
        mu, nu = mp(eps) * 3, mp(eps) * 4
        pf = principal_function(eta, e, t, g, mu, nu, dps=40)
        with mpmath.workdps(50):
            y, x = [mp(v) for v in eta], [mp(v) for v in e]
            T, G = mp(t), mp(g)
            S1 = sum((y[i] - x[i]) ** 2 for i in range(3)) / (2 * T) - G * T * (y[2] + x[2]) / 2
            S1 -= G**2 * T**3 / 24
            quad = sum(y[i] ** 2 + y[i] * x[i] + x[i] ** 2 for i in (0, 1))
            S2 = -(mu**2) * T / 6 * quad - nu**2 * T / 6 * (
                y[2] ** 2
                + y[2] * x[2]
                + x[2] ** 2
                + G * (y[2] + x[2]) * T**2 / 4
                + G**2 * T**4 / 40
            )
            return pf.S - S1 - S2

    with mpmath.workdps(50):
        order = mpmath.log(residual("0.002") / residual("0.001")) / mpmath.log(2)
    assert abs(order - 4) < 0.01


# -- error estimates ----------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["R3", "flat", "near_conjugate", "long", "float"])
def test_error_estimates_are_small_and_honest(name: str) -> None:
    case = ALL[name]
    sol, pf = principal_at_solution(case, 30)
    sol60 = solve(case, 60)
    c = case
    pf60 = principal_function(sol.eta, c["e"], c["t"], c["g"], c["mu"], c["nu"], dps=60)
    pairs = [
        (sol.errors, SOLUTION_KEYS, solution_values(sol), solution_values(sol60)),
        (pf.errors, PRINCIPAL_KEYS, principal_values(pf), principal_values(pf60)),
    ]
    with mpmath.workdps(80):
        for errors, keys, low, high in pairs:
            assert set(errors) == set(keys)
            for key, a, b in zip(keys, low, high, strict=True):
                assert errors[key] <= mp("1e-30"), key
                assert scaled_difference(a, b) <= errors[key], key


# -- what is refused ----------------------------------------------------------------------------


def test_conjugate_point_is_refused() -> None:
    e = CASES["R1"]["e"]
    with pytest.raises(ValueError, match=r"mu.*conjugate point"):
        principal_function(("1", "2", "3"), e, "1", "1", mpmath.pi, "0.45")
    with pytest.raises(ValueError, match=r"nu.*conjugate point"):
        principal_function(("1", "2", "3"), e, "2", "1", "0.3", mpmath.pi)
    # A float next to π is not a conjugate point: S is large but exists.
    pf = principal_function(("1", "2", "3"), e, "1", "1", math.pi, "0.45")
    assert abs(pf.S) > 1e15
    with pytest.raises(ValueError, match=r"^t:"):
        principal_function(("1", "2", "3"), e, "0", "1", "0.3", "0.45")


GOOD = {"g": "1", "mu": "0.3", "nu": "0.45", "e": ("0.2", "-0.4", "1.5"), "t": "2.5"}


@pytest.mark.parametrize(
    ("changes", "pattern"),
    [
        ({"g": "inf"}, r"^g must be finite"),
        ({"mu": "-0.3"}, r"^mu: .*>= 0"),
        ({"nu": -1}, r"^nu: .*>= 0"),
        ({"t": float("nan")}, r"^t must be finite"),
        ({"e": ("1", "2")}, r"^e: expected a sequence of three"),
        ({"e": ("1", "2", "-inf")}, r"^e\[2\] must be finite"),
        ({"p": ("1", "2", "3", "4")}, r"^p: expected a sequence of three"),
        ({"eta": "123"}, r"^eta: expected a sequence of three"),
        ({"mu": "x"}, r"^mu: 'x' is not a number"),
        ({"dps": 3}, r"^dps must be an integer"),
    ],
)
def test_bad_input_names_the_parameter(changes: dict, pattern: str) -> None:
    args = {**GOOD, "p": ("0.7", "0.3", "2.1"), "eta": ("1", "2", "3"), "dps": 30, **changes}
    solution_args = {k: args[k] for k in ("g", "mu", "nu", "e", "p", "t", "dps")}
    principal_args = {k: args[k] for k in ("eta", "e", "t", "g", "mu", "nu", "dps")}
    if "eta" not in changes:
        with pytest.raises(ValueError, match=pattern):
            projectile_solution(**solution_args)
    if "p" not in changes:
        with pytest.raises(ValueError, match=pattern):
            principal_function(**principal_args)
