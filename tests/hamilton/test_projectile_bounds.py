"""Hamilton's projectile with proved bounds (Arb balls, ``projectile_bounds``).

The truth is the mpmath route (``projectile_solution``: the same formulas in another arithmetic,
its cancelling differences by added precision instead of a bounded series) at 40 more digits,
and the 20-digit reference values; every bound must hold, and prove the digits asked.
"""

from __future__ import annotations

import mpmath
import pytest
from test_projectile import ALL, CASES, SOLUTION_KEYS, solution_values, solve

from cayley_heyoka.core.accuracy import PrecisionNotReached
from cayley_heyoka.hamilton import projectile_bounds as module
from cayley_heyoka.reference import projectile_bounds


def bounds(case: dict, dps: int):
    c = case
    return projectile_bounds(c["g"], c["mu"], c["nu"], c["e"], c["p"], c["t"], dps=dps)


@pytest.mark.parametrize("dps", [20, 40])
@pytest.mark.parametrize("name", sorted(ALL))
def test_bounds_hold(name: str, dps: int) -> None:
    """The reference cases and the extremes beyond them: a parabola (μ = ν = 0), ν = 1e-20,
    t < 0, μt just short of π, 250 time units, a float input."""
    b = bounds(ALL[name], dps)
    with mpmath.workdps(dps + 60):
        want = solution_values(solve(ALL[name], dps + 40))
        for key, value in zip(SOLUTION_KEYS, want, strict=True):
            assert abs(b.values[key] - value) <= b.bounds[key], key
            assert b.bounds[key] <= mpmath.mpf(10) ** -dps * max(1, abs(value)), key


@pytest.mark.parametrize("name", sorted(CASES))
def test_reference_values_lie_within_the_bounds(name: str) -> None:
    b = bounds(CASES[name], 30)
    case = CASES[name]
    want = [*case["eta"], *case["varpi"], case["S"]]
    with mpmath.workdps(40):
        for key, text in zip(SOLUTION_KEYS, want, strict=True):
            # The values carry 20 significant digits.
            value = mpmath.mpf(text)
            assert abs(b.values[key] - value) <= mpmath.mpf("1e-19") * abs(value), key


def test_the_cancelling_series_is_bounded() -> None:
    """(x − sin x)/x³ below ½ by its series, its tail in the radius: the exact value (by
    mpmath at 200 digits) lies within it, down to x = 1e-30 and at the switch."""
    from flint import arb, ctx

    for text in ("1e-30", "0.001", "0.3", "0.4999", "0.5", "2"):
        with ctx.workprec(120):
            b = module._x_minus_sin(arb(text))
            mid, rad = module.exact_mid(b), module.bound(b)
        with mpmath.workdps(200):
            x = mpmath.mpf(text)
            exact = (x - mpmath.sin(x)) / x**3
            assert abs(mid - exact) <= rad + mpmath.mpf(10) ** -38, text
            assert rad < mpmath.mpf(10) ** -30, text


def test_a_bound_that_cannot_be_proved_is_reported(monkeypatch) -> None:
    monkeypatch.setattr(module, "MAX_GROWTH", 0)
    with pytest.raises(PrecisionNotReached):
        bounds(CASES["R1"], 30)


@pytest.mark.parametrize(
    ("change", "pattern"),
    [
        ({"mu": "-0.3"}, "mu: the frequency must be >= 0"),
        ({"e": ("0", "0")}, "e: expected a sequence of three numbers"),
        ({"p": "abc"}, "p: expected a sequence of three numbers"),
        ({"t": "nan"}, "t must be finite"),
        ({"g": "x"}, "g: 'x' is not a number"),
    ],
)
def test_bad_input_is_refused_as_the_mpmath_route_refuses_it(change: dict, pattern: str) -> None:
    with pytest.raises(ValueError, match=pattern):
        bounds({**CASES["R1"], **change}, 20)
