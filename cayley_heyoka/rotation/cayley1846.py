"""Cayley's 1846 solution of the free rigid body in Rodrigues' parameters, in mpmath.

From Cayley (1846), "On the rotation of a solid body round a fixed point", eqs. (5)–(28); additive
constants as in docs/reference.md ("Euler 1758 and Cayley 1846"). Symbols of the memoir, used below:

* ``A, B, C`` principal moments, ``p, q, r`` body rates, ``L_b = (Ap, Bq, Cr)``.
* ``λ, μ, ν`` — the Cayley–Rodrigues parameters of the attitude, whose matrix (eq. (6)) maps
  body components to space components; ``κ = 1 + λ² + μ² + ν² = sec²(θ/2)``.
* ``a, b, c`` — space components of the angular momentum (constant), ``k² = a² + b² + c²``;
  ``h = Ap² + Bq² + Cr²`` (= 2T).
* ``Ω = λAp + μBq + νCr`` and ``υ = (k² + aAp + bBq + cCr)/2`` (eqs. (9), (12)), tied by the
  "singular equation" ``Ω² = κυ − k²`` (13).
* ``Φ = ap + bq + cr`` and ``V = det[(a, b, c), L_b, ω]`` (15); ``dυ = ½V dt`` (19).
* ``2 tan⁻¹(Ω/k)`` — Cayley's angle, smooth in t and unwrapped continuously (it passes an odd
  multiple of π whenever the rotation angle θ of the attitude passes π).

The motion: p, q, r from Euler's regularised parametrisation (:mod:`.euler1758`, §2.1);
``2 tan⁻¹(Ω/k)`` from its time form ``d/dt = k(h + Φ)/(k² + aAp + bBq + cCr)`` integrated in
Θ; λ, μ, ν from (14), ``2υρ = Ω(a + L_b) + L_b × a``, and κ from (13). Cayley's own
quadratures (27), (28) in υ are evaluated separately (:meth:`Cayley1846.quadratures_in_upsilon`)
as an independent check of t and of the increment of the angle.

With ``α = 2 tan⁻¹(Ω/k)``, (13) gives ``κ = k² sec²(α/2)/υ``; the unit quaternion
``w = √υ cos(α/2)/k``, ``(x, y, z) = [k sin(α/2)(a + L_b) + cos(α/2) L_b × a]/(2k√υ)`` has
``(x, y, z)/w = ρ`` of (14), unit norm (because ``|a + L_b|² = 4υ`` and
``|L_b × a|² = 2υ(k² − a·L_b)``) and is continuous where Ω passes through ∞.
"""

from __future__ import annotations

import bisect
from dataclasses import dataclass, field

import mpmath

from ..core.accuracy import PrecisionNotReached, certify, shown, shown_error, to_mpf
from ..core.balls import Enclosure
from ..core.inputs import check_dps, read_inertia, read_rates, read_triple
from ..core.vectors import cross, dot
from .attitude import matvec, rodrigues_to_matrix
from .euler1758 import (
    GUARD,
    GUESS_DPS,
    QuarterwiseIntegral,
    RegularisedRates,
    ThetaPoint,
    quarter_sin_cos,
    separatrix_distance,
    theta_at_time,
)

__all__ = ["Cayley1846", "Cayley1846State", "UpsilonQuadratures"]

_STATE_FIELDS = ("p", "q", "r", "upsilon", "omega_over_k", "angle", "kappa", "lambda_", "mu", "nu")
_QUATERNION = ("quaternion_w", "quaternion_x", "quaternion_y", "quaternion_z")


