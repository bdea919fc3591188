"""Arb balls (python-flint) for the closed forms' proved bounds: exact inputs in, exact
mpmath numbers out.

A ball ``[mid ± rad]`` provably holds its value. Inputs enter exactly: decimal text is
enclosed (one tenth is no binary number; its ball holds it), a float, an integer, a
:class:`~fractions.Fraction`, an mpmath number or a heyoka quad or MPFR number is exact. A
ball's midpoint and radius are exact binary numbers, returned as mpmath numbers without
rounding.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from decimal import Decimal
from fractions import Fraction

import mpmath
import numpy as np
from flint import arb

from .accuracy import to_mpf
from .exact import upper

__all__ = [
    "Enclosure",
    "ball",
    "bound",
    "exact_mid",
    "gap_bound",
    "exact_rational",
    "scaled_bound",
    "to_ball",
]


def ball(x: object, name: str = "value") -> arb:
    """An input as a ball holding it exactly; errors name the parameter ``name``."""
    if isinstance(x, str):
        text = x.strip()
        to_mpf(text, name)  # the same refusals as the mpmath path (not a number, not finite)
        return arb(text)
    if isinstance(x, Decimal) and x.is_finite():
        x = Fraction(x)
    if isinstance(x, Fraction):
        return arb(x.numerator) / arb(x.denominator)
    if isinstance(x, int | np.integer) and not isinstance(x, bool):
        return arb(int(x))  # exact: to_mpf would round it to mpmath's precision
    if isinstance(x, mpmath.mpf):  # as it is: to_mpf would round it to mpmath's precision
        if not mpmath.isfinite(x):
            raise ValueError(f"{name} must be finite, got {x!r}")
        value = x
    else:  # floats, ints and heyoka's quad and MPFR numbers: exact
        value = to_mpf(x, name)
    sign, man, exp, _ = value._mpf_  # (mpmath's man_exp drops the sign)
    # (mantissa, exponent): exact at any working precision.
    return arb((-int(man) if sign else int(man), int(exp)))


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


def gap_bound(value: object, exact: arb) -> float:
    """A float proved to bound ``|value − x|`` for the number ``x`` that the ball ``exact``
    holds (Arb's upper bound of the difference, rounded up): the error of a written value.
    Computed at the bits of both midpoints, not at python-flint's global precision."""
    from flint import ctx

    x = ball(value)
    bits = sum(int(b.mid().man_exp()[0]).bit_length() for b in (x, exact)) + 64
    with ctx.workprec(bits):
        return upper(_exact((x - exact).abs_upper()))


def to_ball(value: mpmath.mpf, radius: mpmath.mpf) -> arb:
    """The ball ``[value ± radius]`` again, exactly (both are short binary numbers)."""
    return ball(value) + arb(0, ball(radius))


@dataclass(frozen=True)
class Enclosure:
    """Values with proved bounds: the exact value of ``name`` lies within ``bounds[name]`` of
    ``values[name]`` (the midpoint of an Arb ball, an mpmath number). ``bits`` is the working
    precision that proved them."""

    values: dict[str, mpmath.mpf]
    bounds: dict[str, mpmath.mpf]
    bits: int

    def digits(self, name: str) -> float:
        """Decimal digits proved for ``name``, relative (absolute where the value is below 1)."""
        radius = self.bounds[name]
        if radius == 0:
            return math.inf
        with mpmath.workprec(64):
            scale = max(abs(self.values[name]), mpmath.mpf(1))
            return float(-mpmath.log10(radius / scale))
