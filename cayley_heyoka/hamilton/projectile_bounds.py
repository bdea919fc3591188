"""Hamilton's projectile (113.)–(114.) and S along the motion, in Arb balls: proved bounds.

The formulas are :func:`.projectile.motion`'s (symbols there), evaluated in ball arithmetic
(python-flint): every input enters exactly (decimal text enclosed, binary numbers exact), and
each value is a ball that provably holds the exact value. The even functions that cancel near
0 — sin x / x and (x − sin x)/x³ — are Arb's ``sinc`` and, for |x| < ½, the alternating series
Σ (−1)ᵏ x²ᵏ/(2k + 3)! with its first omitted term added to the radius (the terms decrease for
|x| < 1, so that term bounds the tail). The working precision doubles until every value is
proved to the digits asked, up to 16×; past that the bound reached is reported
(:class:`~cayley_heyoka.core.accuracy.PrecisionNotReached`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction

import mpmath
from flint import arb, ctx

from ..core.accuracy import PrecisionNotReached
from ..core.balls import Enclosure, ball, bound, exact_mid
from ..core.inputs import check_dps, read_triple
from .projectile import Elementary, motion, read_parameters

__all__ = ["ProjectileBounds", "projectile_bounds"]

NAMES = ("eta1", "eta2", "eta3", "varpi1", "varpi2", "varpi3", "S")
GROWTH, MAX_GROWTH = 2, 16


@dataclass(frozen=True)
class ProjectileBounds(Enclosure):
    """The projectile at one time, each value with a proved bound (:class:`Enclosure`):
    ``eta1 … eta3, varpi1 … varpi3, S``."""


def _x_minus_sin(x: arb) -> arb:
    """(x − sin x)/x³, 1/6 at 0."""
    if abs(x) < arb(1) / 2:
        # Σ (−1)^k x^{2k}/(2k+3)!: for |x| < ½ the terms fall by more than 80 each, so the
        # first omitted one bounds the tail.
        x2, term, total, k = x * x, arb(1) / 6, arb(0), 0
        tiny = arb(2) ** (-ctx.prec - 10)
        while True:
            total += term
            k += 1
            term = -term * x2 / ((2 * k + 2) * (2 * k + 3))
            if abs(term) < tiny:
                return total + arb(0, abs(term).upper())
    return (x - x.sin()) / (x * x * x)


ARB = Elementary(lambda x: x.cos(), lambda x: x.sinc(), _x_minus_sin, arb(0))


def _motion(g: arb, mu: arb, nu: arb, e: Sequence[arb], p: Sequence[arb], t: arb) -> list[arb]:
    out = motion(g, mu, nu, e, p, t, ARB)
    return [out[n] for n in NAMES]


def projectile_bounds(
    g: object,
    mu: object,
    nu: object,
    e: Sequence[object],
    p: Sequence[object],
    t: object,
    dps: int = 30,
) -> ProjectileBounds:
    """:func:`.projectile.projectile_solution` with proved bounds (same parameters, read the
    same way and checked there first), each below ``10**-dps`` (relative above 1)."""
    dps = check_dps(dps)
    with mpmath.workdps(dps + 20):  # the mpmath route's checks and messages, before any work
        # (an exact time difference, a Fraction, needs none)
        read_parameters(g, mu, nu, 0 if isinstance(t, Fraction) else t)
        read_triple(e, "e")
        read_triple(p, "p")
    first = int(dps * 3.33) + 64
    # Rounding x = ωt costs log₁₀|x| digits in cos x and sin x: the first attempt adds them.
    with ctx.workprec(64):
        span = max(abs(exact_mid(ball(w, "mu/nu") * ball(t, "t"))) for w in (mu, nu))
    first += int(3.33 * float(mpmath.log10(1 + span))) + 4
    bits, last = first, ("the values", math.inf)
    while bits <= MAX_GROWTH * first:
        with ctx.workprec(bits):
            balls = _motion(
                ball(g, "g"),
                ball(mu, "mu"),
                ball(nu, "nu"),
                [ball(x, "e") for x in e],
                [ball(x, "p") for x in p],
                ball(t, "t"),
            )
            values = {n: exact_mid(b) for n, b in zip(NAMES, balls, strict=True)}
            bounds = {n: bound(b) for n, b in zip(NAMES, balls, strict=True)}
        worst = max(NAMES, key=lambda n: bounds[n] / max(abs(values[n]), 1))
        reached = bounds[worst] / max(abs(values[worst]), 1)
        if reached <= mpmath.mpf(10) ** -dps:
            return ProjectileBounds(values, bounds, bits)
        last = (worst, float(reached))
        bits *= GROWTH
    raise PrecisionNotReached(last[0], dps, last[1], "no tighter bound was proved")