@dataclass(frozen=True, repr=False)
class Cayley1846State:
    """Cayley's solution at one time, in the conventions of docs/reference.md.

    Attributes
    ----------
    t, p, q, r : mpf
        Time and body rates.
    upsilon : mpf
        υ = (k² + aAp + bBq + cCr)/2.
    omega_over_k : mpf
        Ω/k = tan(angle/2) (infinite when the rotation angle θ passes π).
    angle : mpf
        2 tan⁻¹(Ω/k), continuous in t, its value at t = 0 the principal value in (−π, π).
    kappa : mpf
        κ = (Ω² + k²)/υ (eq. (13)) = 1 + λ² + μ² + ν².
    lambda_, mu, nu : mpf
        Cayley–Rodrigues parameters from eq. (14).
    quaternion : tuple of mpf
        (w, x, y, z), Hamilton's convention, (x, y, z)/w = (λ, μ, ν); continuous in t and regular
        at θ = π, with w > 0 at t = 0.
    errors : dict
        Error estimate per quantity (absolute if ``|value| ≤ 1``, else relative); the quaternion's
        components are ``quaternion_w`` … ``quaternion_z``.
    """

    t: mpmath.mpf
    p: mpmath.mpf
    q: mpmath.mpf
    r: mpmath.mpf
    upsilon: mpmath.mpf
    omega_over_k: mpmath.mpf
    angle: mpmath.mpf
    kappa: mpmath.mpf
    lambda_: mpmath.mpf
    mu: mpmath.mpf
    nu: mpmath.mpf
    quaternion: tuple[mpmath.mpf, mpmath.mpf, mpmath.mpf, mpmath.mpf]
    errors: dict[str, mpmath.mpf] = field(repr=False)

    @property
    def error(self) -> mpmath.mpf:
        """The worst error estimate of the state."""
        return max(self.errors.values())

    def __repr__(self) -> str:
        """One line: the time, the body rates, υ, Cayley's angle 2 tan⁻¹(Ω/k), the worst error
        (λ, μ, ν are left to the attributes: infinite at a half-turn, they say little here)."""
        return (
            f"<Cayley1846State t = {shown(self.t)}: p, q, r = {shown(self.p, self.q, self.r)}, "
            f"υ = {shown(self.upsilon)}, 2 tan⁻¹(Ω/k) = {shown(self.angle)}, "
            f"error {shown_error(self.error)}>"
        )

    @property
    def rodrigues(self) -> tuple[mpmath.mpf, mpmath.mpf, mpmath.mpf]:
        """(λ, μ, ν)."""
        return (self.lambda_, self.mu, self.nu)


@dataclass(frozen=True, repr=False)
class UpsilonQuadratures:
    """Cayley's quadratures (27), (28) in υ taken along the motion from 0 to t.

    Attributes
    ----------
    t : mpf
        ``2∫dυ/V`` summed over the pieces: the elapsed time recovered.
    angle_increment : mpf
        ``k∫(h + Φ)dυ/(υV)``: the increment of 2 tan⁻¹(Ω/k) over [0, t].
    turning_points : int
        Turning values of υ passed strictly inside (0, t) (or (t, 0)).
    errors : dict
        Error estimates of ``t`` and ``angle_increment``.
    """

    t: mpmath.mpf
    angle_increment: mpmath.mpf
    turning_points: int
    errors: dict[str, mpmath.mpf] = field(repr=False)

    @property
    def error(self) -> mpmath.mpf:
        return max(self.errors.values())

    def __repr__(self) -> str:
        """One line: the recovered t, the angle's increment, the turning points, the worst error."""
        return (
            f"<UpsilonQuadratures t = {shown(self.t)}, angle increment "
            f"{shown(self.angle_increment)}, {self.turning_points} turning "
            f"point{'' if self.turning_points == 1 else 's'}, "
            f"error {shown_error(self.error)}>"
        )


