"""The exact values of a run's numbers in mpmath, and the differences of two runs' numbers.

Every comparison of two results goes through here — a reference's certificate from two
precisions, a consistency check against its twin, :func:`~cayley_heyoka.testing.
assert_trajectory_close` — so that each resolves differences below double's ε in quad and
MPFR runs and each reads an undefined value alike.

*Exact.* :func:`exact` gives the mpmath number equal to a float, a numpy float, an integer, a
heyoka ``real128`` or ``real``, whatever mpmath's global precision: each is built from its
binary significand and exponent at as many bits as they hold (a ``real128`` from its IEEE
binary128 bytes; an MPFR ``real`` from its round-trip decimal text read at its own bits).
Non-finite values are recognised by value, never through text.

*Undefined here.* A result value may be NaN by design: Cayley's Θ and Σ on the rows where an
orbit is carried on the tilted frame (docs/orbits.md, "Near-equatorial orbits"). The engine
stops a run at any other non-finite output (:func:`cayley_heyoka.core.recording.first_nonfinite`),
so that a NaN in a result means "undefined here". Two results agree where both are undefined:
:func:`difference` is 0 there. A value undefined in one result only is a disagreement: its
difference is infinite, never left out.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import mpmath
import numpy as np

__all__ = ["difference", "exact", "exact_array", "is_nan", "upper"]

_BINARY128_FRACTION = 112
_BINARY128_BIAS = 16383


def is_nan(x: Any) -> bool:
    """Whether ``x`` is NaN (any float type: NaN alone is unequal to itself)."""
    return bool(x != x)


def exact(x: Any) -> mpmath.mpf:
    """``x`` as an mpmath number of exactly its value (NaN and ±∞ as mpmath's).

    Raises
    ------
    TypeError
        For a bool or anything that is not a real number.
    """
    if isinstance(x, bool | np.bool_):
        raise TypeError(f"expected a number, got {x!r}")
    if isinstance(x, mpmath.mpf):
        return x
    if isinstance(x, int | np.integer):
        return _dyadic(int(x), 0)
    if isinstance(x, float | np.floating):
        if not np.isfinite(x):
            return _non_finite(x)
        n, d = x.as_integer_ratio()  # exact; the denominator is a power of two
        return _dyadic(n, 1 - d.bit_length())
    kind = type(x).__name__
    if type(x).__module__.startswith("heyoka") and kind in ("real128", "real"):
        if is_nan(x) or is_nan(x * 0):
            return _non_finite(x)
        if kind == "real128":
            return _binary128(x.tobytes())
        # MPFR's decimal text round-trips (result files store it so): read at the number's
        # own bits, it is the number again, exactly.
        with mpmath.workprec(int(x.prec)):
            return mpmath.mpf(str(x))
    raise TypeError(f"expected a real number, got {type(x).__name__} {x!r:.40}")


def exact_array(values: Any) -> list[mpmath.mpf]:
    """:func:`exact` of each of ``values`` (flattened)."""
    return [exact(x) for x in np.ravel(np.asarray(values, dtype=object))]


def difference(a: Any, b: Any) -> np.ndarray:
    """``|a − b|`` element by element, exactly, rounded up to float64; shape of ``a``.

    0 where both are NaN (undefined in both: agreement) or equal infinities; ∞ where one only
    is NaN or infinite.

    Raises
    ------
    ValueError
        When the shapes differ.
    """
    if np.shape(a) != np.shape(b):
        raise ValueError(f"shapes differ: {np.shape(a)} and {np.shape(b)}")
    xs, ys = exact_array(a), exact_array(b)
    out = np.array([_gap(x, y) for x, y in zip(xs, ys, strict=True)], dtype=float)
    return out.reshape(np.shape(a))


def _gap(x: mpmath.mpf, y: mpmath.mpf) -> float:
    if mpmath.isnan(x) or mpmath.isnan(y):
        return 0.0 if mpmath.isnan(x) and mpmath.isnan(y) else np.inf
    if mpmath.isinf(x) or mpmath.isinf(y):
        return 0.0 if x == y else np.inf
    # Exact subtraction and sign: abs() would round to mpmath's global precision.
    d = mpmath.fsub(x, y, exact=True)
    return upper(d if d >= 0 else mpmath.fneg(d, exact=True))


def upper(x: mpmath.mpf) -> float:
    """``x`` as a float rounded up, so that an error bound stays a bound."""
    f = float(x)
    return f if f >= x else float(np.nextafter(f, np.inf))


def _dyadic(man: int, exp: int) -> mpmath.mpf:
    with mpmath.workprec(max(53, abs(man).bit_length() + 1)):
        return mpmath.mpf((man, exp))


def _binary128(raw: bytes) -> mpmath.mpf:
    """The value of IEEE binary128 bytes (little-endian, as heyoka's ``real128`` holds them)."""
    bits = int.from_bytes(raw, "little")
    sign = -1 if bits >> 127 else 1
    field = (bits >> _BINARY128_FRACTION) & 0x7FFF
    fraction = bits & ((1 << _BINARY128_FRACTION) - 1)
    if field == 0:  # zero or subnormal
        return _dyadic(sign * fraction, 1 - _BINARY128_BIAS - _BINARY128_FRACTION)
    man = fraction | (1 << _BINARY128_FRACTION)
    return _dyadic(sign * man, field - _BINARY128_BIAS - _BINARY128_FRACTION)


def _non_finite(x: Any) -> mpmath.mpf:
    if is_nan(x):
        return mpmath.nan
    return mpmath.inf if x > 0 else -mpmath.inf


def all_finite(values: Iterable[Any]) -> bool:
    """Whether every one of ``values`` is finite (by value: no text)."""
    return all(not (is_nan(v) or is_nan(v * 0)) for v in values)
