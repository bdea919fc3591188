"""Floating-point precisions and the construction of numbers in them.

Every number that enters an integrator (state, parameters, tolerance, output times) is built
here, in the target type, from its *decimal text* when the text is known. ``real128(1.1)``
would carry the double rounding error of ``1.1`` into a quadruple-precision run; building
``real128("1.1")`` does not.
"""

from __future__ import annotations

import functools
import math
import re
from collections.abc import Iterable
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import numpy as np

from .errors import SceneError


class _Heyoka:
    """heyoka, imported when a quad or MPFR number is first built: a double result file is
    read through this module (``cayley-heyoka info``) without it, and it costs ~0.4 s. The
    first use puts the module itself in ``hy``, so later uses cost nothing extra."""

    def __getattr__(self, name: str) -> Any:
        import heyoka

        globals()["hy"] = heyoka
        return getattr(heyoka, name)


hy: Any = _Heyoka()

Number = float | int | str
"""A scene number: a Python float/int, or decimal text kept exact until the target type is known."""

_MIN_BITS = 64
#: Most significand bits of ``{bits = N}`` (docs/scenes.md, "Numbers"). heyoka's Taylor order
#: grows with the bits and the compile time faster (one time unit of a free body: 3.4 s at 1024
#: bits, 39 s at 2048); and the round-off scales of the checks use :attr:`Precision.epsilon`
#: as a double, which underflows to 0 beyond 1074 bits.
MAX_BITS = 1024
#: Scene numbers are refused beyond these (docs/scenes.md, "Numbers"), before any big integer
#: is built from them: ``1e999999999`` would otherwise hang building its exact value. The
#: magnitude bound fits in quad (about 1e±4932) and multiprecision; double checks its own.
MAX_DECIMAL_EXPONENT = 4000
MAX_SIGNIFICANT_DIGITS = 4000
_INTEGER_LIMIT = 10 ** (MAX_DECIMAL_EXPONENT + 1)  # the first integer of magnitude 1e4001
_DIGITS = r"[0-9](?:_?[0-9])*"
_DECIMAL = re.compile(
    rf"(?P<sign>[+-]?)(?:(?P<int>{_DIGITS})(?:\.(?P<frac>{_DIGITS})?)?|\.(?P<frac_only>{_DIGITS}))"
    rf"(?:[eE](?P<exp>[+-]?{_DIGITS}))?"
)