class _CayleyConstants:
    """Everything that depends on the inputs only, at one working precision."""

    def __init__(self, inertia, rates, rodrigues, target_dps: int) -> None:
        I = read_inertia(inertia)  # noqa: E741 - the inertia triple
        w = read_rates(rates)
        rho = read_triple(rodrigues, "rodrigues")
        self.motion = RegularisedRates(I, w, target_dps)
        self.inertia = I
        Lb = [I[i] * w[i] for i in range(3)]
        self.space_momentum = matvec(rodrigues_to_matrix(rho), Lb)  # eq. (6): (a, b, c)
        self.h = dot(Lb, w)
        self.k = mpmath.sqrt(dot(Lb, Lb))
        omega0 = dot(rho, Lb)
        self.angle0 = 2 * mpmath.atan(omega0 / self.k)
        self.angle = QuarterwiseIntegral(self.motion, self.dangle_dtheta, "angle")
        self.angle_at_theta0 = self.angle(self.motion.theta0)
        self._turning: list[mpmath.mpf] | None = None

    def momentum(self, rates) -> list[mpmath.mpf]:
        I = self.inertia  # noqa: E741
        return [I[i] * rates[i] for i in range(3)]

    def upsilon(self, Lb) -> mpmath.mpf:
        """υ = |a + L_b|²/4: the same as (k² + a·L_b)/2, as a sum of squares."""
        return sum((x + y) ** 2 for x, y in zip(self.space_momentum, Lb, strict=True)) / 4

    def dangle_dt(self, rates) -> mpmath.mpf:
        """d[2 tan⁻¹(Ω/k)]/dt = k(h + Φ)/(2υ) (Cayley 1846, eqs. (19)–(28))."""
        Phi = dot(self.space_momentum, rates)
        return self.k * (self.h + Phi) / (2 * self.upsilon(self.momentum(rates)))

    def dangle_dtheta(self, s: mpmath.mpf, c: mpmath.mpf) -> mpmath.mpf:
        point = self.motion.at(s, c)
        return self.dangle_dt(point.rates) * point.dt_dtheta

    def angle_at(self, theta: ThetaPoint) -> mpmath.mpf:
        return self.angle0 + self.angle(theta) - self.angle_at_theta0

    # -- υ as a function of Θ, for the quadratures in υ ---------------------------------------
    def upsilon_at(self, theta: mpmath.mpf) -> mpmath.mpf:
        point = self.motion.at(mpmath.sin(theta), mpmath.cos(theta))
        return self.upsilon(self.momentum(point.rates))

    def dupsilon_dtheta(self, s: mpmath.mpf, c: mpmath.mpf) -> mpmath.mpf:
        """dυ/dΘ = ½ a·d(L_b)/dΘ at sin Θ = s, cos Θ = c."""
        return dot(self.space_momentum, self.momentum(self.motion.derivative(s, c))) / 2

    def upsilon_step(self, s0: mpmath.mpf, c0: mpmath.mpf, step: mpmath.mpf):
        """υ(Θ₀ + step) − υ(Θ₀) without cancellation, and sin, cos of Θ₀ + step."""
        difference, s1, c1 = self.motion.step_from(s0, c0, step)
        return dot(self.space_momentum, self.momentum(difference)) / 2, s1, c1

    def turning_thetas(self) -> list[mpmath.mpf]:
        """The Θ in [0, 2π) where dυ/dΘ = 0 (V = 0), in increasing order (cached)."""
        if self._turning is None:
            self._turning = _turning_thetas(self)
        return self._turning

    def slow_thetas(self) -> list[mpmath.mpf]:
        """Θ in [0, 2π) where x₃² is least: the slow passages next to the separatrix."""
        slope = self.motion.c[self.motion.i3]
        if slope == 0:
            return []
        first = mpmath.mpf(0) if slope > 0 else mpmath.pi / 2
        return [first, first + mpmath.pi]


def _sample_points(slow: list[mpmath.mpf]) -> list[mpmath.mpf]:
    """Θ samples on [0, 2π]: uniform, plus geometric clusters at the slow passages."""
    two_pi = 2 * mpmath.pi
    points = [two_pi * i / 128 for i in range(129)]
    for centre in slow:
        for j in range(2, 56):
            for side in (-1, 1):
                x = centre + side * mpmath.mpf(2) ** -j
                points.append(x % two_pi)
    return sorted(set(points))


def _turning_thetas(k: _CayleyConstants) -> list[mpmath.mpf]:
    """Zeros of dυ/dΘ on one period: sign changes on a sample grid, refined by Illinois."""
    with mpmath.workdps(GUESS_DPS):
        grid = _sample_points(k.slow_thetas())

    def slope(theta: mpmath.mpf) -> mpmath.mpf:
        return k.dupsilon_dtheta(mpmath.sin(theta), mpmath.cos(theta))

    samples = [(x, slope(x)) for x in grid]
    roots = []
    for (a, fa), (b, fb) in zip(samples, samples[1:], strict=False):
        if fa == 0:
            roots.append(a)
        elif fa * fb < 0:
            roots.append(_illinois(slope, a, fa, b, fb, k.motion.target_dps))
    two_pi = 2 * mpmath.pi
    return sorted({x % two_pi for x in roots})


