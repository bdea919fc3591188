"""Rigorous enclosures of the free body's closed form (Cayley 1843, §7) in Arb ball arithmetic.

:mod:`.quadratures` evaluates the closed form in mpmath at one working precision, and
:mod:`.closed_form` estimates its error by the difference of two precisions. Here the same
formulas run in Arb (python-flint): every number is a ball ``[mid ± rad]`` that provably holds
the exact value, the inputs included (a decimal string is enclosed, not rounded; a float or a
quad number is exact), so each result comes with a proved bound instead of an estimate.

The Jacobi functions come from theta quotients at nome ``q = exp(−π K′/K)`` (Arb's theta
functions carry the factor π in their argument, so ``z = u/(2K)``)::

    sn u = θ₃(0) θ₁(z) / (θ₂(0) θ₄(z)),   cn u = θ₄(0) θ₂(z) / (θ₂(0) θ₄(z)),
    dn u = θ₄(0) θ₃(z) / (θ₃(0) θ₄(z)),

and Π(n; χ|m), F(χ|m), K(m) from Arb's Carlson forms. Discrete choices (which axis is the
intermediate one, the half-period index of u) are taken from the midpoints; each branch is a
valid formula wherever the ball lies, so the choice never weakens the bound. Where a sign the
formulas need cannot be proved at a precision, the precision is raised; past the limit the
bound reached is reported (:class:`~cayley_heyoka.core.accuracy.PrecisionNotReached`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import mpmath
from flint import acb, arb, ctx

from ..core.accuracy import PrecisionNotReached
from ..core.balls import Enclosure, ball, bound, exact_mid, scaled_bound
from .attitude import quaternion_multiply

__all__ = ["FreeBodyBounds", "enclose", "enclose_crossings"]

#: The state's values, in the order of :class:`FreeBodyBounds`.
FIELDS = ("p", "q", "r", "phi", "psi", "qw", "qx", "qy", "qz", "lambda", "mu", "nu")


@dataclass(frozen=True)
class FreeBodyBounds(Enclosure):
    """The free body at time ``t``, each value with a proved bound (:class:`Enclosure`).

    Fields: ``p, q, r`` (body rates), ``phi`` (Cayley's φ), ``psi`` (Ψ = 2 tan⁻¹ν₀, unwrapped),
    the unit quaternion ``qw, qx, qy, qz`` of the body in the space frame and its
    ``lambda, mu, nu`` (unbounded at a half-turn).
    """

    t: mpmath.mpf = mpmath.mpf(0)


# ---------------------------------------------------------------------------- the attitude
def attitude_quaternion(spec: tuple[str, Any]) -> list[arb]:
    """A quaternion of the attitude ``(kind, value)`` as a scene states it (any norm, w ≥ 0):
    ``("quaternion", (w, x, y, z))``, ``("rodrigues", (λ, μ, ν))`` — the quaternion
    (1, λ, μ, ν) — or ``("matrix", rows)`` by the largest pivot, as the run starts it
    (:func:`.attitude.matrix_to_quaternion`). Every number enters exactly."""
    kind, value = spec
    if kind == "rodrigues":
        return [arb(1), *(ball(x, "rodrigues") for x in value)]
    if kind == "quaternion":
        q = [ball(x, "attitude") for x in value]
    elif kind == "matrix":
        (a, b, c), (a1, b1, c1), (a2, b2, c2) = ([ball(x, "matrix") for x in row] for row in value)
        cands = [a + b1 + c2, a - b1 - c2, b1 - a - c2, c2 - a - b1]
        k = max(range(4), key=lambda i: float(cands[i].mid()))  # any positive pivot is exact
        s = 2 * (1 + cands[k]).sqrt()
        q = [
            [s / 4, (b2 - c1) / s, (c - a2) / s, (a1 - b) / s],
            [(b2 - c1) / s, s / 4, (a1 + b) / s, (c + a2) / s],
            [(c - a2) / s, (a1 + b) / s, s / 4, (c1 + b2) / s],
            [(a1 - b) / s, (c + a2) / s, (c1 + b2) / s, s / 4],
        ][k]
    else:
        raise ValueError(f"attitude: unknown kind {kind!r}")
    return [-x for x in q] if q[0].mid() < 0 else q


def _sign(x: arb, what: str) -> int:
    """The proved sign of ``x``; a ball about 0 needs more precision."""
    if x > 0:
        return 1
    if x < 0:
        return -1
    raise _Undecided(what)


class _Undecided(ArithmeticError):
    """A sign the formulas need is not proved at this precision."""


# ---------------------------------------------------------------------------- the solution
class _Solution:
    """Cayley's constants of one body in balls, and its state at a time.

    ``kind`` and ``axis`` are the closed form's discrete choices, taken from the exact inputs
    by :class:`.quadratures.Constants`: "asymmetric", "symmetric" (``axis`` the symmetry
    axis) or "steady".
    """

    def __init__(
        self,
        inertia: Sequence[object],
        rates: Sequence[object],
        attitude: tuple[str, Any] | None,
        kind: str,
        axis: int | None = None,
    ) -> None:
        I = [ball(x, "inertia") for x in inertia]  # noqa: E741 - the inertia triple
        w1 = [ball(x, "rates") for x in rates]
        self.I, self.w1, self.kind = I, w1, kind
        self.h = sum((I[i] * w1[i] * w1[i] for i in range(3)), arb(0))
        self.k = sum(((I[i] * w1[i]) ** 2 for i in range(3)), arb(0)).sqrt()
        if kind == "asymmetric":
            self._jacobi_constants()
        elif kind == "symmetric":
            assert axis is not None
            self._symmetric_constants(axis)
        self.q0_start = self.invariable_quaternion(arb(0), *w1)
        if attitude is None:
            self.outer = [arb(1), arb(0), arb(0), arb(0)]
        else:
            qa = attitude_quaternion(attitude)
            norm = sum((x * x for x in qa), arb(0)).sqrt()
            qa = [x / norm for x in qa]
            w, x, y, z = self.q0_start
            self.outer = quaternion_multiply(qa, [w, -x, -y, -z])

    # -- three distinct moments: Jacobi's functions (§7.1) ------------------------------------
    def _jacobi_constants(self) -> None:
        I, w1 = self.I, self.w1
        A, B, C = I
        a = [(C - B) / A, (A - C) / B, (B - A) / C]
        Kc = -a[0] * a[1] * a[2]
        s = _sign(Kc, "the sign of (A − B)(B − C)(C − A)")
        e = [s * w1[i] * w1[i] / a[i] for i in range(3)]
        iX, iY, iZ = sorted(range(3), key=lambda i: float(e[i].mid()))
        e3, e2, e1 = e[iX], e[iY], e[iZ]
        _sign(e1 - e2, "the distance from the separatrix")
        _sign(e2 - e3, "the order of the roots")
        self.s, self.iX, self.iY, self.iZ = s, iX, iY, iZ
        self.m = m = (e2 - e3) / (e1 - e3)
        self.Omega = (abs(Kc) * (e1 - e3)).sqrt()
        self.cX = (-s * a[iX] * (e2 - e3)).sqrt()
        self.cY = (s * a[iY] * (e2 - e3)).sqrt()
        self.cZ = (s * a[iZ] * (e1 - e3)).sqrt()
        self.sZ = _sign(w1[iZ], "the sign of the rate that never vanishes")
        self.sY = s * self.sZ
        self.e2, self.e3 = e2, e3
        mc = acb(m)
        self.K = mc.elliptic_k().real
        K1 = acb(1 - m).elliptic_k().real
        self.tau = acb(0, K1 / self.K)
        self.theta0 = [x.real for x in acb(0).modular_theta(self.tau)]
        self.chi0 = arb.atan2(w1[iX] / self.cX, self.sY * w1[iY] / self.cY)
        self.u0 = acb.elliptic_f(acb(self.chi0), mc).real
        k2, C2 = self.k * self.k, C * C
        if iX == 2:
            D0, D1 = k2, k2 - C2 * self.cX**2
        elif iY == 2:
            D0, D1 = k2 - C2 * self.cY**2, k2
        else:
            D0, D1 = k2 - C2 * self.cZ**2, k2 - C2 * self.cZ**2 * (1 - m)
        self.n = n = 1 - D1 / D0
        self.psi_coeff = self.k * (C * self.h - k2) / (C * self.Omega * D0)
        self.Pi_complete = acb.elliptic_pi(acb(n), mc).real
        self.Pi_chi0 = acb.elliptic_pi_inc(acb(n), acb(self.chi0), mc).real
        self.r_is_dn = iZ == 2
        if self.r_is_dn:
            self.winding_coeff = self.sZ * self.cZ * (k2 - C * self.h) / (self.Omega * D0)
            self.winding_chi0 = _pi_circular(n, self.chi0)

    def _jacobi(self, ur: arb) -> tuple[arb, arb, arb]:
        z = acb(ur / (2 * self.K))
        t1, t2, t3, t4 = (x.real for x in z.modular_theta(self.tau))
        _, z2, z3, z4 = self.theta0
        return z3 * t1 / (z2 * t4), z4 * t2 / (z2 * t4), z4 * t3 / (z3 * t4)

    def _jacobi_state(self, t: arb) -> tuple[list[arb], arb, arb]:
        u = self.Omega * t + self.u0
        # ur in [−K, K] (by the midpoints): cn ≥ 0 there, so atan2 gives am without a branch cut.
        j = _floor((u + self.K) / (2 * self.K))
        ur = u - 2 * j * self.K
        sn, cn, dn = self._jacobi(ur)
        sign = -1 if j % 2 else 1
        chi_r = arb.atan2(sn, cn)
        w = [arb(0)] * 3
        w[self.iX] = sign * self.cX * sn
        w[self.iY] = sign * self.sY * self.cY * cn
        w[self.iZ] = self.sZ * self.cZ * dn
        phi = self.s * (self.e2 - self.e3) * (sn * sn - self.chi0.sin() ** 2)
        Pi = acb.elliptic_pi_inc(acb(self.n), acb(chi_r), acb(self.m)).real
        Pi += 2 * j * self.Pi_complete
        psi = self.k * t / self.I[2] + self.psi_coeff * (Pi - self.Pi_chi0)
        if self.r_is_dn:
            chi = _pi_circular(self.n, chi_r) + j * arb.pi() / (1 - self.n).sqrt()
            psi += self.winding_coeff * (chi - self.winding_chi0)
        else:
            # r changes sign, so (Bq, Ap) stays in an open half-plane: the principal angle.
            A, B = self.I[0], self.I[1]
            x1, y1 = B * self.w1[1], A * self.w1[0]
            x, y = B * w[1], A * w[0]
            psi += arb.atan2(x1 * y - y1 * x, x1 * x + y1 * y)
        return w, phi, psi

    # -- two equal moments (§7.5) -------------------------------------------------------------
    def _symmetric_constants(self, i: int) -> None:
        I, w1 = self.I, self.w1
        j, l = (i + 1) % 3, (i + 2) % 3
        self.axis, self.pair = i, (j, l)
        self.omega_pair = (I[i] - I[j]) * w1[i] / I[j]
        if i == 2:
            self.psi_rate = self._steady_rate(w1)
            return
        C, k = I[2], self.k
        other = j if l == 2 else l
        r1, x1 = w1[2], w1[other]
        sign = -1 if other == j else 1
        rho = (r1 * r1 + x1 * x1).sqrt()
        self.delta = arb.atan2(sign * x1, r1)
        self.arc_a, self.arc_b = k, C * rho
        self.arc_s = ((k - C * rho) * (k + C * rho)).sqrt()

    def _symmetric_state(self, t: arb) -> tuple[list[arb], arb, arb]:
        i, (j, l) = self.axis, self.pair
        w1, om = self.w1, self.omega_pair
        c, s = (om * t).cos(), (om * t).sin()
        w = [arb(0)] * 3
        w[i] = w1[i]
        w[j] = w1[j] * c - w1[l] * s
        w[l] = w1[l] * c + w1[j] * s
        A, B, C = self.I
        # As the mpmath form: the quotient whose moments differ (C ≠ B unless A is the axis).
        if i != 0:
            phi = (w1[0] ** 2 - w[0] ** 2) / ((C - B) / A)
        else:
            phi = (w1[1] ** 2 - w[1] ** 2) / ((A - C) / B)
        if i == 2:
            return w, phi, self.psi_rate * t
        integral = (self._arc(om * t + self.delta) - self._arc(self.delta)) / om
        return w, phi, self.k * t / C + (self.h - self.k * self.k / C) * integral

    def _arc(self, theta: arb) -> arb:
        """Continuous antiderivative of 1/(a + b cos θ), a > |b|."""
        a, b, s = self.arc_a, self.arc_b, self.arc_s
        pi = arb.pi()
        jj = _floor((theta + pi) / (2 * pi))
        tr = theta - 2 * jj * pi
        half = arb.atan2((a - b).sqrt() * (tr / 2).sin(), (a + b).sqrt() * (tr / 2).cos())
        return (2 * jj * pi + 2 * half) / s

    # -- the state ------------------------------------------------------------------------------
    def _steady_rate(self, w: Sequence[arb]) -> arb:
        p, q, r = w
        A, B, _ = self.I
        return (self.h + self.k * r) / self.k_plus_Cr(r, A * p, B * q)

    def state(self, t: arb) -> dict[str, arb]:
        if self.kind == "asymmetric":
            w, phi, psi = self._jacobi_state(t)
        elif self.kind == "symmetric":
            w, phi, psi = self._symmetric_state(t)
        else:
            w, phi, psi = list(self.w1), arb(0), self._steady_rate(self.w1) * t
        q0 = self.invariable_quaternion(psi, *w)
        q = quaternion_multiply(self.outer, q0)
        out = dict(zip("pqr", w, strict=True))
        out.update(phi=phi, psi=psi)
        out.update(zip(("qw", "qx", "qy", "qz"), q, strict=True))
        # λ = x/w: a ball of w about 0 (a half-turn) gives an unbounded λ, reported as such.
        out.update(zip(("lambda", "mu", "nu"), (c / q[0] for c in q[1:]), strict=True))
        return out

    def crossing_time(self, index: int, j: int) -> arb:
        """The time of the crossing :meth:`.quadratures.Constants.crossing_time` numbers ``j``."""
        if self.kind == "asymmetric":
            u = (2 * j if index == self.iX else 2 * j + 1) * self.K
            return (u - self.u0) / self.Omega
        a, b = self.pair
        w1 = self.w1
        # δ with w_index = ρ cos(ωt + δ), as Constants._pair_phase.
        phase = arb.atan2(w1[b], w1[a]) if index == a else arb.atan2(-w1[a], w1[b])
        return (arb.pi() / 2 + j * arb.pi() - phase) / self.omega_pair

    def k_plus_Cr(self, r: arb, Ap: arb, Bq: arb) -> arb:
        # Both forms are exact; the midpoint picks the one without cancellation.
        if r.mid() >= 0:
            return self.k + self.I[2] * r
        return (Ap * Ap + Bq * Bq) / (self.k - self.I[2] * r)

    def invariable_quaternion(self, psi: arb, p: arb, q: arb, r: arb) -> list[arb]:
        """§7.4: the body in the invariable frame, as :class:`.quadratures.Constants` has it."""
        A, B, _ = self.I
        Ap, Bq = A * p, B * q
        kc = self.k_plus_Cr(r, Ap, Bq)
        c, s = (psi / 2).cos(), (psi / 2).sin()
        f = (kc / (2 * self.k)).sqrt()
        g = (2 * self.k * kc).sqrt()
        return [c * f, (s * Ap + c * Bq) / g, (s * Bq - c * Ap) / g, s * f]


def _at_a_half_turn(values: dict[str, mpmath.mpf], bounds: dict[str, mpmath.mpf]) -> None:
    """λ, μ, ν where the ball of w holds 0 (a half-turn, or next to one): Arb's quotient is
    unbounded; the values are the midpoints' quotient (±∞ where w is exactly 0, as the mpmath
    route gives), their bounds infinite."""
    w = values["qw"]
    for name, c in (("lambda", "qx"), ("mu", "qy"), ("nu", "qz")):
        if not mpmath.isfinite(values[name]) or not mpmath.isfinite(bounds[name]):
            # The quotient to the midpoints' own bits (they are exact binary numbers).
            with mpmath.workprec(max(256, values[c]._mpf_[3] + w._mpf_[3])):
                values[name] = values[c] / w if w != 0 else mpmath.inf
            bounds[name] = mpmath.inf


def _floor(x: arb) -> int:
    """⌊midpoint⌋: a branch index (any index is exact; the midpoint's keeps the ball small)."""
    return int(mpmath.floor(exact_mid(x)))


def _pi_circular(n: arb, chi: arb) -> arb:
    """Π(n; χ | 0) = arctan(√(1 − n) tan χ)/√(1 − n) for |χ| ≤ π/2."""
    root = (1 - n).sqrt()
    return arb.atan2(root * chi.sin(), chi.cos()) / root


#: Working precision grows by this factor per attempt, up to ``MAX_GROWTH`` × the first.
GROWTH, MAX_GROWTH = 2, 16
#: The values whose digits are asked for; λ, μ, ν are derived (unbounded at a half-turn).
TARGETS = FIELDS[:9]


def _attempts(dps: int, extra_digits: int) -> list[int]:
    first = int((dps + extra_digits) * 3.33) + 64
    bits, out = first, []
    while bits <= MAX_GROWTH * first:
        out.append(bits)
        bits *= GROWTH
    return out


def enclose(
    inputs: tuple[Sequence[object], Sequence[object], tuple[str, Any] | None],
    kind: str,
    axis: int | None,
    t: object,
    dps: int,
    extra_digits: int = 0,
) -> FreeBodyBounds:
    """The state at ``t`` with every bound below ``10**-dps`` (scaled), or
    :class:`~cayley_heyoka.core.accuracy.PrecisionNotReached` naming what was reached.

    ``inputs`` are ``(inertia, rates, attitude)`` as :class:`.closed_form.FreeRigidBody`
    read and checked them, the attitude as :func:`attitude_quaternion` takes it; ``kind`` and
    ``axis`` its discrete choices; ``extra_digits`` the digits the first attempt adds for the
    span (u = Ωt + u₀ loses log₁₀(t/period) of them).
    """
    last: tuple[str, float] = ("the constants", math.inf)
    for bits in _attempts(dps, extra_digits):
        with ctx.workprec(bits):
            try:
                state = _Solution(*inputs, kind, axis).state(ball(t, "t"))
            except _Undecided as undecided:
                last = (str(undecided), math.inf)
                continue
            values = {name: exact_mid(state[name]) for name in FIELDS}
            bounds = {name: bound(state[name]) for name in FIELDS}
            _at_a_half_turn(values, bounds)
            tt = exact_mid(ball(t, "t"))
        worst = max(TARGETS, key=lambda n: scaled_bound(values[n], bounds[n]))
        reached = scaled_bound(values[worst], bounds[worst])
        if reached <= mpmath.mpf(10) ** -dps:
            return FreeBodyBounds(values, bounds, bits, tt)
        last = (worst, float(reached))
    raise PrecisionNotReached(last[0], dps, last[1], "no tighter bound was proved")


def enclose_crossings(
    inputs: tuple[Sequence[object], Sequence[object], tuple[str, Any] | None],
    kind: str,
    axis: int | None,
    index: int,
    numbers: Sequence[int],
    dps: int,
    extra_digits: int = 0,
) -> list[tuple[mpmath.mpf, mpmath.mpf]]:
    """The times (midpoint, proved bound) of the crossings ``numbers`` of body axis ``index``
    (numbered as :meth:`.quadratures.Constants.crossing_indices` numbers them)."""
    last: tuple[str, float] = ("the constants", math.inf)
    for bits in _attempts(dps, extra_digits):
        with ctx.workprec(bits):
            try:
                solution = _Solution(*inputs, kind, axis)
            except _Undecided as undecided:
                last = (str(undecided), math.inf)
                continue
            times = [solution.crossing_time(index, j) for j in numbers]
            out = [(exact_mid(x), bound(x)) for x in times]
        scaled = [scaled_bound(v, b) for v, b in out]
        if not scaled or max(scaled) <= mpmath.mpf(10) ** -dps:
            return out
        last = ("a crossing time", float(max(scaled)))
    raise PrecisionNotReached(last[0], dps, last[1], "no tighter bound was proved")