@dataclass(frozen=True)
class Precision:
    """A floating-point type for the integration.

    Parameters
    ----------
    kind
        ``"double"`` (IEEE binary64), ``"quad"`` (IEEE binary128 through heyoka's ``real128``)
        or ``"real"`` (MPFR multiprecision through heyoka's ``real``).
    bits
        Significand bits for ``"real"``; ignored (fixed) for the other kinds.
    """

    kind: str = "double"
    bits: int = 53

    def __post_init__(self) -> None:
        fixed = {"double": 53, "quad": 113}
        if self.kind in fixed:
            object.__setattr__(self, "bits", fixed[self.kind])
        elif self.kind == "real":
            bits = self.bits
            if isinstance(bits, bool) or not isinstance(bits, int) or bits < _MIN_BITS:
                raise SceneError(
                    "integrator.precision.bits",
                    f"must be an integer >= {_MIN_BITS} for multiprecision, got {bits!r:.40}",
                )
        else:
            raise SceneError(
                "integrator.precision",
                f"must be 'double', 'quad' or {{bits = N}}, got {self.kind!r}",
            )

    @classmethod
    def from_spec(cls, spec: Any) -> Precision:
        """Parse the scene form: ``"double"``, ``"quad"`` or ``{bits = N}``."""
        if isinstance(spec, Precision):
            return spec
        if spec in ("double", "quad"):
            return cls(spec)
        if isinstance(spec, dict):
            extra = set(spec) - {"bits"}
            if extra or "bits" not in spec:
                raise SceneError(
                    "integrator.precision", f"a table must be {{bits = N}}, got {spec!r}"
                )
            bits = spec["bits"]
            if isinstance(bits, str) and bits.isascii() and bits.isdigit() and len(bits) < 10:
                bits = int(bits)
            # A scene's limit, not the type's: the package itself computes above it (reference
            # certificates, closed forms with guard bits).
            if (
                isinstance(bits, bool)
                or not isinstance(bits, int)
                or not _MIN_BITS <= bits <= MAX_BITS
            ):
                raise SceneError(
                    "integrator.precision.bits",
                    f"must be an integer >= {_MIN_BITS} and <= {MAX_BITS} for multiprecision, "
                    f"got {bits!r:.40}",
                )
            return cls("real", bits)
        raise SceneError(
            "integrator.precision", f"must be 'double', 'quad' or {{bits = N}}, got {spec!r}"
        )

    def to_spec(self) -> str | dict[str, int]:
        """The scene form, inverse of :meth:`from_spec`."""
        return {"bits": self.bits} if self.kind == "real" else self.kind

    @property
    def name(self) -> str:
        """A short label: ``double``, ``quad`` or ``real256``."""
        return f"real{self.bits}" if self.kind == "real" else self.kind

    @property
    def fp_type(self) -> type:
        """The scalar type heyoka uses for this precision."""
        return {"double": float, "quad": hy.real128, "real": hy.real}[self.kind]

    @property
    def heyoka_kwargs(self) -> dict[str, Any]:
        """Keyword arguments selecting this precision in heyoka's constructors."""
        if self.kind == "double":
            return {}
        if self.kind == "quad":
            return {"fp_type": hy.real128}
        return {"fp_type": hy.real, "prec": self.bits}

    @property
    def epsilon(self) -> float:
        """Machine epsilon 2**(1 - bits), as a double (it is only used for scaling checks)."""
        return 2.0 ** (1 - self.bits)

    @property
    def dps(self) -> int:
        """Decimal digits that round-trip this precision (for text output and mpmath)."""
        return int(np.ceil(self.bits * np.log10(2.0))) + 2

    def number(self, value: Number) -> Any:
        """Build ``value`` in the target type, from its decimal text when it is a string.

        Text follows one grammar in every precision (:func:`decimal_text`). A value that this
        precision cannot hold (beyond double's range, or so small it would round to zero) is
        refused with :class:`SceneError` on ``integrator.precision``: the choice of precision
        is what cannot carry it.
        """
        if isinstance(value, bool):
            raise TypeError(f"expected a number, got {value!r}")
        if self.kind == "real" and isinstance(value, hy.real) and value.prec == self.bits:
            return value
        if self.kind == "quad" and isinstance(value, hy.real128):
            return value
        if isinstance(value, str) and self.kind != "real":
            return _from_text(self.kind, value)
        return self._convert(value)

    def _convert(self, value: Number) -> Any:
        text = decimal_text(value) if isinstance(value, str) else None
        if self.kind == "quad":
            return hy.real128(text if text is not None else _exact_text(value))
        if self.kind == "real":
            return hy.real(text if text is not None else _exact_text(value), self.bits)
        if text is None and not isinstance(value, int):
            return float(value)
        # Quad and multiprecision hold every magnitude the grammar allows; double does not.
        try:
            x = float(text if text is not None else value)
        except OverflowError:  # an integer beyond double's range
            x = np.inf
        if abs(x) == np.inf or (x == 0) != (exact_fraction(value) == 0):
            raise SceneError(
                "integrator.precision",
                f"{self.name} cannot hold {value!r:.60} (it would become {x!r}); choose a "
                "wider precision or rescale the problem",
            )
        return x

    def constant(self, value: int | Fraction | str) -> hy.expression:
        """A number node of the equations, exactly ``value`` or correctly rounded to it.

        heyoka folds numbers in the type of their nodes: ``3/5`` built from double nodes is the
        double 0.6 even in a quad system. Equations therefore build every constant here.
        """
        if isinstance(value, Fraction) and value.denominator != 1:
            # Both operands exact, so the division is IEEE/MPFR correctly rounded.
            if max(abs(value.numerator), value.denominator).bit_length() <= self.bits:
                return hy.expression(self.number(value.numerator) / self.number(value.denominator))
            return hy.expression(self.number(fraction_text(value, self)))
        if isinstance(value, Fraction):
            value = value.numerator
        return hy.expression(self.number(value))

    def dyadic(self, n: int, e: int) -> Any:
        """``n 2ᵉ`` rounded once to the target type, in its own arithmetic: the integer is
        rounded once (a Python float, ``real128`` or ``real`` built from it) and the scaling
        by 2ᵉ is exact. No decimal text: cheap enough for an event handler."""
        if self.kind == "double":
            return math.ldexp(float(n), e)
        if self.kind == "quad":
            return hy.real128(n) * hy.real128(math.ldexp(1.0, e))
        return hy.real(n, self.bits) * hy.real(math.ldexp(1.0, e), self.bits)

    def array(self, values: Iterable[Number]) -> np.ndarray:
        """A 1-d numpy array of ``values`` in the target type."""
        values = list(values)
        if self.kind == "double":
            return np.array([self.number(v) for v in values], dtype=float)
        # The dtype is explicit: an empty list would otherwise become float64, which heyoka's
        # compiled functions refuse for real128 and real.
        return np.array([self.number(v) for v in values], dtype=self.fp_type)

    def to_text(self, values: np.ndarray) -> np.ndarray:
        """Decimal strings that load back bit-for-bit with :meth:`from_text`."""
        if self.kind == "double":
            return np.array([repr(float(v)) for v in np.ravel(values)], dtype=object).reshape(
                np.shape(values)
            )
        return np.array([str(v) for v in np.ravel(values)], dtype=object).reshape(np.shape(values))

    def from_text(self, texts: np.ndarray) -> np.ndarray:
        """Inverse of :meth:`to_text`."""
        texts = np.asarray(texts)
        flat = [t.decode() if isinstance(t, bytes) else str(t) for t in texts.ravel()]
        # Our own text, not a scene's: it may hold the nan or inf of a run that failed, which
        # the scene grammar (number) refuses.
        if self.kind == "double":
            values = np.array([float(t) for t in flat], dtype=float)
        elif self.kind == "quad":
            values = np.array([hy.real128(t) for t in flat], dtype=self.fp_type)
        else:
            values = np.array([hy.real(t, self.bits) for t in flat], dtype=self.fp_type)
        return values.reshape(texts.shape)