def _illinois(f, a, fa, b, fb, dps: int) -> mpmath.mpf:
    """A root of f in the bracket [a, b] (f(a)f(b) < 0) by the Illinois variant of regula falsi."""
    side = 0
    tiny = 8 * mpmath.eps * max(1, abs(a), abs(b))
    previous = a
    for _ in range(400):
        x = (a * fb - b * fa) / (fb - fa)
        fx = f(x)
        if fx == 0 or abs(x - previous) <= tiny or abs(b - a) <= tiny:
            return x
        previous = x
        if fx * fb > 0:
            b, fb = x, fx
            if side == -1:
                fa /= 2
            side = -1
        else:
            a, fa = x, fx
            if side == 1:
                fb /= 2
            side = 1
    raise PrecisionNotReached("turning point of υ", dps, float(abs(b - a)), "no convergence")


class Cayley1846:
    """Cayley's 1846 solution of the free rigid body (see the module docstring).

    Parameters
    ----------
    inertia : sequence of three numbers
        Principal moments (A, B, C), > 0, obeying the triangle inequality. Strings are read as
        exact decimals, floats at their exact binary value.
    rates : sequence of three numbers
        Body rates (p, q, r) at t = 0, not all zero.
    rodrigues : sequence of three numbers
        (λ, μ, ν) of the initial attitude: the body→space matrix of eq. (6) at t = 0.
    dps : int
        Decimal digits certified for every returned quantity (≥ 5).

    Attributes
    ----------
    a, b, c : mpf
        Space components of the angular momentum.
    h, k : mpf
        Twice the kinetic energy and ``|L|``.

    Raises
    ------
    ValueError
        For invalid input (the message names the parameter), a steady rotation about a
        principal axis, or a motion on the separatrix.

    Notes
    -----
    Every quantity is computed at ``dps + 12`` and ``dps + 24`` digits (:func:`certify`); a call
    that cannot reach ``dps`` digits raises :class:`PrecisionNotReached`. That happens to Ω/k and
    λ, μ, ν within about ``10**-12`` (in 2 tan⁻¹(Ω/k)) of a half-turn θ = π, where they are
    infinite; the quaternion stays regular there.
    """

    def __init__(self, inertia, rates, rodrigues, *, dps: int = 30) -> None:
        self.dps = check_dps(dps)
        self._inputs = (inertia, rates, rodrigues)
        self._constants: dict[int, _CayleyConstants] = {}
        with mpmath.workdps(self.dps + GUARD):
            self.constants(self.dps + GUARD)  # validates the input
        values = certify(self._integrals, self.dps, guard=GUARD).values
        self.a, self.b, self.c, self.h, self.k = (values[n] for n in ("a", "b", "c", "h", "k"))

    def __repr__(self) -> str:
        """One line: the body, Cayley's constants h, k and (a, b, c), the period of p, q, r, the
        distance from the separatrix (three distinct moments only), the precision.

        h, k, a, b, c are certified at construction; the inertia and the period are read from the
        constants built then (``dps + GUARD`` digits): a repr runs no quadrature.
        """
        k = self.constants(self.dps + GUARD)
        with mpmath.workdps(self.dps + GUARD):
            period = 4 * k.motion.quarter_period
            distance = separatrix_distance(k.inertia, self.h, self.k * self.k)
        said = (
            f"h = {shown(self.h)}, k = {shown(self.k)}, a, b, c = "
            f"{shown(self.a, self.b, self.c)}, period {shown(period)}"
        )
        if distance is not None:
            said += f", separatrix distance {shown(distance)}"
        return f"<Cayley1846 A, B, C = {shown(*k.inertia)}: {said}, dps {self.dps}>"

    def _integrals(self, dps: int) -> dict[str, mpmath.mpf]:
        k = self.constants(dps)
        a, b, c = k.space_momentum
        return {"a": a, "b": b, "c": c, "h": k.h, "k": k.k}

    def constants(self, dps: int) -> _CayleyConstants:
        """The constants at ``dps`` working digits (cached), built from the exact inputs."""
        if dps not in self._constants:
            # The seed precision GUESS_DPS cannot meet the final target: it gets its own.
            with mpmath.workdps(dps):
                self._constants[dps] = _CayleyConstants(*self._inputs, min(self.dps, dps - 5))
        return self._constants[dps]

    def _motion(self, dps: int) -> RegularisedRates:
        return self.constants(dps).motion

    def enclose(self, t) -> Enclosure:
        """The state at time ``t`` with *proved* bounds: the fields of :class:`Cayley1846State`
        (the quaternion as ``quaternion_w`` … ``quaternion_z``) as ``values[name]`` and
        ``bounds[name]``, from Cayley's 1843 solution in Arb balls (:mod:`.classical_bounds`;
        the angle's whole turns from :meth:`at`)."""
        from .classical_bounds import cayley1846_bounds

        return cayley1846_bounds(self, t)

    def at(self, t) -> Cayley1846State:
        """The state at time t (any sign), with an error estimate per quantity.

        Parameters
        ----------
        t : number
            Time (string, int, float or mpf; finite).

        Returns
        -------
        Cayley1846State
        """

        def compute(dps: int) -> dict[str, mpmath.mpf]:
            k = self.constants(dps)
            theta = theta_at_time(self._motion, to_mpf(t, "t"), dps)
            rates = k.motion.at(*quarter_sin_cos(theta.quarter, theta.offset)).rates
            Lb = k.momentum(rates)
            a = k.space_momentum
            upsilon = k.upsilon(Lb)
            angle = k.angle_at(theta)
            cos_half, sin_half = mpmath.cos_sin(angle / 2)
            omega_over_k = sin_half / cos_half
            Omega = k.k * omega_over_k
            a_plus_L = [x + y for x, y in zip(a, Lb, strict=True)]
            L_cross_a = cross(Lb, a)
            rho = [
                (Omega * x + y) / (2 * upsilon) for x, y in zip(a_plus_L, L_cross_a, strict=True)
            ]
            root = mpmath.sqrt(upsilon)
            vector = [
                (k.k * sin_half * x + cos_half * y) / (2 * k.k * root)
                for x, y in zip(a_plus_L, L_cross_a, strict=True)
            ]
            return {
                "p": rates[0],
                "q": rates[1],
                "r": rates[2],
                "upsilon": upsilon,
                "omega_over_k": omega_over_k,
                "angle": angle,
                "kappa": (Omega * Omega + k.k * k.k) / upsilon,
                "lambda_": rho[0],
                "mu": rho[1],
                "nu": rho[2],
                "quaternion_w": root * cos_half / k.k,
                "quaternion_x": vector[0],
                "quaternion_y": vector[1],
                "quaternion_z": vector[2],
            }

        with mpmath.workdps(self.dps + GUARD):
            time = to_mpf(t, "t")
        result = certify(compute, self.dps, guard=GUARD, hint="Cayley 1846 solution")
        v = result.values
        return Cayley1846State(
            t=time,
            **{name: v[name] for name in _STATE_FIELDS},
            quaternion=tuple(v[name] for name in _QUATERNION),
            errors=result.errors,
        )

    def quadratures_in_upsilon(self, t) -> UpsilonQuadratures:
        """Cayley's quadratures (27), (28) in υ along the motion from 0 to t.

        The path is cut at the turning values of υ (V = 0, located as the zeros of dυ/dΘ) and,
        next to the separatrix, at the slow passages where V dips without vanishing
        (Cayley 1846, the quadratures (27)–(28)). Every piece lies in a stretch between two
        consecutive turning values υᵢ, υᵢ₊₁ and is integrated in the χ of that stretch,
        υ = υᵢ + (υᵢ₊₁ − υᵢ) sin²χ, which removes the square-root singularities of both turning
        values (also for the end pieces, whose other end is υ(0) or υ(t)). At each node (18) is
        solved on the branch of the stretch: its first two equations hold identically on the
        polhode as parametrised by Θ (:mod:`.euler1758`), and the third,
        ``aAp + bBq + cCr = 2υ − k²``, is solved by Newton's method for the Θ-offset from the
        nearer turning point, the change of υ being computed without cancellation (the
        caution (1)). Whole stretches repeat every period and are integrated once.

        Parameters
        ----------
        t : number
            End time (either sign).

        Returns
        -------
        UpsilonQuadratures
            The recovered t and the increment of 2 tan⁻¹(Ω/k), to be compared with ``t`` and
            ``at(t).angle − at(0).angle``.
        """
        count: list[int] = []

        def compute(dps: int) -> dict[str, mpmath.mpf]:
            k = self.constants(dps)
            end = theta_at_time(self._motion, to_mpf(t, "t"), dps).value
            start = k.motion.theta0.value
            sign = 1 if end >= start else -1
            lo, hi = min(start, end), max(start, end)
            pieces = list(_pieces(k, lo, hi))
            count.append(sum(1 for _, _, tb, _, y in pieces if y == tb))
            total = mpmath.mpc(0)
            # A whole stretch recurs unchanged one period (2π in Θ) later.
            whole: dict[int, mpmath.mpc] = {}
            for index, ta, tb, x, y in pieces:
                if (x, y) != (ta, tb):
                    total += _stretch_integral(k, ta, tb, x, y)
                    continue
                if index not in whole:
                    whole[index] = _stretch_integral(k, ta, tb, x, y)
                total += whole[index]
            return {"t": sign * total.real, "angle_increment": sign * total.imag}

        result = certify(compute, self.dps, guard=GUARD, hint="Cayley 1846 υ-quadratures")
        return UpsilonQuadratures(
            t=result.values["t"],
            angle_increment=result.values["angle_increment"],
            turning_points=count[-1],
            errors=result.errors,
        )


