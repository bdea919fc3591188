"""Euler's 1758 solution of the free rigid body relative to a fixed direction P, in mpmath.

From Euler (1758), "Du mouvement de rotation des corps solides autour d'un axe variable" (reproduced
by Cayley, 1868); additive constants of the angles as in docs/reference.md. Symbols of the memoir,
used below:

* ``A, B, C`` principal moments; ``p, q, r`` body rates (Euler's x, y, z).
* ``L, M, N = (B − C)/A, (C − A)/B, (A − B)/C`` (Euler's A, B, C), so that ``ṗ = Lqr`` etc.
* ``u`` with ``du = pqr dt``, ``u(0) = 0``; ``𝔄, 𝔅, ℭ = p(0)², q(0)², r(0)²`` so that
  ``p² = 𝔄 + 2Lu``, ``q² = 𝔅 + 2Mu``, ``r² = ℭ + 2Nu``.
* ``E = ω²(0)``, ``F = Ap² + Bq² + Cr²`` (= 2T), ``G = A²p² + B²q² + C²r²`` (= |L|²),
  ``H = L²A𝔅ℭ + M²Bℭ𝔄 + N²C𝔄𝔅``, ``K = EG − F²`` (§5).
* ``P`` a direction fixed in space; ``(cos l, cos m, cos n)`` its body components;
  ``𝔇 = Ap cos l + Bq cos m + Cr cos n`` (= L·P, constant), ``v = ω·P``.
* ``f = √(G − 𝔇²)``, ``s = √(K − 2LMN G u)`` (= |L_b × ω|).
* ``U`` — Euler's angle (§6): ``sin U = (Gv − 𝔇F)/(fs)``, ``cos U = √G R/(fs)`` with
  ``R = det[P, L_b, ω]``; ``U − π/2`` is the azimuth of ω about L from the half-plane holding P.
* ``φ + 𝔉`` — the inclination of the arc from P to the instantaneous axis (§8), with
  ``tan(φ + 𝔉) = (Ff − 𝔇 s sin U)/(√G s cos U)``.

Euler's λ, μ, ν are *spherical angles* (inclinations of the arcs from P to the principal axes),
not the Cayley–Rodrigues parameters of the rest of the project; they are not needed here (were
they, the code would call them ``incl_l, incl_m, incl_n``).

The motion is evaluated in the regularised angle Θ of §2.1 (``u = u_lo + Δ sin²Θ``), in which
``t = ∫ du/(pqr)`` becomes an analytic quadrature with break points at multiples of π/2; Θ
increases with t. :class:`RegularisedRates` holds that parametrisation and is shared with
:mod:`.cayley1846`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import NamedTuple

import mpmath

from ..core.accuracy import PrecisionNotReached, certify, shown, shown_error, to_mpf
from ..core.balls import Enclosure
from ..core.inputs import check_dps, read_inertia, read_rates, read_triple
from ..core.vectors import cross

__all__ = [
    "Euler1758",
    "EulerState",
    "QuarterwiseIntegral",
    "RegularisedRates",
    "ThetaPoint",
    "quarter_sin_cos",
    "separatrix_distance",
    "theta_at_time",
]

GUARD = 12
# Precision of the cheap first solve whose result only seeds Newton's method at full precision.
GUESS_DPS = 20
# Gauss–Legendre is the fast rule for these analytic integrands; its nodes cost too much to
# compute beyond this degree (192 nodes), where tanh-sinh takes over (it also copes with the
# sharp peaks next to the separatrix).
GAUSS_MAXDEGREE = 7


# -- the regularised parametrisation (§2.1) --------------------------------------------------------
class ThetaPoint(NamedTuple):
    """Θ = quarter·π/2 + offset with 0 ≤ offset ≤ π/2: trigonometry stays on small arguments."""

    quarter: int
    offset: mpmath.mpf

    @property
    def value(self) -> mpmath.mpf:
        return self.quarter * mpmath.pi / 2 + self.offset

    @classmethod
    def of(cls, theta: mpmath.mpf) -> ThetaPoint:
        half_pi = mpmath.pi / 2
        quarter = int(mpmath.floor(theta / half_pi))
        offset = theta - quarter * half_pi
        if offset < 0:
            offset = mpmath.mpf(0)
        return cls(quarter, min(offset, half_pi))


def quarter_sin_cos(quarter: int, x: mpmath.mpf) -> tuple[mpmath.mpf, mpmath.mpf]:
    """sin Θ and cos Θ at Θ = quarter·π/2 + x."""
    c, s = mpmath.cos_sin(x)
    j = quarter % 4
    if j == 0:
        return s, c
    if j == 1:
        return c, -s
    if j == 2:
        return -s, -c
    return -c, s


class RatesAt(NamedTuple):
    u: mpmath.mpf
    rates: tuple[mpmath.mpf, mpmath.mpf, mpmath.mpf]
    dt_dtheta: mpmath.mpf


Integrand = Callable[[mpmath.mpf, mpmath.mpf], mpmath.mpf]


class RegularisedRates:
    """Euler's body rates in the regularised angle Θ (u = u_lo + Δ sin²Θ), at one precision.

    Build it inside ``mpmath.workdps(d)``; every method must run at that same precision.

    Parameters
    ----------
    inertia, rates : sequence of mpf
        Principal moments and body rates at t = 0 (already validated).
    target_dps : int
        The digits finally requested: a quadrature whose own error estimate exceeds
        ``10**-target_dps`` raises :class:`PrecisionNotReached`.

    Raises
    ------
    ValueError
        For a steady rotation about a principal axis (Δ = 0: nothing to parametrise) and for a
        motion on the separatrix (the component that never vanishes would reach zero).
    """

    def __init__(
        self, inertia: Sequence[mpmath.mpf], rates: Sequence[mpmath.mpf], target_dps: int
    ) -> None:
        I = tuple(inertia)  # noqa: E741 - the inertia triple
        w = tuple(rates)
        self.target_dps = target_dps
        self.tolerance = mpmath.mpf(10) ** -target_dps
        self.c = tuple((I[(i + 1) % 3] - I[(i + 2) % 3]) / I[i] for i in range(3))
        frak = tuple(x * x for x in w)
        self.frak = frak
        # |L_b × ω|² = K term by term: zero exactly for a rotation about a principal axis.
        if all(
            (I[(i + 1) % 3] - I[(i + 2) % 3]) * w[(i + 1) % 3] * w[(i + 2) % 3] == 0
            for i in range(3)
        ):
            raise ValueError(
                "rates: steady rotation about a principal axis (ω ∥ L, Δ = 0); Euler's angle U "
                "and Cayley's υ-quadratures are undefined for it"
            )
        c = self.c
        positive = [i for i in range(3) if c[i] > 0]
        negative = [i for i in range(3) if c[i] < 0]
        root = {i: -frak[i] / (2 * c[i]) for i in positive + negative}
        i_lo = max(positive, key=lambda i: root[i])
        i_hi = min(negative, key=lambda i: root[i])
        i3 = 3 - i_lo - i_hi
        self.i_lo, self.i_hi, self.i3 = i_lo, i_hi, i3
        self.u_lo = root[i_lo]
        # Both terms ≥ 0: Δ carries no cancellation.
        self.delta = frak[i_hi] / (2 * abs(c[i_hi])) + frak[i_lo] / (2 * c[i_lo])
        # x₃² = 𝔣₃ + 2c₃u at Θ = 0 and at Θ = π/2, each from the root it is measured against.
        self.x3sq_at_0 = frak[i3] - c[i3] * frak[i_lo] / c[i_lo]
        self.x3sq_at_half_pi = frak[i3] - c[i3] * frak[i_hi] / c[i_hi]
        if min(self.x3sq_at_0, self.x3sq_at_half_pi) <= 0:
            raise ValueError(
                "rates: the motion lies on the separatrix (2T·B_mid = |L|²); it is aperiodic and "
                "the quarter period is infinite"
            )
        # Next to the separatrix 1/|x₃| peaks sharply at a multiple of π/2: Gauss–Legendre
        # cannot resolve such a peak at an endpoint, tanh-sinh can.
        low, high = sorted((self.x3sq_at_0, self.x3sq_at_half_pi))
        self.sharp = low < high / 100
        self.sigma = 1 if w[i3] > 0 else -1
        self.amp_lo = mpmath.sqrt(2 * c[i_lo] * self.delta)
        self.amp_hi = self.sigma * mpmath.sqrt(2 * abs(c[i_hi]) * self.delta)
        self.scale = mpmath.sqrt(c[i_lo] * abs(c[i_hi]))
        self.theta0 = ThetaPoint.of(mpmath.atan2(w[i_lo] / self.amp_lo, w[i_hi] / self.amp_hi))
        self.time = QuarterwiseIntegral(self, lambda s, c: self.at(s, c).dt_dtheta, "t", even=True)
        self.quarter_period = self.time.quarters[0]
        self.time_at_theta0 = self.time(self.theta0)

    # -- pointwise -------------------------------------------------------------------------------
    def x3_squared(self, s: mpmath.mpf, c: mpmath.mpf) -> mpmath.mpf:
        """x₃² written as a sum of two non-negative terms, so it keeps its digits when small."""
        slope = 2 * self.c[self.i3] * self.delta
        if slope >= 0:
            return self.x3sq_at_0 + slope * s * s
        return self.x3sq_at_half_pi - slope * c * c

    def at(self, s: mpmath.mpf, c: mpmath.mpf) -> RatesAt:
        """u, (p, q, r) and dt/dΘ at the Θ with sin Θ = s, cos Θ = c."""
        x3sq = self.x3_squared(s, c)
        root = mpmath.sqrt(x3sq)
        x = [mpmath.mpf(0)] * 3
        x[self.i_lo] = self.amp_lo * s
        x[self.i_hi] = self.amp_hi * c
        x[self.i3] = self.sigma * root
        u = self.u_lo + self.delta * s * s
        return RatesAt(u, (x[0], x[1], x[2]), 1 / (self.scale * root))

    def derivative(self, s: mpmath.mpf, c: mpmath.mpf) -> tuple[mpmath.mpf, ...]:
        """d(p, q, r)/dΘ."""
        d = [mpmath.mpf(0)] * 3
        d[self.i_lo] = self.amp_lo * c
        d[self.i_hi] = -self.amp_hi * s
        slope = 2 * self.c[self.i3] * self.delta
        d[self.i3] = self.sigma * slope * s * c / mpmath.sqrt(self.x3_squared(s, c))
        return (d[0], d[1], d[2])

    def step_from(
        self, s0: mpmath.mpf, c0: mpmath.mpf, step: mpmath.mpf
    ) -> tuple[tuple[mpmath.mpf, ...], mpmath.mpf, mpmath.mpf]:
        """(p, q, r)(Θ₀ + step) − (p, q, r)(Θ₀), free of cancellation for a small step.

        Θ₀ is given by s0 = sin Θ₀, c0 = cos Θ₀; also returns sin and cos of Θ₀ + step.
        """
        ch, sh = mpmath.cos_sin(step / 2)
        mid_c, mid_s = c0 * ch - s0 * sh, s0 * ch + c0 * sh
        s1, c1 = s0 + 2 * mid_c * sh, c0 - 2 * mid_s * sh
        # sin²Θ₁ − sin²Θ₀ = sin(Θ₁ − Θ₀) sin(Θ₁ + Θ₀)
        dsq = 4 * sh * ch * mid_s * mid_c
        roots = mpmath.sqrt(self.x3_squared(s0, c0)) + mpmath.sqrt(self.x3_squared(s1, c1))
        d = [mpmath.mpf(0)] * 3
        d[self.i_lo] = 2 * self.amp_lo * mid_c * sh
        d[self.i_hi] = -2 * self.amp_hi * mid_s * sh
        d[self.i3] = self.sigma * 2 * self.c[self.i3] * self.delta * dsq / roots
        return (d[0], d[1], d[2]), s1, c1

    # -- quadrature ------------------------------------------------------------------------------
    def quad(
        self, integrand: Callable[[mpmath.mpf], object], a: mpmath.mpf, b: mpmath.mpf, name: str
    ) -> mpmath.mpf | mpmath.mpc:
        """∫_a^b integrand: Gauss–Legendre, then tanh-sinh if that did not converge.

        Tanh-sinh alone when the motion is next to the separatrix (``sharp``). Raises
        :class:`PrecisionNotReached` when the estimate exceeds the target (scaled like the closed
        forms': absolute up to 1, relative above).
        """
        if a == b:
            return mpmath.mpf(0)
        converged = False
        if not self.sharp:
            value, error = mpmath.quad(
                integrand, [a, b], method="gauss-legendre", maxdegree=GAUSS_MAXDEGREE, error=True
            )
            converged = error <= mpmath.eps * max(1, abs(value))
        if not converged:
            value, error = mpmath.quad(integrand, [a, b], method="tanh-sinh", error=True)
        if error > self.tolerance * max(1, abs(value)):
            raise PrecisionNotReached(
                name, self.target_dps, float(error), "the quadrature did not converge"
            )
        return value

    def quad_in_quarter(
        self, integrand: Integrand, quarter: int, a: mpmath.mpf, b: mpmath.mpf, name: str
    ) -> mpmath.mpf:
        """∫ integrand dΘ over Θ = quarter·π/2 + [a, b] (an integrand of sin Θ, cos Θ)."""
        return self.quad(lambda x: integrand(*quarter_sin_cos(quarter, x)), a, b, name)

    # -- t → Θ ---------------------------------------------------------------------------------
    def theta_at(self, t: mpmath.mpf, guess: ThetaPoint | None = None) -> ThetaPoint:
        """Θ(t): the quarter from T_q, then a safeguarded Newton iteration inside it (§10).

        Each Newton step adds the integral over the step to the running value, so only the
        first evaluation integrates over a long interval.
        """
        target = t + self.time_at_theta0
        T_q = self.quarter_period
        quarter = int(mpmath.floor(target / T_q))
        remainder = target - quarter * T_q
        half_pi = mpmath.pi / 2
        if guess is not None and guess.quarter == quarter:
            x = guess.offset
        elif guess is not None and guess.quarter < quarter:
            x = mpmath.mpf(0)
        elif guess is not None:
            x = half_pi
        else:
            x = half_pi * remainder / T_q

        def dt_dtheta(offset: mpmath.mpf) -> mpmath.mpf:
            return self.at(*quarter_sin_cos(quarter, offset)).dt_dtheta

        lo, hi = mpmath.mpf(0), half_pi
        elapsed = self.time.partial(quarter, x)
        tiny = 16 * mpmath.eps
        for _ in range(200):
            if elapsed < remainder:
                lo = max(lo, x)
            else:
                hi = min(hi, x)
            new = x + (remainder - elapsed) / dt_dtheta(x)
            if not lo <= new <= hi:
                new = (lo + hi) / 2
            elapsed += self.quad(dt_dtheta, x, new, "t (Newton step for Θ)")
            step, x = new - x, new
            if abs(step) <= tiny or hi - lo <= tiny:
                return ThetaPoint(quarter, x)
        raise PrecisionNotReached("Θ(t)", self.target_dps, float(abs(step)), "Newton failed")


class QuarterwiseIntegral:
    """``F(Θ) = ∫₀^Θ f dΘ`` of a 2π-periodic integrand ``f(sin Θ, cos Θ)``.

    Whole periods and whole quarters come from four cached quarter integrals, so the cost does
    not grow with Θ; the remaining partial quarter is integrated from its nearer end, which keeps
    a peak of the integrand at a multiple of π/2 (next to the separatrix) at an endpoint.

    Parameters
    ----------
    motion : RegularisedRates
    integrand : callable
        ``f(sin Θ, cos Θ)``.
    name : str
        Quantity named in a :class:`PrecisionNotReached`.
    even : bool
        ``f`` depends on sin²Θ only: the four quarters are equal and one is integrated.
    """

    def __init__(
        self, motion: RegularisedRates, integrand: Integrand, name: str, *, even: bool = False
    ) -> None:
        self.motion, self.integrand, self.name = motion, integrand, name
        half_pi = mpmath.pi / 2
        first = motion.quad_in_quarter(integrand, 0, 0, half_pi, name)
        if even:
            self.quarters = [first] * 4
        else:
            self.quarters = [first] + [
                motion.quad_in_quarter(integrand, j, 0, half_pi, name) for j in (1, 2, 3)
            ]
        self.per_period = sum(self.quarters)

    def partial(self, quarter: int, x: mpmath.mpf) -> mpmath.mpf:
        """∫ f over [quarter·π/2, quarter·π/2 + x]."""
        half_pi = mpmath.pi / 2
        if x <= half_pi / 2:
            return self.motion.quad_in_quarter(self.integrand, quarter, 0, x, self.name)
        rest = self.motion.quad_in_quarter(self.integrand, quarter, x, half_pi, self.name)
        return self.quarters[quarter % 4] - rest

    def between(self, a: ThetaPoint, b: ThetaPoint) -> mpmath.mpf:
        """∫_a^b f dΘ for two points in the same quarter."""
        return self.motion.quad_in_quarter(self.integrand, a.quarter, a.offset, b.offset, self.name)

    def __call__(self, point: ThetaPoint) -> mpmath.mpf:
        periods, j = divmod(point.quarter, 4)
        return periods * self.per_period + sum(self.quarters[:j]) + self.partial(j, point.offset)


def theta_at_time(
    motion_at: Callable[[int], RegularisedRates], t: mpmath.mpf, dps: int
) -> ThetaPoint:
    """Θ(t) at working precision ``dps``, seeded by a cheap solve at ``GUESS_DPS`` digits.

    ``motion_at(d)`` must return the parametrisation built at ``d`` digits.
    """
    with mpmath.workdps(GUESS_DPS):
        guess = motion_at(GUESS_DPS).theta_at(+t)
    return motion_at(dps).theta_at(t, guess)


def separatrix_distance(
    inertia: Sequence[mpmath.mpf], twice_energy: mpmath.mpf, momentum_squared: mpmath.mpf
) -> mpmath.mpf | None:
    """(2T·B_mid − |L|²)/|L|², as :class:`~.closed_form.FreeRigidBody` defines it; None unless
    the three moments are distinct (a symmetric body has no separatrix).

    Evaluate it at working precision: next to the separatrix the difference cancels.
    """
    if len(set(inertia)) < 3:
        return None
    middle = sorted(inertia)[1]
    return (middle * twice_energy - momentum_squared) / momentum_squared


# -- Euler's solution ------------------------------------------------------------------------------
@dataclass(frozen=True, repr=False)
class EulerState:
    """Euler's solution at one time, in the conventions of docs/reference.md.

    Attributes
    ----------
    t, p, q, r : mpf
        Time and body rates.
    u : mpf
        Euler's auxiliary variable (du = pqr dt, u(0) = 0).
    v : mpf
        ω·P.
    U : mpf
        Euler's angle, continuous, U(0) the principal value of atan2(Gv₀ − 𝔇F, √G R₀).
    cos_l, cos_m, cos_n : mpf
        Body components of P.
    phi_plus_F : mpf
        φ + 𝔉, continuous, its value at t = 0 the principal value of Euler's atan2.
    errors : dict
        Error estimate per quantity (absolute if |value| ≤ 1, else relative).
    """

    t: mpmath.mpf
    p: mpmath.mpf
    q: mpmath.mpf
    r: mpmath.mpf
    u: mpmath.mpf
    v: mpmath.mpf
    U: mpmath.mpf
    cos_l: mpmath.mpf
    cos_m: mpmath.mpf
    cos_n: mpmath.mpf
    phi_plus_F: mpmath.mpf
    errors: dict[str, mpmath.mpf] = field(repr=False)

    @property
    def error(self) -> mpmath.mpf:
        """The worst error estimate of the state."""
        return max(self.errors.values())

    def __repr__(self) -> str:
        """One line: the time, the body rates, Euler's angles U and φ + 𝔉, the worst error."""
        return (
            f"<EulerState t = {shown(self.t)}: p, q, r = {shown(self.p, self.q, self.r)}, "
            f"U = {shown(self.U)}, φ + 𝔉 = {shown(self.phi_plus_F)}, "
            f"error {shown_error(self.error)}>"
        )


_EULER_FIELDS = ("p", "q", "r", "u", "v", "U", "cos_l", "cos_m", "cos_n", "phi_plus_F")


class _EulerConstants:
    """Everything that depends on the inputs only, at one working precision."""

    def __init__(self, inertia, rates, direction, target_dps: int) -> None:
        I = read_inertia(inertia)  # noqa: E741 - the inertia triple
        w = read_rates(rates)
        P = read_triple(direction, "direction")
        norm = mpmath.sqrt(sum(x * x for x in P))
        if abs(norm - 1) > mpmath.mpf("1e-12"):
            raise ValueError(
                f"direction: the body components of P must have unit norm to within 1e-12, "
                f"got norm {mpmath.nstr(norm, 15)}"
            )
        P = [x / norm for x in P]
        self.motion = RegularisedRates(I, w, target_dps)
        self.inertia = I
        Lb = [I[i] * w[i] for i in range(3)]
        L, M, N = self.motion.c
        fA, fB, fC = self.motion.frak
        A, B, C = I
        self.LMN = L * M * N
        self.E = sum(x * x for x in w)
        self.F = sum(Lb[i] * w[i] for i in range(3))
        self.G = sum(x * x for x in Lb)
        self.H = L * L * A * fB * fC + M * M * B * fC * fA + N * N * C * fA * fB
        self.K = L * L * A * A * fB * fC + M * M * B * B * fC * fA + N * N * C * C * fA * fB
        self.D = sum(Lb[i] * P[i] for i in range(3))
        self.root_G = mpmath.sqrt(self.G)
        # G − 𝔇² = |L_b × P|² for a unit P: the cross product keeps the digits of a small f.
        self.f = mpmath.sqrt(sum(x * x for x in cross(Lb, P)))
        if self.f <= mpmath.mpf("1e-12") * self.root_G:
            raise ValueError(
                "direction: P is (anti)parallel to the angular momentum to within 1e-12 rad "
                "(f = √(G − 𝔇²) = 0); U and φ + 𝔉 are undefined"
            )
        v0 = sum(w[i] * P[i] for i in range(3))
        R0 = _det(P, Lb, w)
        self.U0 = mpmath.atan2(self.G * v0 - self.D * self.F, self.root_G * R0)
        s0 = mpmath.sqrt(self.K)
        self.phi0 = mpmath.atan2(
            self.F * self.f - self.D * s0 * mpmath.sin(self.U0),
            self.root_G * s0 * mpmath.cos(self.U0),
        )
        self.U = QuarterwiseIntegral(self.motion, self.dU_dtheta, "U", even=True)
        self.U_at_theta0 = self.U(self.motion.theta0)
        self._phi_branches()

    # -- the branch of φ + 𝔉 ----------------------------------------------------------------
    def _phi_branches(self) -> None:
        """Choose how φ + 𝔉 = arg z, z = √G s cos U + i(Ff − 𝔇 s sin U), is kept continuous.

        With s* = Ff/|𝔇|: where s < s*, Im z = Ff − 𝔇 s sin U > 0 and the principal atan2 is
        continuous; where s > s*, |z − iFf| ≥ |𝔇|s > Ff, so arg z is the continuous argument of
        z − iFf (closed form in U) plus a principal correction (:meth:`phi_lift`). φ + 𝔉 can
        wind only in the second case (ω circling P). s² = K − 2LMN G u is linear in sin²Θ, so s
        crosses s* at one known offset in each quarter of Θ, if at all; there the two forms are
        matched by a whole number of turns. Only cached integrals are needed: the cost does not
        depend on t beyond a sum over the crossings.
        """
        m = self.motion
        ends = [self.K - 2 * self.LMN * self.G * u for u in (m.u_lo, m.u_lo + m.delta)]
        self.s_star_sq = (self.F * self.f / self.D) ** 2 if self.D != 0 else mpmath.inf
        s0 = mpmath.sqrt(self.K)
        if max(ends) <= self.s_star_sq:
            self.phi_regime = "principal"
        elif min(ends) >= self.s_star_sq:
            self.phi_regime = "lift"
            self.lift_turns = _turns(self.phi0 - self.phi_lift(self.U0, s0))
        else:
            self.phi_regime = "mixed"
            # the offset, in the even quarters, of the crossing s = s*; π/2 minus it in the odd
            self.switch_offset = mpmath.asin(
                mpmath.sqrt((self.s_star_sq - ends[0]) / (ends[1] - ends[0]))
            )
            self.U_to_switch = self.U.partial(0, self.switch_offset)
            self.starts_lifted = self.K > self.s_star_sq
            self.start_turns = (
                _turns(self.phi0 - self.phi_lift(self.U0, s0)) if self.starts_lifted else 0
            )

    def phi_lift(self, U: mpmath.mpf, s: mpmath.mpf) -> mpmath.mpf:
        """A determination of arg z continuous in (U, s) for s > s* (see :meth:`_phi_branches`).

        z − iFf = s(a cos U + ib sin U), a = √G, b = −𝔇, has the continuous argument
        sgn(b)[U + atan2((|b| − a) sin U cos U, a cos²U + |b| sin²U)], and
        z/(z − iFf) has a positive real part.
        """
        a, b = self.root_G, -self.D
        sin_U, cos_U = mpmath.sin(U), mpmath.cos(U)
        winding = U + mpmath.atan2((abs(b) - a) * sin_U * cos_U, a * cos_U**2 + abs(b) * sin_U**2)
        Ff = self.F * self.f
        correction = mpmath.atan2(
            Ff * a * cos_U, s * (a * a * cos_U**2 + b * b * sin_U**2) + Ff * b * sin_U
        )
        return mpmath.sign(b) * winding + correction

    def phi_at(self, theta: ThetaPoint, U: mpmath.mpf, s: mpmath.mpf) -> mpmath.mpf:
        """φ + 𝔉 at Θ, continuous from its principal value at t = 0."""
        if self.phi_regime == "principal":
            return self.phi_principal(U, s)
        if self.phi_regime == "lift":
            return self.phi_lift(U, s) + 2 * mpmath.pi * self.lift_turns
        lifted, turns = self.starts_lifted, self.start_turns
        for quarter in _switch_quarters(self.motion.theta0, theta, self.switch_offset):
            U_switch = self._U_at_switch(quarter)
            s_star = mpmath.sqrt(self.s_star_sq)
            principal, lift = self.phi_principal(U_switch, s_star), self.phi_lift(U_switch, s_star)
            if lifted:
                turns = _turns(lift + 2 * mpmath.pi * turns - principal)
            else:
                turns = _turns(principal + 2 * mpmath.pi * turns - lift)
            lifted = not lifted
        value = self.phi_lift(U, s) if lifted else self.phi_principal(U, s)
        return value + 2 * mpmath.pi * turns

    def _U_at_switch(self, quarter: int) -> mpmath.mpf:
        """U where s = s* in the given quarter, from cached integrals only."""
        periods, j = divmod(quarter, 4)
        partial = self.U_to_switch if j % 2 == 0 else self.U.quarters[j] - self.U_to_switch
        inside = periods * self.U.per_period + sum(self.U.quarters[:j]) + partial
        return self.U0 + inside - self.U_at_theta0

    def s_squared(self, rates) -> mpmath.mpf:
        """K − 2LMN G u = |L_b × ω|², summed as squares."""
        I = self.inertia  # noqa: E741
        return sum(
            ((I[(i + 1) % 3] - I[(i + 2) % 3]) * rates[(i + 1) % 3] * rates[(i + 2) % 3]) ** 2
            for i in range(3)
        )

    def dU_dt(self, rates) -> mpmath.mpf:
        """√G (H − 2LMN F u)/(K − 2LMN G u) = √G (Aṗ² + Bq̇² + Cṙ²)/(A²ṗ² + B²q̇² + C²ṙ²)."""
        I = self.inertia  # noqa: E741
        c = self.motion.c
        h_term = sum(I[i] * (c[i] * rates[(i + 1) % 3] * rates[(i + 2) % 3]) ** 2 for i in range(3))
        return self.root_G * h_term / self.s_squared(rates)

    def dU_dtheta(self, s: mpmath.mpf, c: mpmath.mpf) -> mpmath.mpf:
        point = self.motion.at(s, c)
        return self.dU_dt(point.rates) * point.dt_dtheta

    def U_at(self, theta: ThetaPoint) -> mpmath.mpf:
        return self.U0 + self.U(theta) - self.U_at_theta0

    def phi_principal(self, U: mpmath.mpf, s: mpmath.mpf) -> mpmath.mpf:
        """Euler's atan2 for φ + 𝔉 (§8), principal value."""
        return mpmath.atan2(
            self.F * self.f - self.D * s * mpmath.sin(U), self.root_G * s * mpmath.cos(U)
        )


def _turns(angle: mpmath.mpf) -> int:
    """The whole number of turns nearest to ``angle``."""
    return int(mpmath.nint(angle / (2 * mpmath.pi)))


def _switch_quarters(start: ThetaPoint, end: ThetaPoint, offset: mpmath.mpf) -> list[int]:
    """Quarters whose crossing s = s* (at ``offset``, or π/2 − ``offset`` in odd quarters) lies
    strictly between ``start`` and ``end``, in the order the motion meets them."""

    def crossing(quarter: int) -> ThetaPoint:
        return ThetaPoint(quarter, offset if quarter % 2 == 0 else mpmath.pi / 2 - offset)

    def before(x: ThetaPoint, y: ThetaPoint) -> bool:
        return (x.quarter, x.offset) < (y.quarter, y.offset)

    if before(start, end):
        quarters = range(start.quarter, end.quarter + 1)
        return [q for q in quarters if before(start, crossing(q)) and before(crossing(q), end)]
    quarters = range(start.quarter, end.quarter - 1, -1)
    return [q for q in quarters if before(end, crossing(q)) and before(crossing(q), start)]


def _det(a, b, c) -> mpmath.mpf:
    return sum(a[i] * x for i, x in enumerate(cross(b, c)))


class Euler1758:
    """Euler's 1758 solution relative to a fixed direction P (see the module docstring).

    Parameters
    ----------
    inertia : sequence of three numbers
        Principal moments (A, B, C), > 0, obeying the triangle inequality. Strings are read as
        exact decimals, floats at their exact binary value.
    rates : sequence of three numbers
        Body rates (p, q, r) at t = 0, not all zero.
    direction : sequence of three numbers
        (cos l, cos m, cos n): the body components of P at t = 0. Must have unit norm to within
        1e-12; it is then normalised exactly. P must not be (anti)parallel to the angular
        momentum (to within 1e-12 rad).
    dps : int
        Decimal digits certified for every returned quantity (≥ 5).

    Raises
    ------
    ValueError
        For invalid input (the message names the parameter), a steady rotation about a
        principal axis, or a motion on the separatrix.

    Notes
    -----
    Every quantity is computed at ``dps + 12`` and ``dps + 24`` digits (:func:`certify`); a
    call that cannot reach ``dps`` digits raises :class:`PrecisionNotReached`. Whole periods of
    the motion are added from cached quarter integrals, so the cost of :meth:`at` hardly grows
    with t.
    """

    def __init__(self, inertia, rates, direction, *, dps: int = 30) -> None:
        self.dps = check_dps(dps)
        self._inputs = (inertia, rates, direction)
        self._constants: dict[int, _EulerConstants] = {}
        with mpmath.workdps(self.dps + GUARD):
            self.constants(self.dps + GUARD)  # validates the input

    def __repr__(self) -> str:
        """One line: the body, P, Euler's constants F (= 2T) and G (= |L|²), the period of
        p, q, r, the distance from the separatrix (three distinct moments only), the precision.

        Read from the constants built at construction (``dps + GUARD`` digits, far more than the
        six shown): a repr runs no quadrature and certifies nothing.
        """
        k = self.constants(self.dps + GUARD)
        with mpmath.workdps(self.dps + GUARD):
            direction = read_triple(self._inputs[2], "direction")
            period = 4 * k.motion.quarter_period
            distance = separatrix_distance(k.inertia, k.F, k.G)
        said = f"F = {shown(k.F)}, G = {shown(k.G)}, period {shown(period)}"
        if distance is not None:
            said += f", separatrix distance {shown(distance)}"
        return (
            f"<Euler1758 A, B, C = {shown(*k.inertia)}, P = ({shown(*direction)}): {said}, "
            f"dps {self.dps}>"
        )

    def constants(self, dps: int) -> _EulerConstants:
        """The constants at ``dps`` working digits (cached), built from the exact inputs."""
        if dps not in self._constants:
            # The seed precision GUESS_DPS cannot meet the final target: it gets its own.
            with mpmath.workdps(dps):
                self._constants[dps] = _EulerConstants(*self._inputs, min(self.dps, dps - 5))
        return self._constants[dps]

    def _motion(self, dps: int) -> RegularisedRates:
        return self.constants(dps).motion

    @property
    def quarter_period(self) -> mpmath.mpf:
        """T_q: the time Θ takes over any quarter [kπ/2, (k + 1)π/2]."""
        return certify(
            lambda d: {"T_q": self.constants(d).motion.quarter_period}, self.dps, guard=GUARD
        ).values["T_q"]

    @property
    def period(self) -> mpmath.mpf:
        """4 T_q: the period of (p, q, r)."""
        return certify(
            lambda d: {"T": 4 * self.constants(d).motion.quarter_period}, self.dps, guard=GUARD
        ).values["T"]

    def enclose(self, t) -> Enclosure:
        """The state at time ``t`` with *proved* bounds: the fields of :class:`EulerState` as
        ``values[name]`` and ``bounds[name]``, from Cayley's 1843 solution in Arb balls
        (:mod:`.classical_bounds`; the angles' whole turns from :meth:`at`)."""
        from .classical_bounds import euler1758_bounds

        return euler1758_bounds(self, t)

    def at(self, t) -> EulerState:
        """The state at time t (any sign), with an error estimate per quantity.

        Parameters
        ----------
        t : number
            Time (string, int, float or mpf; finite).

        Returns
        -------
        EulerState
        """

        def compute(dps: int) -> dict[str, mpmath.mpf]:
            k = self.constants(dps)
            time = to_mpf(t, "t")
            theta = theta_at_time(self._motion, time, dps)
            s, c = quarter_sin_cos(theta.quarter, theta.offset)
            point = k.motion.at(s, c)
            p, q, r = point.rates
            A, B, C = k.inertia
            L, M, N = k.motion.c
            U = k.U_at(theta)
            sin_U, cos_U = mpmath.sin(U), mpmath.cos(U)
            s_ = mpmath.sqrt(k.s_squared(point.rates))
            G, F, D, f, root_G = k.G, k.F, k.D, k.f, k.root_G
            sin_term = f * sin_U / (G * s_)
            cos_term = f * cos_U / (root_G * s_)
            return {
                "p": p,
                "q": q,
                "r": r,
                "u": point.u,
                "v": (D * F + f * s_ * sin_U) / G,
                "U": U,
                # §7, with BC(Mℭ − N𝔅) = G − AF etc.
                "cos_l": D * A * p / G + (G - A * F) * p * sin_term + L * A * q * r * cos_term,
                "cos_m": D * B * q / G + (G - B * F) * q * sin_term + M * B * r * p * cos_term,
                "cos_n": D * C * r / G + (G - C * F) * r * sin_term + N * C * p * q * cos_term,
                "phi_plus_F": k.phi_at(theta, U, s_),
            }

        with mpmath.workdps(self.dps + GUARD):
            time = to_mpf(t, "t")
        result = certify(compute, self.dps, guard=GUARD, hint="Euler 1758 solution")
        v = result.values
        return EulerState(t=time, **{name: v[name] for name in _EULER_FIELDS}, errors=result.errors)
