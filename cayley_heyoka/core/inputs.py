"""Reading the inputs of the closed forms: exact numbers, and errors that name the parameter."""

from __future__ import annotations

from collections.abc import Sequence

import mpmath

from .accuracy import to_mpf

__all__ = ["check_dps", "read_inertia", "read_rates", "read_triple"]


#: The most digits a closed form is evaluated to: 1000 take seconds, 2000 half a minute, and
#: the time grows faster than the square (a reference run needs at most ~320).
MAX_DPS = 1000


def check_dps(dps: object) -> int:
    """The requested number of digits: an integer in 5 … :data:`MAX_DPS`."""
    if isinstance(dps, bool) or not isinstance(dps, int) or not 5 <= dps <= MAX_DPS:
        raise ValueError(f"dps must be an integer in 5 … {MAX_DPS}, got {dps!r}")
    return dps


def read_triple(values: object, name: str) -> list[mpmath.mpf]:
    """Three finite numbers, read exactly (:func:`to_mpf`); errors name ``name``."""
    if isinstance(values, str) or not isinstance(values, Sequence) or len(values) != 3:
        raise ValueError(f"{name}: expected a sequence of three numbers, got {values!r}")
    return [to_mpf(x, f"{name}[{i}]") for i, x in enumerate(values)]


def read_inertia(values: object, require_physical: bool = True) -> list[mpmath.mpf]:
    """Principal moments: three finite numbers > 0 obeying the triangle inequality.

    ``require_physical=False`` waives the triangle inequality: no rigid body violates it, but
    Euler's equations stay well posed (the separatrix cases of tests/reference/test_closed_form.py
    use 1, 2, 4).
    """
    A, B, C = read_triple(values, "inertia")
    if min(A, B, C) <= 0:
        raise ValueError(f"inertia: the principal moments must be > 0, got {values!r}")
    if require_physical and (A + B < C or B + C < A or C + A < B):
        raise ValueError(
            f"inertia: the moments {values!r} violate the triangle inequality "
            "(A + B >= C, B + C >= A, C + A >= B); pass require_physical=False for a "
            "mathematical test body"
        )
    return [A, B, C]


def read_rates(values: object) -> list[mpmath.mpf]:
    """Body rates: three finite numbers, not all zero."""
    w = read_triple(values, "rates")
    if all(x == 0 for x in w):
        raise ValueError("rates: the angular velocity is zero; there is no motion")
    return w