def _exact_text(value: Any) -> str:
    """Decimal text equal to ``value`` exactly (floats are dyadic, so this is finite)."""
    if isinstance(value, str):
        return value
    if isinstance(value, int | np.integer):
        return str(int(value))
    if isinstance(value, float | np.floating):
        if not np.isfinite(value):
            return str(float(value))
        f = Fraction(float(value))
        # A dyadic fraction n/2^k has an exact decimal expansion with k digits.
        k = f.denominator.bit_length() - 1
        digits = f.numerator * 5**k
        sign = "-" if digits < 0 else ""
        s = str(abs(digits)).rjust(k + 1, "0")
        return f"{sign}{s[:-k]}.{s[-k:]}" if k else f"{sign}{s}"
    return str(value)


def dyadic_parts(value: Any) -> tuple[int, int]:
    """(m, e) with the mpmath number ``value = m 2ᵉ`` exactly."""
    sign, man, exp, _ = value._mpf_
    man = int(man)  # an mpz under mpmath's gmpy2 backend, which heyoka's types refuse
    return (-man if sign else man), int(exp)


def exact_fraction(value: Number) -> Fraction:
    """The exact rational value of a scene number (used for validation without rounding).

    Raises
    ------
    ValueError
        If text is not a decimal number (:func:`decimal_text`) or a value is not finite or
        beyond :data:`MAX_DECIMAL_EXPONENT`.
    """
    if isinstance(value, bool):
        raise TypeError(f"expected a number, got {value!r}")
    if isinstance(value, str):
        return _text_fraction(value)
    if isinstance(value, int) and abs(value) >= _INTEGER_LIMIT:
        # Not printed: Python refuses to print an integer of more than 4300 digits.
        raise ValueError(
            f"an integer of {abs(value).bit_length()} bits is beyond 1e±{MAX_DECIMAL_EXPONENT} "
            "(the limit of scene numbers)"
        )
    return Fraction(value)


def scene_mpf(value: Any) -> Any:
    """A scene number as an mpmath number, exact to mpmath's current precision (its rational
    value divided there once); an mpmath number is returned as it is."""
    import mpmath

    if isinstance(value, mpmath.mpf):
        return value
    f = exact_fraction(value)
    return mpmath.mpf(f.numerator) / f.denominator


def decimal_text(text: str) -> str:
    """Normalise a scene number written as text, the same way for every precision.

    The grammar is TOML's decimal numbers, also accepting ``1.`` and ``.5``: an optional
    sign, digits with an optional fraction, an optional exponent ``e±N``; ``_`` may separate
    two digits. ``inf``, ``nan``, hexadecimal and anything else are refused (``ValueError``),
    and so are more than :data:`MAX_SIGNIFICANT_DIGITS` digits or a magnitude beyond
    ``1e±``:data:`MAX_DECIMAL_EXPONENT`, before any big integer is built. Returns
    ``MANTISSAeEXPONENT`` with an integer mantissa, text every backend reads alike.
    """
    mantissa, exponent = _decimal_parts(text)
    return f"{mantissa}e{exponent}"


@functools.lru_cache(maxsize=4096)
def _from_text(kind: str, text: str) -> Any:
    # Double and real128 numbers are immutable: the base scene's text is converted once per
    # sweep, not once per member. (heyoka's MPFR numbers are not cached: each carries its
    # precision, and they are rarely the cost.)
    return Precision(kind)._convert(text)


@functools.lru_cache(maxsize=4096)
def _text_fraction(text: str) -> Fraction:
    # Scenes of a sweep repeat the base scene's text: parsed once (Fractions are immutable).
    mantissa, exponent = _decimal_parts(text)
    return Fraction(mantissa) * Fraction(10) ** exponent


