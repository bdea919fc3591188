"""Floating-point precisions and the construction of numbers in them.

Every number that enters an integrator (state, parameters, tolerance, output times) is built
here, in the target type, from its *decimal text* when the text is known. ``real128(1.1)``
would carry the double rounding error of ``1.1`` into a quadruple-precision run; building
``real128("1.1")`` does not.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import heyoka as hy
import numpy as np

from .errors import SceneError

Number = float | int | str
"""A scene number: a Python float/int, or decimal text kept exact until the target type is known."""

_MIN_BITS = 64


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
            if not isinstance(self.bits, int) or self.bits < _MIN_BITS:
                raise SceneError(
                    "integrator.precision.bits",
                    f"must be an integer >= {_MIN_BITS} for multiprecision, got {self.bits!r}",
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
            if isinstance(bits, str) and bits.isdigit():
                bits = int(bits)
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
        """Build ``value`` in the target type, from its decimal text when it is a string."""
        if isinstance(value, bool):
            raise TypeError(f"expected a number, got {value!r}")
        if self.kind == "real" and isinstance(value, hy.real) and value.prec == self.bits:
            return value
        if self.kind == "quad" and isinstance(value, hy.real128):
            return value
        if self.kind == "double":
            return float(value)
        if self.kind == "quad":
            return hy.real128(value if isinstance(value, str) else _exact_text(value))
        if isinstance(value, str):
            return hy.real(value, self.bits)
        return hy.real(_exact_text(value), self.bits)

    def array(self, values: Iterable[Number]) -> np.ndarray:
        """A 1-d numpy array of ``values`` in the target type."""
        values = list(values)
        if self.kind == "double":
            return np.array([float(v) for v in values], dtype=float)
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
        return self.array(flat).reshape(texts.shape)


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


def exact_fraction(value: Number) -> Fraction:
    """The exact rational value of a scene number (used for validation without rounding)."""
    if isinstance(value, bool):
        raise TypeError(f"expected a number, got {value!r}")
    if isinstance(value, str):
        return Fraction(value.strip().replace("_", ""))
    return Fraction(value)


def fraction_text(value: Fraction, precision: Precision) -> str:
    """Decimal text of a rational, with enough digits to round correctly in ``precision``."""
    import mpmath

    with mpmath.workdps(precision.dps + 15):
        return mpmath.nstr(mpmath.mpf(value.numerator) / value.denominator, precision.dps + 10)
