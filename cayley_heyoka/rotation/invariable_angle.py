"""Ψ = 2 tan⁻¹ν₀, the body's angle about the invariable line, integrated with the motion.

Referred to the invariable frame (space z along the angular momentum L, its azimuth fixed by
ν₀(0) = 0), Cayley (1843) reduces the attitude of the torque-free body to the angle
Ψ = 2 tan⁻¹ν₀ about L, a quadrature over the rates:

    dΨ/dt = (h + k r) / (k + C r),    h = Ap² + Bq² + Cr² (= 2T),  k = |L|

(docs/theory/rotation.md; the closed form ``FreeRigidBody.at(t).psi`` evaluates the same Ψ).
With ``output.invariable_angle = true`` a torque-free scene integrates Ψ beside the rates and
reports it as the result variable ``psi``, continuous (not reduced modulo 2π), Ψ(0) = 0, so
that an integration and the closed form can be compared on the quantity the memoir is about.
``h`` and ``k`` are the motion's constants, computed exactly from the initial rates and rounded
once to the run's precision.

Kept small: heyoka's error control scales the tolerance by the largest state component, so a Ψ
of thousands of radians would lengthen every step of the rates. The state carries
``u = (Ψ − n C)/8``, with ``C`` = 2π rounded to the run's precision and ``n`` an integer count
of turns (|u| < C/8 < 0.8, the size of the rates' own scale or below; the division by 8 is
exact). A terminal event where u reaches ±C/8 moves a turn into ``n`` (exactly, by Sterbenz's
lemma) and the reported ``Ψ = 8u + nC``, with ``nC`` rounded once per turn. Ψ is not monotone
in general (dΨ/dt < 0 where h + kr < 0), so the event watches both ends.
"""

from __future__ import annotations

from collections.abc import Mapping
from fractions import Fraction
from typing import Any

import mpmath

from ..core.errors import SceneError
from ..core.model import ParTable, TerminalSpec
from ..core.precision import Precision, fraction_text, two_pi_parts

Expr = Any  # a heyoka expression
#: u = (Ψ − nC)/SCALE: a power of two, so that the scaling is exact.
SCALE = 8


def wanted(options: dict[str, Any]) -> bool:
    """Whether the scene's ``output.invariable_angle`` asks for Ψ (refusing a non-boolean)."""
    value = options.get("invariable_angle", False)
    if not isinstance(value, bool):
        raise SceneError("output.invariable_angle", f"must be true or false, got {value!r}")
    return value


class InvariableAngle:
    """The state variable ``u``, its equation, the turn count and the events that keep it small.

    Parameters
    ----------
    pars
        The model's parameters; ``psi.h``, ``psi.k``, ``psi.two_pi_scaled`` and
        ``psi.turns`` are allocated in it.
    precision
        The run's precision.
    inertia, rates
        The exact moments ``A, B, C`` and initial rates ``p, q, r``.
    state_index
        Position of ``u`` in the integrator's state.
    """

    def __init__(
        self,
        pars: ParTable,
        precision: Precision,
        values: Mapping[str, Any],
        state_index: int,
    ) -> None:
        self.precision = precision
        self.state_index = state_index
        self.n = 0
        self._C, self._step = _two_pi(precision)
        self.h = pars.add("psi.h", values["psi.h"])
        self.k = pars.add("psi.k", values["psi.k"])
        self.bound = pars.add("psi.two_pi_scaled", values["psi.two_pi_scaled"])
        self.turns = pars.add("psi.turns", values["psi.turns"])
        self._scale = pars.constant(SCALE)  # in the run's type: no double node in a quad system
        self._turns_index = pars.index("psi.turns")

    def rhs(self, r: Expr, C: Expr) -> Expr:
        """du/dt = (h + k r) / (SCALE (k + C r))."""
        return (self.h + self.k * r) / (self._scale * (self.k + C * r))

    def psi(self, u: Expr) -> Expr:
        """The continuous Ψ, for output."""
        return self._scale * u + self.turns

    def terminal(self, u: Expr) -> TerminalSpec:
        """One event for both turns: u² − (C/8)² crosses zero upwards where u leaves
        (−C/8, C/8) at either end; the handler tells which end by u's sign."""
        return TerminalSpec(u * u - self.bound * self.bound, 1, self, "psi_turns")

    def __call__(self, ta: Any, pars: Any) -> None:
        """Terminal-event handler: move one turn from the state into the count."""
        forwards = ta.state[self.state_index] > 0
        if forwards:
            ta.state[self.state_index] -= self._step
        else:
            ta.state[self.state_index] += self._step
        self.n += 1 if forwards else -1
        mc, ec = self._C
        pars[self._turns_index] = self.precision.dyadic(self.n * mc, ec)

    def checkpoint(self) -> int:
        """The turns counted (the engine's snapshot of a run carries it)."""
        return self.n

    def resume(self, n: int) -> None:
        """Continue after ``n`` turns (the parameters come back with the snapshot)."""
        self.n = int(n)


def values(
    precision: Precision,
    inertia: tuple[Fraction, Fraction, Fraction],
    rates: tuple[Fraction, Fraction, Fraction],
) -> dict[str, Any]:
    """The parameters of Ψ for the exact moments ``A, B, C`` and initial rates ``p, q, r``:
    ``h = 2T``, ``k = |L|``, the turn C/8 and no turn yet.

    Raises
    ------
    SceneError
        ``output.invariable_angle``: Ψ is undefined for these rates.
    """
    A, B, C = inertia
    p, q, r = rates
    if p == 0 and q == 0 and r <= 0:
        raise SceneError(
            "output.invariable_angle",
            "Ψ = 2 tan⁻¹ν₀ is undefined here: with p = q = 0 and r ≤ 0 the body's third "
            "axis points against L (or L = 0), where k + Cr = 0",
        )
    h = A * p * p + B * q * q + C * r * r
    k2 = (A * p) ** 2 + (B * q) ** 2 + (C * r) ** 2
    with mpmath.workprec(precision.bits + 64):
        k = mpmath.sqrt(mpmath.mpf(k2.numerator) / k2.denominator)
        k_text = mpmath.nstr(k, precision.dps + 20, strip_zeros=False)
    return {
        "psi.h": fraction_text(h, precision),
        "psi.k": k_text,
        "psi.two_pi_scaled": _two_pi(precision)[1],
        "psi.turns": precision.dyadic(0, 0),
    }


def _two_pi(precision: Precision) -> tuple[tuple[int, int], Any]:
    """C = 2π in the run's precision as (mantissa, exponent), and C/8 = C/SCALE (exact)."""
    mc, ec = C = two_pi_parts(precision)
    return C, precision.dyadic(mc, ec - 3)