@functools.lru_cache(maxsize=4096)
def _decimal_parts(text: str) -> tuple[int, int]:
    """(integer mantissa, decimal exponent) of decimal text, within the limits above."""
    m = _DECIMAL.fullmatch(text.strip())
    if m is None:
        raise ValueError(
            f"{text!r} is not a decimal number (digits, optional fraction and exponent, '_' only "
            "between digits; no inf, nan or hexadecimal)"
        )
    whole = (m["int"] or "").replace("_", "")
    frac = (m["frac"] or m["frac_only"] or "").replace("_", "")
    exp_digits = (m["exp"] or "0").replace("_", "").lstrip("+-").lstrip("0") or "0"
    digits = (whole + frac).lstrip("0")
    if len(digits) > MAX_SIGNIFICANT_DIGITS:
        raise ValueError(f"{text[:40]!r}... has more than {MAX_SIGNIFICANT_DIGITS} digits")
    if not digits:
        return 0, 0
    # Digits of the exponent first: int() of a huge digit string is itself the hang.
    if len(exp_digits) > len(str(MAX_DECIMAL_EXPONENT)) + len(str(MAX_SIGNIFICANT_DIGITS)):
        raise ValueError(f"{text[:40]!r}: exponent beyond ±{MAX_DECIMAL_EXPONENT}")
    exponent = int(exp_digits) * (-1 if (m["exp"] or "").startswith("-") else 1) - len(frac)
    magnitude = exponent + len(digits) - 1
    if abs(magnitude) > MAX_DECIMAL_EXPONENT:
        raise ValueError(
            f"{text[:40]!r} is beyond 1e±{MAX_DECIMAL_EXPONENT} (the limit of scene numbers)"
        )
    mantissa = int(digits)
    return (-mantissa if m["sign"] == "-" else mantissa), exponent


def exceeds_pi(value: Number) -> bool:
    """Whether a scene number is larger than π, decided exactly.

    A bound ``<= math.pi`` would refuse π written to 40 digits (the double is below π) in a
    quad run, and accept values between the double and π in none. The exact value written is
    compared with π, which is irrational: the digits of π are raised until the difference
    shows (a scene number has at most :data:`MAX_SIGNIFICANT_DIGITS` digits, so this ends).
    """
    import mpmath

    f = exact_fraction(value)
    if f <= 3:
        return False
    if f >= 4:
        return True
    dps = 50
    while True:
        with mpmath.workdps(dps):
            difference = mpmath.mpf(f.numerator) / f.denominator - mpmath.pi
            if abs(difference) > mpmath.mpf(10) ** (10 - dps):
                return difference > 0
        dps *= 2


def normalised(values: Iterable[Number], precision: Precision) -> tuple[Number, ...]:
    """``v / |v|`` correctly rounded in ``precision`` (as decimal text with guard digits).

    A direction accepted to 1e-12 of unit length (:func:`cayley_heyoka.core.scene.unit_vector`)
    and used as written would carry that error into a quad run; one of exactly unit length
    (``[0, 0.6, 0.8]``) is returned as written.
    """
    import mpmath

    values = tuple(values)
    exact = [exact_fraction(v) for v in values]
    if sum(f * f for f in exact) == 1:
        return values
    with mpmath.workdps(precision.dps + 15):
        v = [mpmath.mpf(f.numerator) / f.denominator for f in exact]
        norm = mpmath.sqrt(sum(x * x for x in v))
        return tuple(mpmath.nstr(x / norm, precision.dps + 10, strip_zeros=False) for x in v)


def unit_length(values: Iterable[Number], tolerance: Fraction) -> tuple[bool, str]:
    """Whether ``|v|`` is within ``tolerance`` of 1, decided exactly, and ``|v|`` as short text.

    ``float()`` of the squared norm would overflow for components beyond 1e154.
    """
    import mpmath

    norm2 = sum(exact_fraction(v) ** 2 for v in values)
    inside = (1 - tolerance) ** 2 <= norm2 <= (1 + tolerance) ** 2
    with mpmath.workdps(25):
        return inside, mpmath.nstr(mpmath.sqrt(mpmath.mpf(norm2.numerator) / norm2.denominator), 17)


def fraction_text(value: Fraction, precision: Precision) -> str:
    """Decimal text of a rational, with enough digits to round correctly in ``precision``."""
    if precision.kind == "double":
        # Python's int / int is correctly rounded; repr round-trips that double. Beyond
        # double's range the decimal text below lets Precision.number refuse it by name.
        try:
            x = value.numerator / value.denominator
        except OverflowError:
            x = math.inf
        if math.isfinite(x) and (x != 0) == (value != 0):
            return repr(x)
    import mpmath

    with mpmath.workdps(precision.dps + 15):
        return mpmath.nstr(mpmath.mpf(value.numerator) / value.denominator, precision.dps + 10)
