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
from decimal import Decimal
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
"""A scene number: a Python float/int, or decimal text kept exact until the target type is known.

Every other kind of number enters through :func:`as_number`, which turns it into one of these
with the same exact value."""

#: The kinds of number :func:`as_number` takes, for messages.
NUMBER_KINDS = (
    "an int, a float, decimal text, a fractions.Fraction, a decimal.Decimal, a numpy integer "
    "or float, a heyoka real128 or real, or an mpmath mpf"
)

_MIN_BITS = 64
#: Double's smallest normal number: below it a double keeps fewer than its 53 bits.
SMALLEST_NORMAL = float(np.finfo(float).tiny)
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
        """A short label: ``double``, ``quad`` (IEEE binary128, heyoka's ``real128``) or, for
        MPFR, ``mpfr`` and its bits (``mpfr128`` is not quad: it has 128 significand bits,
        quad 113)."""
        return f"mpfr{self.bits}" if self.kind == "real" else self.kind

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
        is what cannot carry it. (A scene's own numbers are checked by :meth:`hold` when the
        scene is loaded, naming their fields; this refusal is for numbers the package derives.)
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
                f"{self.name} cannot hold {shown(value)} (it would become {x!r}); choose a "
                "wider precision or rescale the problem",
            )
        return x

    def hold(self, value: Number, where: str) -> Any:
        """``value`` in the target type, or :class:`SceneError` on ``where`` (the field that
        wrote it) if this precision cannot hold it to its full significand.

        Refused: a magnitude beyond the type's range, a nonzero value that would round to
        zero, and in double a nonzero value below the smallest normal number (2.2e-308),
        which a double keeps with fewer than its 53 bits (quad and multiprecision have no
        such numbers within the scene's limits, 1e±4000).
        """
        try:
            x = self.number(value)
        except SceneError as exc:
            raise SceneError(where, exc.constraint) from None
        if self.kind == "double" and x != 0 and abs(x) < SMALLEST_NORMAL:
            kept = max(1, 53 - (math.frexp(SMALLEST_NORMAL)[1] - math.frexp(abs(x))[1]))
            raise SceneError(
                where,
                f"{shown(value)} is below double's smallest normal number "
                f"({SMALLEST_NORMAL!r}): a double keeps only {kept} of its 53 bits there; "
                "choose quad or rescale the problem",
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
            if all(type(v) is float for v in values):  # already doubles: nothing to convert
                return np.array(values, dtype=float)
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


def two_pi_parts(precision: Precision) -> tuple[int, int]:
    """(m, e) with ``m 2ᵉ`` = 2π rounded to ``precision``: the value 2π takes in a run, exactly
    (a turn counted in integers of it is exact)."""
    import mpmath

    with mpmath.workprec(precision.bits):
        return dyadic_parts(+(2 * mpmath.pi))


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


def as_number(value: Any) -> Number:
    """The one way a number enters: ``value`` as a scene number with the same exact value.

    An int, a float or decimal text is returned as it is (text is checked by
    :func:`exact_fraction`). Every other kind is turned into one of those, exactly:

    * a numpy integer is an int; a numpy float16, float32 or float64 a float (each is a
      double exactly), a longer numpy float its exact binary value as decimal text;
    * a heyoka ``real128`` or ``real`` and an mpmath ``mpf`` are their exact binary value, as
      a Python float is (a quad 0.1 in a 256-bit run is the quad's 0.1, not 256 bits of 1/10:
      give text for that);
    * a ``fractions.Fraction`` or ``decimal.Decimal`` is its exact decimal text; a fraction
      whose decimal expansion does not end (1/3) is refused, since a scene keeps its numbers
      as text (its result files store it): give the digits meant as text.

    Raises
    ------
    TypeError
        A bool, or anything that is not one of :data:`NUMBER_KINDS`.
    ValueError
        A value that is not finite, a fraction without a finite decimal expansion, or an
        exact value of more than :data:`MAX_SIGNIFICANT_DIGITS` digits.
    """
    if isinstance(value, bool | np.bool_):
        raise TypeError(f"expected a number, got the bool {value!r}")
    if isinstance(value, str):
        return str(value)
    if isinstance(value, int):
        return int(value)
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ValueError(f"{float(value)!r} is not finite")
        return float(value)
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.floating):
        if not np.isfinite(value):
            raise ValueError(f"{value!r} is not finite")
        if value.dtype.itemsize <= 8:
            return float(value)
        m, d = value.as_integer_ratio()
        return _dyadic_text(m, -(d.bit_length() - 1))
    if isinstance(value, Fraction):
        text = exact_decimal(value)
        if text is None:
            raise ValueError(
                f"Fraction({value.numerator}, {value.denominator}) has no finite decimal "
                "expansion, and a scene keeps its numbers exactly as decimal text: give the "
                "digits you mean as text"
            )
        return text
    if isinstance(value, Decimal):
        if not value.is_finite():
            raise ValueError(f"{value!r} is not finite")
        return str(value)
    kind = type(value)
    if kind.__module__.startswith("heyoka") and kind.__name__ in ("real128", "real"):
        import mpmath

        # Their decimal text round-trips: read back at their own bits it is the number exactly.
        bits = 113 if kind.__name__ == "real128" else int(value.prec)
        with mpmath.workprec(bits):
            x = mpmath.mpf(str(value))
        if not mpmath.isfinite(x):
            raise ValueError(f"{value} is not finite")
        return _dyadic_text(*dyadic_parts(x))
    if kind.__module__.startswith("mpmath") and kind.__name__ == "mpf":
        import mpmath

        if not mpmath.isfinite(value):
            raise ValueError(f"{value} is not finite")
        return _dyadic_text(*dyadic_parts(value))
    raise TypeError(f"expected a number ({NUMBER_KINDS}), got {kind.__name__}")