def _pieces(k: _CayleyConstants, lo: mpmath.mpf, hi: mpmath.mpf):
    """Cut [lo, hi] into pieces inside the monotone stretches of υ.

    Yields ``(index, τa, τb, x, y)``: the piece [x, y] lies between the consecutive turning
    points τa < τb, and ``index`` identifies τa among the turning points of one period. Next
    to the separatrix a stretch is cut again at the slow passages, where V dips without
    vanishing (Cayley 1846, the quadratures (27)–(28)).
    """
    two_pi = 2 * mpmath.pi
    turning = k.turning_thetas()
    if not turning:
        raise ValueError("rates: υ is constant along this motion; its quadratures are empty")
    first, last = int(mpmath.floor(lo / two_pi)) - 1, int(mpmath.floor(hi / two_pi)) + 1
    lattice = [x + n * two_pi for n in range(first, last + 1) for x in turning]
    # Elsewhere a cut would only put the square-root branch point of a turning value close to
    # the end of a piece.
    slow = k.slow_thetas() if k.motion.sharp else []
    slow_lattice = sorted(x + n * two_pi for n in range(first, last + 1) for x in slow)
    for position, (ta, tb) in enumerate(zip(lattice, lattice[1:], strict=False)):
        x, y = max(ta, lo), min(tb, hi)
        if x >= y:
            continue
        cuts = [x] + [z for z in slow_lattice if x < z < y] + [y]
        for u, v in zip(cuts, cuts[1:], strict=False):
            yield position % len(turning), ta, tb, u, v


