"""Certified evaluation: every reference value carries an error estimate.

A closed form evaluated in mpmath is only as good as its working precision, and the cancellations
near the separatrix (1 − m → 0) or near a symmetric body (B − A → 0) eat digits silently. So each
quantity is computed twice, at two working precisions ``dps + guard`` and ``dps + 2·guard``; the
difference bounds the error of the first and, with room to spare, that of the second, which is
returned. A call whose estimate exceeds the requested ``10**-dps`` raises
:class:`PrecisionNotReached` instead of returning a silently wrong number.

Errors are *scaled*: absolute for |value| ≤ 1, relative above, the convention of the 25-digit
test values in tests/reference/test_closed_form.py.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from decimal import Decimal
from fractions import Fraction

import mpmath

from .exact import exact
from .precision import NUMBER_KINDS, rational_mpf

__all__ = [
    "Certified",
    "PrecisionNotReached",
    "certify",
    "scaled_difference",
    "shown",
    "shown_error",
    "to_mpf",
]


class PrecisionNotReached(ArithmeticError):
    """A reference quantity could not be computed to the requested number of digits.

    Attributes
    ----------
    quantity : str
        Name of the offending quantity.
    dps : int
        Requested decimal digits.
    estimate : float
        The error estimate that was reached (scaled: absolute if ``|value| ≤ 1``, else relative).
    """

    def __init__(self, quantity: str, dps: int, estimate: float, hint: str = "") -> None:
        self.quantity, self.dps, self.estimate = quantity, dps, estimate
        message = (
            f"{quantity}: cannot certify {dps} digits (error estimate {estimate:.2e} > 1e-{dps})"
        )
        super().__init__(message + (f"; {hint}" if hint else ""))


@dataclass(frozen=True)
class Certified:
    """Values with their error estimates, both keyed by quantity name."""

    values: dict[str, mpmath.mpf]
    errors: dict[str, mpmath.mpf]
    dps: int

    @property
    def worst_error(self) -> mpmath.mpf:
        return max(self.errors.values(), default=mpmath.mpf(0))


def to_mpf(x: object, name: str = "value") -> mpmath.mpf:
    """Convert an input number *exactly*: decimal text at the current precision, floats exactly.

    Strings are the recommended input (``"0.1"`` is one tenth at any precision); a Python float,
    an integer, a numpy number (float16 to longdouble) and a heyoka ``real128`` or ``real`` (a
    quad or MPFR result's times and states) are taken at their exact binary value, whatever
    the current precision, never through ``str`` (:func:`cayley_heyoka.core.exact.exact`); a
    ``Fraction`` or ``Decimal`` is correctly rounded at the current precision (the kinds of
    :func:`~cayley_heyoka.core.precision.as_number`).
    """
    if isinstance(x, bool):
        raise TypeError(f"{name}: expected a number, got a bool")
    if isinstance(x, str):
        try:
            value = mpmath.mpf(x.strip())
        except (ValueError, TypeError) as exc:
            raise ValueError(f"{name}: {x!r} is not a number") from exc
    elif isinstance(x, mpmath.mpf):
        value = x  # as it is: mpmath.mpf(x) would round it to the current precision
    elif type(x).__module__.startswith("mpmath"):
        try:  # a constant (mpmath.pi), evaluated at the current precision
            value = mpmath.mpf(x)
        except (ValueError, TypeError) as exc:
            raise TypeError(f"{name}: {x!r} is not a real number") from exc
    elif isinstance(x, Fraction):
        value = rational_mpf(x)
    elif isinstance(x, Decimal):
        value = rational_mpf(Fraction(x)) if x.is_finite() else mpmath.nan
    else:
        # A number at its exact binary value whatever mpmath's precision (mpmath.mpf(x)
        # would round it to that): a float, an integer, a quad or MPFR result's number.
        try:
            value = exact(x)
        except TypeError as exc:
            raise TypeError(f"{name}: {x!r} is not a real number ({NUMBER_KINDS})") from exc
    if not mpmath.isfinite(value):
        raise ValueError(f"{name} must be finite, got {x!r}")
    return value


def scaled_difference(a: mpmath.mpf, b: mpmath.mpf) -> mpmath.mpf:
    """|a − b|, relative to |b| when |b| > 1 (the convention of the test values)."""
    if a == b:  # also for infinite values (a steady rotation's period)
        return mpmath.mpf(0)
    return abs(a - b) / max(mpmath.mpf(1), abs(b))


def shown(*values: mpmath.mpf, digits: int = 6) -> str:
    """Values to ``digits`` significant digits, comma-separated, for a one-line ``repr``.

    ``mpmath.nstr`` and never ``float``: a reference value may lie beyond double's range, and
    the repr must not turn it into ``inf`` or ``0.0``.
    """
    return ", ".join(mpmath.nstr(x, digits) for x in values)


def shown_error(error: mpmath.mpf) -> str:
    """An error estimate to two significant digits (its order of magnitude is what matters)."""
    return mpmath.nstr(error, 2)


def certify(
    compute: Callable[[int], Mapping[str, mpmath.mpf]],
    dps: int,
    *,
    guard: int = 12,
    hint: str = "",
) -> Certified:
    """Evaluate ``compute(working_dps)`` at two precisions and certify ``dps`` digits.

    Parameters
    ----------
    compute : callable
        ``compute(working_dps)`` must set nothing global and return named mpmath numbers computed
        with ``mpmath.workdps(working_dps)`` active (this function activates it).
    dps : int
        Requested decimal digits (≥ 5).
    guard : int
        Extra digits of the first evaluation; the second uses twice as many.
    hint : str
        Appended to the error message when the request cannot be met.

    Returns
    -------
    Certified
        Values from the more precise evaluation, rounded to ``dps + guard`` digits, and the
        scaled difference of the two evaluations as each value's error estimate.

    Raises
    ------
    PrecisionNotReached
        When any estimate exceeds ``10**-dps``.
    """
    if not isinstance(dps, int) or dps < 5:
        raise ValueError(f"dps must be an integer >= 5, got {dps!r}")
    with mpmath.workdps(dps + guard):
        low = dict(compute(dps + guard))
    with mpmath.workdps(dps + 2 * guard):
        high = dict(compute(dps + 2 * guard))
    values: dict[str, mpmath.mpf] = {}
    errors: dict[str, mpmath.mpf] = {}
    with mpmath.workdps(dps + guard):
        floor = mpmath.mpf(10) ** -(dps + guard)
        for name, value in high.items():
            values[name] = +value  # round to dps + guard digits
            errors[name] = max(scaled_difference(low[name], value), floor)
    tolerance = mpmath.mpf(10) ** -dps
    for name, error in errors.items():
        if error > tolerance:
            raise PrecisionNotReached(name, dps, float(error), hint)
    return Certified(values, errors, dps)