def number_argument(value: Any, name: str, *, positive: bool = False) -> Number:
    """A number given to the Python API as parameter ``name``, through :func:`as_number` and
    the limits of scene numbers (:func:`exact_fraction`); compare it with
    ``exact_fraction(value)``, never through ``float`` (``10**400`` overflows there).

    Raises
    ------
    TypeError
        ``name must be a number (...)``: a bool, or a type :func:`as_number` does not take.
    ValueError
        ``name must be ...``: not finite, beyond the limits, or (``positive``) not > 0.
    """
    try:
        number = as_number(value)
        f = exact_fraction(number)
    except TypeError:
        raise TypeError(f"{name} must be a number ({NUMBER_KINDS}), got {shown(value)}") from None
    except ValueError as exc:
        raise ValueError(f"{name} must be a finite number: {exc}") from None
    if positive and f <= 0:
        raise ValueError(f"{name} must be a number > 0, got {shown(value)}")
    return number


def exact_decimal(value: Fraction) -> str | None:
    """The exact decimal text of ``value``, or None when it has none (a denominator with a
    prime factor other than 2 and 5)."""
    d = value.denominator
    twos = fives = 0
    while d % 2 == 0:
        d //= 2
        twos += 1
    while d % 5 == 0:
        d //= 5
        fives += 1
    if d != 1:
        return None
    k = max(twos, fives)
    digits = abs(value.numerator) * 10**k // value.denominator
    sign = "-" if value < 0 else ""
    text = str(digits).rjust(k + 1, "0")
    whole, frac = (text[:-k], text[-k:].rstrip("0")) if k else (text, "")
    return f"{sign}{whole}.{frac}" if frac else f"{sign}{whole}"