def _stretch_integral(
    k: _CayleyConstants, ta: mpmath.mpf, tb: mpmath.mpf, x: mpmath.mpf, y: mpmath.mpf
) -> mpmath.mpc:
    """∫ [2/V + i k(h + Φ)/(υV)] dυ over Θ ∈ [x, y] ⊂ [ta, tb], ta, tb turning points.

    In χ with υ = υa + (υb − υa) sin²χ the square-root branch points of both turning values are
    removed, so the integrand is analytic on the whole stretch χ ∈ [0, π/2].
    """
    sa, ca = mpmath.sin(ta), mpmath.cos(ta)
    sb, cb = mpmath.sin(tb), mpmath.cos(tb)
    ua = k.upsilon_at(ta)
    length = tb - ta
    change, _, _ = k.upsilon_step(sa, ca, length)
    if change == 0:
        raise ValueError("rates: υ is constant along this motion; its quadratures are empty")
    forward = 1 if change > 0 else -1
    half_pi = mpmath.pi / 2
    # Nodes this close to a turning value carry weights below 10⁴ε; V there is all rounding.
    skip = mpmath.eps * 10**4 * length

    def chi_of(theta: mpmath.mpf) -> mpmath.mpf:
        from_a, _, _ = k.upsilon_step(sa, ca, theta - ta)
        from_b, _, _ = k.upsilon_step(sb, cb, theta - tb)
        # max(…, 0): next to a turning value rounding may flip the sign of a tiny change.
        return mpmath.atan2(
            mpmath.sqrt(max(from_a / change, 0)), mpmath.sqrt(max(-from_b / change, 0))
        )

    chi_x = mpmath.mpf(0) if x == ta else chi_of(x)
    chi_y = half_pi if y == tb else chi_of(y)

    # Solved nodes (χ, Θ − ta), both sorted (Θ is monotone in χ): interpolating between
    # neighbours seeds Newton's method.
    chis, etas = [mpmath.mpf(0), half_pi], [mpmath.mpf(0), length]

    def integrand(chi: mpmath.mpf):
        sin_chi, cos_chi = mpmath.sin(chi), mpmath.cos(chi)
        i = bisect.bisect(chis, chi)
        left, right = max(i - 1, 0), min(i, len(chis) - 1)
        span = chis[right] - chis[left]
        eta = etas[left] + (etas[right] - etas[left]) * ((chi - chis[left]) / span if span else 0)
        if chi <= half_pi / 2:
            s0, c0, direction, offset, guess = sa, ca, 1, change * sin_chi**2, eta
        else:
            s0, c0, direction, offset, guess = sb, cb, -1, -change * cos_chi**2, length - eta
        if guess < skip:
            return 0
        eta, s, c = _solve_offset(k, s0, c0, direction, offset, guess, length)
        bisect.insort(etas, eta if direction > 0 else length - eta)
        chis.insert(bisect.bisect(chis, chi), chi)
        rates = k.motion.at(s, c).rates
        V = dot(k.space_momentum, cross(k.momentum(rates), rates))
        if V * forward <= 0:
            raise PrecisionNotReached(
                "t (υ-quadrature)", k.motion.target_dps, 1.0, "V changed sign inside a stretch"
            )
        upsilon = ua + change * sin_chi**2
        Phi = dot(k.space_momentum, rates)
        weight = change * 2 * sin_chi * cos_chi
        return mpmath.mpc(2 / V, k.k * (k.h + Phi) / (upsilon * V)) * weight

    return k.motion.quad(integrand, chi_x, chi_y, "t (υ-quadrature)")


def _solve_offset(k, s0, c0, direction, offset, guess, length):
    """η and sin, cos of Θ₀ + direction·η, η ∈ [0, length], where υ − υ(Θ₀) = offset (Newton).

    υ − υ(Θ₀) is monotone in η on the stretch; a bracket on η guards the Newton steps.
    """
    lo, hi = mpmath.mpf(0), length
    eta = guess
    tiny = 16 * mpmath.eps * length
    for _ in range(100):
        change, s, c = k.upsilon_step(s0, c0, direction * eta)
        residual = change - offset
        if (residual < 0) == (offset > 0):
            lo = eta
        else:
            hi = eta
        slope = direction * k.dupsilon_dtheta(s, c)
        new = eta - residual / slope if slope != 0 else (lo + hi) / 2
        if not lo <= new <= hi:
            new = (lo + hi) / 2
        step, eta = new - eta, new
        if abs(step) <= tiny:
            return eta, s, c  # s, c at the previous η, within 16ε of the root
    raise PrecisionNotReached(
        "t (υ-quadrature)", k.motion.target_dps, float(abs(step)), "Newton failed for Θ(υ)"
    )
