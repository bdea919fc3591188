"""Arb balls (python-flint) for the closed forms' proved bounds: exact inputs in, exact
mpmath numbers out.

A ball ``[mid ± rad]`` provably holds its value. Inputs enter exactly: decimal text is
enclosed (one tenth is no binary number; its ball holds it), a float, an integer, a
:class:`~fractions.Fraction`, an mpmath number or a heyoka quad or MPFR number is exact. A
ball's midpoint and radius are exact binary numbers, returned as mpmath numbers without
rounding.
"""

from __future__ import annotations

from fractions import Fraction

import mpmath
from flint import arb

from .accuracy import to_mpf

__all__ = ["ball", "bound", "exact_mid", "exact_rational", "scaled_bound"]


def ball(x: object, name: str = "value") -> arb:
    """An input as a ball holding it exactly; errors name the parameter ``name``."""
    if isinstance(x, str):
        text = x.strip()
        to_mpf(text, name)  # the same refusals as the mpmath path (not a number, not finite)
        return arb(text)
    if isinstance(x, Fraction):
        return arb(x.numerator) / arb(x.denominator)
    value = to_mpf(x, name)  # floats, ints, mpf and heyoka's quad and MPFR numbers: exact
    sign, man, exp, _ = value._mpf_  # (mpmath's man_exp drops the sign)
    return (-1 if sign else 1) * arb(int(man)) * arb(2) ** int(exp)


def _exact(x: arb) -> mpmath.mpf:
    """An exact arb number (a midpoint, a radius) as an mpmath number, exactly."""
    if x == 0:
        return mpmath.mpf(0)
    if not x.is_finite():
        return mpmath.nan
    man, exp = x.man_exp()
    with mpmath.workprec(max(53, int(man).bit_length() + 8)):
        return mpmath.mpf((int(man), int(exp)))


def exact_mid(x: arb) -> mpmath.mpf:
    """The ball's midpoint, exactly (NaN for a ball Arb could not bound)."""
    return _exact(x.mid())


def bound(x: arb) -> mpmath.mpf:
    """The ball's radius, exactly: a proved bound of the midpoint's error (∞ if unbounded)."""
    return _exact(x.rad()) if x.is_finite() else mpmath.inf


def scaled_bound(value: mpmath.mpf, radius: mpmath.mpf) -> mpmath.mpf:
    """``radius`` relative to ``value`` above 1 and absolute below (as the certificates scale
    errors), rounded up so that it stays a bound."""
    with mpmath.workprec(64):
        return radius / max(abs(value), mpmath.mpf(1)) * (1 + mpmath.mpf(2) ** -60)


def exact_rational(x: mpmath.mpf) -> Fraction:
    """An mpmath number's exact rational value (a time difference without rounding)."""
    sign, man, exp, _ = x._mpf_  # (mpmath's man_exp drops the sign)
    return (-1 if sign else 1) * Fraction(int(man)) * Fraction(2) ** int(exp)