def _dyadic_text(m: int, e: int) -> Number:
    """``m 2ᵉ`` exactly: an int, or decimal text ``M e-K`` (``m 5ᵏ 10⁻ᵏ``, k = −e)."""
    if m == 0:
        return 0
    while m % 2 == 0:
        m //= 2
        e += 1
    if e >= 0:
        if abs(m).bit_length() + e > _INTEGER_LIMIT.bit_length():
            raise ValueError(f"{m} x 2^{e} is beyond 1e±{MAX_DECIMAL_EXPONENT}")
        return m << e
    digits = abs(m) * 5 ** (-e)
    # 14000 bits are ~4200 digits: the grammar's digit limit then applies to the text, and
    # Python's str() of an int (at most 4300 digits) is still allowed.
    if digits.bit_length() > 14000:
        raise ValueError(
            f"its exact value has more than {MAX_SIGNIFICANT_DIGITS} digits (the limit of "
            "scene numbers): give it as decimal text"
        )
    return f"{'-' if m < 0 else ''}{digits}e{e}"


def shown(value: Any) -> str:
    """``value`` for a message, never cut so that it reads as another number: a long integer
    or text is abbreviated with its magnitude and length (``10**400`` is not 60 digits)."""
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) >= 10**20:
        digits = len(str(abs(value))) if abs(value) < _INTEGER_LIMIT else None
        if digits is None:
            return f"an integer of {abs(value).bit_length()} bits"
        lead = str(abs(value))[:6]
        sign = "-" if value < 0 else ""
        return f"{sign}{lead[0]}.{lead[1:]}e+{digits - 1} (an integer of {digits} digits)"
    if isinstance(value, str):
        text = repr(value)
        if len(text) <= 60:
            return text
        return f"{text[:24]}…{text[-12:]} ({len(value)} characters)"
    text = repr(value) if isinstance(value, float) else str(value)
    return text if len(text) <= 60 else f"{text[:24]}…{text[-12:]} ({len(text)} characters)"


def approx(value: Fraction, digits: int = 3) -> str:
    """A rational to ``digits`` significant digits, beyond a float's range too (the steps a
    quad span of 1e4000 needs): ``2.17e+305``."""
    if abs(value) < Fraction(10) ** 300:
        return f"{float(value):.{digits}g}"
    import mpmath

    with mpmath.workdps(digits + 5):
        return mpmath.nstr(rational_mpf(value), digits, min_fixed=0, max_fixed=0)


def scene_mpf(value: Any) -> Any:
    """A scene number as an mpmath number, correctly rounded to mpmath's current precision
    (:func:`rational_mpf`); an mpmath number is returned as it is."""
    import mpmath

    if isinstance(value, mpmath.mpf):
        return value
    return rational_mpf(exact_fraction(value))


def rational_mpf(value: Fraction) -> Any:
    """``value`` correctly rounded (to nearest) at mpmath's current precision.

    ``mpf(numerator) / denominator`` rounds twice (the numerator of π written to 36 digits
    has 120 bits): at 30 digits it lands above mpmath's π while the exact value is below it,
    so a range check made exactly and one made in mpmath disagree. Rounding once keeps every
    comparison with a correctly rounded constant (π, 2π) the same as the exact one.
    """
    import mpmath
    from mpmath import libmp

    if value.denominator == 1:
        return mpmath.mpf(value.numerator)
    return mpmath.mp.make_mpf(
        libmp.from_rational(value.numerator, value.denominator, mpmath.mp.prec, libmp.round_nearest)
    )


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
    """Whether ``|v|`` is within ``tolerance`` of 1, decided exactly, and ``|v|`` as short text
    (for the refusal of one that is not; empty for one that is).

    ``float()`` of the squared norm would overflow for components beyond 1e154.
    """
    import mpmath

    norm2 = sum(exact_fraction(v) ** 2 for v in values)
    if (1 - tolerance) ** 2 <= norm2 <= (1 + tolerance) ** 2:
        return True, ""  # a scene's every member checks its attitude: no root for nothing
    with mpmath.workdps(25):
        return False, mpmath.nstr(mpmath.sqrt(mpmath.mpf(norm2.numerator) / norm2.denominator), 17)


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
