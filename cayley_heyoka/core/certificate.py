"""Certificates of reference solutions: error bounds, and the ladder of precisions they climb.

A reference is certified either by its closed form (each value's own error bound) or by a
second run in a higher precision (:func:`difference_certificate`); the certificate holds
the absolute error of every output and event time, and the largest of them scaled (relative
above 1). :func:`precision_for` and :func:`next_precision` are the precisions tried.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .evaluation import Rounding
from .exact import difference
from .precision import Precision

BITS_PER_DIGIT = math.log2(10)


def precision_for(digits: float) -> Precision:
    """The cheapest precision with ``digits`` significant decimal digits."""
    bits = math.ceil(digits * BITS_PER_DIGIT) + 1
    if bits <= 53:
        return Precision("double")
    if bits <= 113:
        return Precision("quad")
    return Precision("real", 32 * math.ceil(bits / 32))


def label(prec: Precision) -> str:
    """How a precision is named to people: heyoka's ``real128`` is IEEE quad, not MPFR."""
    names = {"double": "double", "quad": "quad (IEEE binary128)"}
    return names.get(prec.kind, f"MPFR {prec.bits} bits")


def next_precision(prec: Precision) -> Precision:
    """The next rung of the ladder: at least 32 more bits, or a quarter more."""
    if prec.kind == "double":
        return Precision("quad")
    bits = prec.bits + max(32, prec.bits // 4)
    return Precision("real", 32 * math.ceil(bits / 32))


@dataclass
class Certificate:
    """The error bound of a reference solution.

    Attributes
    ----------
    method
        ``"closed form"`` or ``"two precisions"``.
    compared_with
        What the solution was compared with (the closed form's name, or the other precision).
    errors
        Absolute error of each variable and monitor at each output time (shape of its
        array; 0 where the value is undefined, NaN, in both results compared). A certificate
        of a file covers every array the file holds (:func:`uncovered`).
    event_errors
        Estimated absolute error of each recorded event's times.
    proved
        The errors are proved bounds (ball arithmetic on a closed form), not estimates.
    scaled
        The largest error, absolute where |value| ≤ 1 and relative above.
    worst
        Where the largest scaled error is: ``(variable, time)``.
    """

    method: str
    compared_with: str
    errors: dict[str, np.ndarray]
    event_errors: dict[str, np.ndarray] = field(default_factory=dict)
    proved: bool = False
    scaled: float = 0.0
    worst: tuple[str, float] = ("", 0.0)

    def digits_text(self) -> str:
        """The digits for a message: "12.3 digits", "no digits" for an unbounded error, "every
        digit" where no error was found (two runs that agree exactly)."""
        digits = self.digits()
        if math.isfinite(digits):
            return f"{digits:.1f} digits"
        return "every digit (no error found)" if digits > 0 else "no digits"

    def digits(self) -> float:
        """Decimal digits certified: -log10 of the largest scaled error."""
        return math.inf if self.scaled == 0 else -math.log10(self.scaled)


def _scaled(values: np.ndarray, errors: np.ndarray) -> np.ndarray:
    """Errors relative above 1 and absolute below; an unbounded error (an infinite value's,
    λ at a half-turn) stays infinite instead of becoming ∞/∞ and being passed over. A zero
    error is zero whatever the value: that of a value undefined (NaN) in both runs compared
    (:func:`cayley_heyoka.core.exact.difference`)."""
    with np.errstate(invalid="ignore", over="ignore"):
        mag = np.abs(np.asarray(values, dtype=float))
        scaled = errors / np.maximum(mag, 1.0)
    scaled = np.where(np.isnan(scaled) | np.isinf(errors), np.inf, scaled)
    return np.where(errors == 0, 0.0, scaled)


def worst(cert: Certificate, values: dict[str, np.ndarray], t: np.ndarray) -> Certificate:
    """``cert`` with its largest scaled error and where it is, over ``values`` (by name: the
    result's variables and monitors) at the output times ``t``."""
    best = (0.0, "", 0.0)
    for name, err in cert.errors.items():
        s = _scaled(values[name], err)
        if s.size and np.max(s) > best[0]:
            row = int(np.unravel_index(int(np.argmax(s)), s.shape)[0])  # a vector's row
            best = (float(np.max(s)), name, float(t[row]))
    for name, err in cert.event_errors.items():
        if err.size and np.max(err) > best[0]:
            best = (float(np.max(err)), f"event {name}", math.nan)
    cert.scaled, cert.worst = best[0], (best[1], best[2])
    return cert


def written(result: Any) -> dict[str, np.ndarray]:
    """Every array a result file holds on its output times, by name: its variables and
    monitors (what a certificate must cover; a thinned view may hold variables only)."""
    return {**result.variables, **getattr(result, "monitors", {})}


def uncovered(cert: Certificate, result: Any) -> tuple[str, ...]:
    """The variables and monitors of ``result`` that ``cert`` gives no error for."""
    return tuple(name for name in written(result) if name not in cert.errors)


def difference_certificate(written_run: Any, other: Any) -> Certificate:
    """The certificate of ``written_run`` from a less precise run ``other`` of the same scene:
    the difference of every variable and monitor at every output time, and of every event
    time (a value undefined in both runs agrees: :func:`cayley_heyoka.core.exact.difference`)."""
    ours, theirs = written(written_run), written(other)
    errors = {name: difference(values, theirs[name]) for name, values in ours.items()}
    event_errors = {}
    for name, log in written_run.events.items():
        them = other.events.get(name)
        if them is None or len(them) != len(log) or list(them.label) != list(log.label):
            raise RuntimeError(
                f"event {name!r}: {len(log)} occurrences in {written_run.precision.name}, "
                f"{0 if them is None else len(them)} in {other.precision.name} — the "
                "runs disagree on an event (one grazing zero?): no certificate"
            )
        event_errors[name] = difference(log.time, them.time)
    cert = Certificate("two precisions", other.precision.name, errors, event_errors)
    return worst(cert, ours, np.asarray(written_run.t, dtype=float))


def precision_of(result: Any) -> Precision:
    """The precision of a result, or of a thinned view of one (which has only the arrays)."""
    if hasattr(result, "precision"):
        return result.precision
    x = np.ravel(result.t)[0]
    if isinstance(x, float | np.floating):
        return Precision("double")
    return Precision("real", x.prec) if hasattr(x, "prec") else Precision("quad")


def rounding_of(prec: Precision) -> Rounding:
    """What the closed-form workers need of a precision."""
    return Rounding(prec.kind, prec.bits)
