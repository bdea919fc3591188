"""Proved values of Euler's 1758 and Cayley's 1846 forms (``Euler1758.enclose``,
``Cayley1846.enclose``): from Cayley's 1843 solution in Arb balls, held against their own
quadrature routes at 40 more digits on the memoirs' test cases."""

from __future__ import annotations

import mpmath
import pytest
from test_cayley1846 import CASES as CAYLEY
from test_euler1758 import CASES as EULER

from cayley_heyoka.reference import Cayley1846, Euler1758

TIMES = ("0", "-3.3", "250.5")


@pytest.mark.parametrize("name", sorted(EULER))
def test_euler_bounds_hold(name):
    case = EULER[name]
    args = (case["inertia"], case["rates"], case["direction"])
    proved, exact = Euler1758(*args, dps=30), Euler1758(*args, dps=70)
    for t in (case["t"], *TIMES):
        b = proved.enclose(t)
        want = exact.at(t)
        with mpmath.workdps(90):
            for key, value in b.values.items():
                assert abs(value - getattr(want, key)) <= b.bounds[key], (t, key)
                assert b.digits(key) >= 30, (t, key)


@pytest.mark.parametrize("name", sorted(CAYLEY))
def test_cayley_bounds_hold(name):
    """R1 passes a half-turn near t = 3.09 (the angle through π): 250.5 lies many such
    passages on, so the angle's whole turns matter."""
    case = CAYLEY[name]
    args = (case["inertia"], case["rates"], case["rodrigues"])
    proved, exact = Cayley1846(*args, dps=30), Cayley1846(*args, dps=70)
    for t in (case["t"], *TIMES):
        b = proved.enclose(t)
        s = exact.at(t)
        want = {k: getattr(s, k) for k in b.values if not k.startswith("quaternion")}
        names = ("quaternion_w", "quaternion_x", "quaternion_y", "quaternion_z")
        want.update(zip(names, s.quaternion, strict=True))
        with mpmath.workdps(90):
            for key, value in b.values.items():
                assert abs(value - want[key]) <= b.bounds[key], (t, key)
                assert b.digits(key) >= 30, (t, key)
