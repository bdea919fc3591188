"""Keeping the departure ρ small: whole revolutions are moved out of the integrated state.

ρ grows by about 2π per orbit. Integrated as it is, it would lose absolute accuracy like its own ulp
(after 1000 orbits ρ ≈ 6000 carries ~1e-12 per rounding, against ~1e-15 for the other variables),
and heyoka's error control, which scales the tolerance by the largest state component, would loosen
the step for every variable by the same factor (docs/orbits.md, "Near-equatorial orbits", practical
note).

So the integrator carries ``ρ_s = ρ − k C``, where ``C`` is 2π rounded to the run's precision
and ``k`` an integer held in runtime parameters. A terminal event at ``ρ_s = C`` (ρ only
increases: ρ̇ = h/r² > 0) subtracts ``C`` — exactly, by Sterbenz's lemma — and adds one to ``k``.
The equations need ρ only modulo 2π (through ``u = ρ − Σ``, or cos ρ and sin ρ), which is
``ρ_s + k (C − 2π)``: the *phase* parameter ``k (C − 2π)``, computed exactly and rounded once,
removes the rounding of 2π, which would otherwise accumulate k times. The reported ρ is
``ρ_s + k C`` (the *offset* parameter), continuous across the events.

The handler works in the run's arithmetic: ``k C`` and ``k (C − 2π)`` are integers times powers
of two (C exactly, C − 2π to the run's bits + 128), each rounded once to the run's type from
the exact integer product: a Python float, ``real128`` or ``real`` built from the integer
(correctly rounded) and scaled by a power of two (exact). No decimal text, no mpmath arithmetic
per revolution.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import mpmath

from ..core.model import ParTable
from ..core.precision import Precision, dyadic_parts

Expr = Any  # a heyoka expression


class Revolutions:
    """The revolution count ``k`` of ρ and the parameters that carry it.

    ``k`` itself lives in the parameters: ``orbit.rho_offset`` is ``k C`` rounded once, from
    which the handler reads ``k`` back (exactly, for any count a run can reach), so that the
    handler keeps no number of its own and serves every scene of its structure.

    Parameters
    ----------
    pars
        The model's parameter table; ``orbit.two_pi``, ``orbit.rho_offset`` and
        ``orbit.rho_phase`` are allocated in it.
    precision
        The run's precision (``C`` is 2π rounded to it).
    values
        Their values (:func:`values`).
    state_index
        Position of ρ in the integrator's state.
    """

    def __init__(
        self, pars: ParTable, precision: Precision, values: Mapping[str, Any], state_index: int
    ) -> None:
        self.precision = precision
        self.state_index = state_index
        turn = _Turn.of(precision)
        self._C_run = precision.number(turn.text(turn.C))
        self._C_parts, self._D = turn.C_parts, turn.D
        self.two_pi = pars.add("orbit.two_pi", values["orbit.two_pi"])
        self.offset = pars.add("orbit.rho_offset", values["orbit.rho_offset"])
        self.phase = pars.add("orbit.rho_phase", values["orbit.rho_phase"])
        self._offset_index = pars.index("orbit.rho_offset")
        self._phase_index = pars.index("orbit.rho_phase")
        self._C_double = float(self._C_run)

    def rho(self, rho_state: Expr) -> Expr:
        """The continuous ρ, for output."""
        return rho_state + self.offset

    def angle(self, rho_state: Expr) -> Expr:
        """An expression equal to ρ modulo 2π, for the equations."""
        return rho_state + self.phase

    def event(self, rho_state: Expr) -> Expr:
        """Zero where the integrated ρ reaches C (crossed upwards)."""
        return rho_state - self.two_pi

    def count(self, pars: Any) -> int:
        """The revolutions ``k`` completed, read back from ``k C`` (its relative error, a few
        units of 2⁻⁵³ in double, leaves the nearest integer exact below 2⁵⁰ revolutions)."""
        return round(float(pars[self._offset_index]) / self._C_double)

    def __call__(self, ta: Any, pars: Any) -> None:
        """Terminal-event handler: move one revolution from the state into the parameters."""
        ta.state[self.state_index] -= self._C_run
        k = self.count(pars) + 1
        (mc, ec), (md, ed) = self._C_parts, self._D
        scaled = self.precision.dyadic
        pars[self._offset_index] = scaled(k * mc, ec)
        pars[self._phase_index] = scaled(k * md, ed)


class _Turn:
    """C = 2π rounded to a precision, C − 2π, and the text of their multiples."""

    _held: dict[int, _Turn] = {}

    def __init__(self, precision: Precision) -> None:
        self.dps = precision.dps + 20
        with mpmath.workprec(precision.bits):
            self.C = +(2 * mpmath.pi)  # exactly the value C takes in the run's precision
        with mpmath.workprec(precision.bits + 128):
            # C − 2π, to enough bits that k (C − 2π) rounds as the exact product would.
            self.D = dyadic_parts(self.C - 2 * mpmath.pi)
        self.C_parts = dyadic_parts(self.C)

    @classmethod
    def of(cls, precision: Precision) -> _Turn:
        turn = cls._held.get(precision.bits)
        if turn is None:
            turn = cls._held[precision.bits] = cls(precision)
        return turn

    def text(self, value: Any) -> str:
        return mpmath.nstr(value, self.dps, strip_zeros=False)


def values(precision: Precision, rho0: str) -> tuple[dict[str, str], str]:
    """The parameters of :class:`Revolutions` for ρ₀ = ``rho0`` (decimal text with guard
    digits) and the reduced ρ₀ the integrator starts from: ρ₀ − k C, k = ⌊ρ₀ / C⌋."""
    turn = _Turn.of(precision)
    C = turn.C
    with mpmath.workdps(turn.dps):
        rho = mpmath.mpf(rho0)
        k = int(mpmath.floor(rho / C))
        reduced = turn.text(rho - k * C)
    return count_values(precision, k), reduced


def count_values(precision: Precision, k: int) -> dict[str, str]:
    """The parameters of :class:`Revolutions` after ``k`` whole revolutions (:func:`values`
    for a ρ₀ in [k C, (k + 1) C))."""
    turn = _Turn.of(precision)
    C = turn.C
    with mpmath.workdps(turn.dps):
        return {
            "orbit.two_pi": turn.text(C),
            "orbit.rho_offset": turn.text(k * C),
            "orbit.rho_phase": turn.text(k * (C - 2 * mpmath.pi)),
        }
