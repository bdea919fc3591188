"""The free rigid body in closed form (Cayley 1843, §6–§8), in mpmath at any precision.

Symbols, as in Cayley (1843), "On the motion of rotation of a solid body" (docs/reference.md):

* ``A, B, C`` principal moments; ``p, q, r`` body rates, ``p₁, q₁, r₁`` their values at t = 0;
  ``h = Ap² + Bq² + Cr²`` (twice the energy), ``k = |L|``.
* ``φ`` — Cayley's auxiliary variable, ``φ(0) = 0``, ``dφ/dt = 2pqr`` (Euler's u = φ/2), so that
  ``p² = p₁² − a_p φ`` with ``a_p = (C − B)/A`` (and ``a_q = (A − C)/B``, ``a_r = (B − A)/C``).
* ``λ₀, μ₀, ν₀`` — the Rodrigues parameters of the body relative to the *invariable frame*
  (space z along L), its azimuth fixed by ``ν₀(0) = 0``; ``Ψ = 2 tan⁻¹ν₀`` unwrapped
  continuously, ``dΨ/dt = (h + kr)/(k + Cr)``.
* Jacobi form (§7.1): ``φ = s[e₃ + (e₂ − e₃) sn²u]``, ``u = Ωt + u₀``, parameter ``m``; the
  component of the intermediate axis is ``c_X sn u``, the other oscillating one ``σ_Y c_Y cn u``,
  the one that never vanishes ``σ_Z c_Z dn u``. (Ω here is the frequency of the Jacobi
  argument, not Cayley's 1846 Ω.)
* ``Ψ(t) = kt/C + k(Ch − k²)/(CΩD₀)[Π(n; am u|m) − Π(n; χ₀|m)] + [φ_e(t) − φ_e(0)]`` (§7.3).

Every evaluation is done twice, at two working precisions (:mod:`cayley_heyoka.core.accuracy`), and
returns its error estimate; digits lost to cancellation next to the separatrix (1 − m small) or
over long spans (Ωt large) are added to the working precision up front.

Two further routes are kept for cross-checks, both free of Jacobi functions and of Π: the
amplitude-substituted quadratures ``t(χ) = ∫dχ/(Ω√(1 − m sin²χ))`` and
``Ψ = ∫(h + kr)/(k + Cr) dt`` in the φ-form (in χ), the r-form (in r, Cayley's
``C√(AB) dr/√(…)``) and the time form (in t).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Literal

import mpmath

from ..core.accuracy import Certified, certify, shown, shown_error, to_mpf
from ..core.inputs import MAX_DPS, check_dps, read_inertia, read_rates, read_triple
from .attitude import (
    matrix_to_quaternion,
    quaternion_multiply,
    quaternion_to_rodrigues,
    rodrigues_to_quaternion,
)
from .quadratures import Constants

if TYPE_CHECKING:
    from .enclosures import FreeBodyBounds

__all__ = ["Crossing", "FreeBodyState", "FreeRigidBody", "free_rigid_body"]

AXES = ("x1", "y1", "z1")
#: The quadratures (cross-checks) place times up to 10³⁰ periods away (their cost grows fast
#: with the digits a long span needs); the Jacobi route and the proved bounds 10¹⁰⁰⁰.
QUADRATURE_SPAN_DIGITS = 31
_SINGULAR_FIELDS = ("nu0", "lambda0", "mu0")


@dataclass(frozen=True, repr=False)
class Crossing:
    """A principal axis crossing the invariable plane.

    ``direction`` is +1 when the axis's component along L becomes positive (the engine's event
    convention); ``error`` is the estimate of the time's error (absolute, or relative above 1),
    or a proved bound of it when ``proved``.
    """

    time: mpmath.mpf
    direction: int
    axis: str
    error: mpmath.mpf
    proved: bool = False

    def __repr__(self) -> str:
        """One line: the axis, the time, the direction, the error estimate or bound."""
        what = "bound" if self.proved else "error"
        return (
            f"<Crossing {self.axis} at t = {shown(self.time)}, direction {self.direction:+d}, "
            f"{what} {shown_error(self.error)}>"
        )


@dataclass(frozen=True, repr=False)
class FreeBodyState:
    """The free body at one time, in the conventions of docs/reference.md.

    Attributes
    ----------
    t, p, q, r : mpf
        Time and body rates.
    phi : mpf
        Cayley's φ (φ(0) = 0, dφ/dt = 2pqr).
    psi : mpf
        Ψ = 2 tan⁻¹ν₀, unwrapped continuously from Ψ(0) = 0.
    nu0, lambda0, mu0 : mpf
        Rodrigues parameters relative to the invariable frame (ν₀ = tan(Ψ/2): infinite when the
        body is a half-turn from the frame; use ``quaternion0`` there).
    quaternion0 : tuple of mpf
        (w, x, y, z) of the body relative to the invariable frame, continuous in t.
    quaternion : tuple of mpf
        (w, x, y, z) of the body relative to the space frame of the initial attitude.
    errors : dict
        Error estimate of each quantity (absolute if ``|value| ≤ 1``, else relative).
    """

    t: mpmath.mpf
    p: mpmath.mpf
    q: mpmath.mpf
    r: mpmath.mpf
    phi: mpmath.mpf
    psi: mpmath.mpf
    nu0: mpmath.mpf
    lambda0: mpmath.mpf
    mu0: mpmath.mpf
    quaternion0: tuple[mpmath.mpf, mpmath.mpf, mpmath.mpf, mpmath.mpf]
    quaternion: tuple[mpmath.mpf, mpmath.mpf, mpmath.mpf, mpmath.mpf]
    errors: dict[str, mpmath.mpf] = field(repr=False)

    @property
    def error(self) -> mpmath.mpf:
        """The worst error estimate of the state (body rates, φ, Ψ and the quaternions).

        λ₀, μ₀, ν₀ are left out: they are infinite at a half-turn and ill-conditioned near it,
        while the quaternions carry the same attitude regularly.
        """
        return max(v for k, v in self.errors.items() if k not in _SINGULAR_FIELDS)

    def __repr__(self) -> str:
        """One line: the time, the body rates, φ and Ψ, the worst error estimate (:attr:`error`:
        λ₀, μ₀, ν₀ would report a half-turn's infinity, not a loss of digits)."""
        return (
            f"<FreeBodyState t = {shown(self.t)}: p, q, r = {shown(*self.rates)}, "
            f"φ = {shown(self.phi)}, Ψ = {shown(self.psi)}, error {shown_error(self.error)}>"
        )

    @property
    def rates(self) -> tuple[mpmath.mpf, mpmath.mpf, mpmath.mpf]:
        return (self.p, self.q, self.r)

    @property
    def rodrigues(self) -> list[mpmath.mpf]:
        """(λ, μ, ν) of the body relative to the space frame (infinite at θ = π)."""
        return quaternion_to_rodrigues(self.quaternion)


class FreeRigidBody:
    """The torque-free rigid body in closed form, certified at ``dps`` digits.

    Parameters
    ----------
    inertia : sequence of 3 numbers
        Principal moments ``A, B, C``: finite, > 0, satisfying the triangle inequality.
        Strings are read as exact decimals at every working precision; floats at their exact
        binary value.
    rates : sequence of 3 numbers
        Body rates ``p, q, r`` at t = 0, finite, not all zero.
    attitude : sequence of 4 numbers, optional
        Unit quaternion (w, x, y, z) of the body relative to the space frame at t = 0 (norm 1
        to within 1e-12, then normalised). Default: the invariable frame with ν₀(0) = 0.
    rodrigues : sequence of 3 numbers, optional
        The initial attitude as Cayley–Rodrigues parameters instead.
    matrix : 3 rows of 3 numbers, optional
        Or as the rotation matrix (body → space; RᵀR = I to within 1e-12, det R > 0), read by
        its largest pivot. At most one of ``attitude``, ``rodrigues`` and ``matrix``; each
        enters :meth:`enclose` exactly as given.
    dps : int
        Decimal digits to certify (≥ 5).
    require_physical : bool
        Refuse moments that no rigid body has (triangle inequality). The closed form does not
        need it; ``False`` admits such test bodies (e.g. A, B, C = 1, 2, 4 in the reference
        values' separatrix cases).

    Raises
    ------
    ValueError
        On invalid input, naming the parameter and the constraint violated; also for a state
        exactly on the separatrix (aperiodic motion, not covered).

    Notes
    -----
    Exposes ``h`` (= 2T), ``k`` (= ``|L|``), ``m``, ``frequency`` (Ω of u = Ωt + u₀), ``period``
    (of p, q, r), ``psi_increment`` (of Ψ per period), ``separatrix_distance``
    (``(2T·B_mid − |L|²)/|L|²``), ``momentum_space`` ((g, g′, g″), space components of L) and
    ``kind`` ("asymmetric", "symmetric" or "steady").
    """

    def __init__(
        self,
        inertia: Sequence[object],
        rates: Sequence[object],
        *,
        attitude: Sequence[object] | None = None,
        rodrigues: Sequence[object] | None = None,
        matrix: Sequence[Sequence[object]] | None = None,
        dps: int = 30,
        require_physical: bool = True,
    ) -> None:
        self.dps = dps = check_dps(dps)
        given = {"quaternion": attitude, "rodrigues": rodrigues, "matrix": matrix}
        given = {k: v for k, v in given.items() if v is not None}
        if len(given) > 1:
            raise ValueError(
                "give at most one of attitude (quaternion), rodrigues and matrix, got "
                + ", ".join(given)
            )
        # The attitude as given, every number exact, for the proved bounds (:meth:`enclose`).
        self._attitude_spec: tuple[str, Any] | None = None
        with mpmath.workdps(dps + 20):
            read_inertia(inertia, require_physical)
            read_rates(rates)
            if rodrigues is not None:
                rho = read_triple(rodrigues, "rodrigues")
                attitude = [mpmath.nstr(x, dps + 20) for x in rodrigues_to_quaternion(rho)]
                self._attitude_spec = ("rodrigues", tuple(rodrigues))
            elif matrix is not None:
                attitude = [mpmath.nstr(x, dps + 20) for x in _read_matrix(matrix)]
                self._attitude_spec = ("matrix", tuple(tuple(row) for row in matrix))
            elif attitude is not None:
                self._attitude_spec = ("quaternion", tuple(attitude))
            if attitude is not None:
                if len(attitude) != 4:
                    raise ValueError(
                        f"attitude: expected a quaternion (w, x, y, z), got {attitude!r}"
                    )
                qa = [to_mpf(x, "attitude") for x in attitude]
                norm = mpmath.sqrt(sum(x * x for x in qa))
                if abs(norm - 1) > mpmath.mpf("1e-12"):
                    raise ValueError(
                        f"attitude: quaternion must have unit norm (to 1e-12), got {norm}"
                    )
        self._inputs = (tuple(inertia), tuple(rates), None if attitude is None else tuple(attitude))
        self._cache: dict[int, Constants] = {}
        # Digits lost to cancellation next to the separatrix come back as working precision.
        probe = self._constants(dps + 30)
        self._extra = 0
        if probe.kind == "asymmetric":
            with mpmath.workdps(dps + 30):
                gap = 1 - probe.m
                self._extra = max(0, int(mpmath.ceil(-mpmath.log10(gap)))) if gap > 0 else 0
        summary = self._certify(lambda c, _w: c.summary(), "constants")
        v = summary.values
        self.kind: str = probe.kind
        self.h, self.k, self.m = v["h"], v["k"], v["m"]
        self.frequency = v.get("frequency", mpmath.nan)
        self.period, self.psi_increment = v["period"], v["psi_increment"]
        self.separatrix_distance = v["separatrix_distance"]
        self.momentum_space = (v["g"], v["g1"], v["g2"])
        self.constant_errors = summary.errors
        # Kept for the repr only: (A, B, C) as read, in the caller's order.
        self._moments = probe.I

    def __repr__(self) -> str:
        """One line: the body, Cayley's constants h and k, the period of p, q, r, the distance
        from the separatrix (three distinct moments only) and the precision.

        Only what construction read and certified is shown: a repr evaluates nothing.
        """
        said = [f"h = {shown(self.h)}", f"k = {shown(self.k)}"]
        if mpmath.isfinite(self.period):
            said.append(f"period {shown(self.period)}")
        if len(set(self._moments)) == 3:
            said.append(f"separatrix distance {shown(self.separatrix_distance)}")
        return (
            f"<FreeRigidBody {self.kind}, A, B, C = {shown(*self._moments)}: {', '.join(said)}, "
            f"dps {self.dps}>"
        )

    # -- plumbing -------------------------------------------------------------------------------
    def _constants(self, wdps: int) -> Constants:
        if wdps not in self._cache:
            inertia, rates, attitude = self._inputs
            self._cache[wdps] = Constants(inertia, rates, attitude, wdps)
        return self._cache[wdps]

    def _certify(self, compute, what: str, extra: int = 0) -> Certified:
        def run(wdps: int):
            return compute(self._constants(wdps), wdps)

        hint = (
            f"{what} at dps={self.dps}: increase dps, or the state is too close to a "
            "singular configuration for this precision"
        )
        return certify(run, self.dps, guard=12 + self._extra + extra, hint=hint)

    def _span_digits(
        self, t: mpmath.mpf, limit: int = MAX_DPS, what: str = "the closed form"
    ) -> int:
        """Digits lost in u = Ωt + u₀ over many periods; refused beyond ``limit`` of them (a
        time 10²⁰⁰⁰⁰ periods away would be computed at 20 000 digits)."""
        if not mpmath.isfinite(self.period) or self.period == 0:
            return 0
        with mpmath.workprec(64):  # a count of digits: never mpmath's global precision's
            digits = int(mpmath.log10(1 + abs(t) / self.period)) + 1
        if digits > limit:
            raise ValueError(
                f"t: {mpmath.nstr(t, 6)} is 1e{digits - 1} periods away; {what} would need "
                f"{digits} more digits than dps to place it, beyond its limit of {limit}"
            )
        return digits

    # -- the state ------------------------------------------------------------------------------
    def at(self, t: object, *, method: Literal["jacobi", "quadrature"] = "jacobi") -> FreeBodyState:
        """The state at time ``t``.

        Parameters
        ----------
        t : number
            Time (any sign), as text, float or mpf.
        method : {"jacobi", "quadrature"}
            ``"jacobi"`` (default): Jacobi elliptic functions and Π(n; χ|m) (§7).
            ``"quadrature"``: an independent route without them — the amplitude-substituted
            quadrature t(χ) inverted by Newton's method, and Ψ by the φ-form quadrature in χ
            (asymmetric bodies only; slower, for cross-checks).
        """
        with mpmath.workdps(self.dps + 20):
            tt = to_mpf(t, "t")
        if method not in ("jacobi", "quadrature"):
            raise ValueError(f"method must be 'jacobi' or 'quadrature', got {method!r}")
        if method == "quadrature" and self.kind != "asymmetric":
            raise ValueError(
                "method='quadrature' needs three distinct moments and no steady rotation"
            )

        def compute(c: Constants, wdps: int):
            tw = to_mpf(t, "t")
            st = c.state(tw) if method == "jacobi" else c.quadrature_state(tw, wdps)
            q0 = c.invariable_quaternion(st["psi"], st["p"], st["q"], st["r"])
            q = quaternion_multiply(c.outer, q0)
            out = dict(st)
            out["nu0"] = q0[3] / q0[0] if q0[0] != 0 else mpmath.inf
            out["lambda0"] = q0[1] / q0[0] if q0[0] != 0 else mpmath.inf
            out["mu0"] = q0[2] / q0[0] if q0[0] != 0 else mpmath.inf
            out.update({f"q0{n}": x for n, x in zip("wxyz", q0, strict=True)})
            out.update({f"q{n}": x for n, x in zip("wxyz", q, strict=True)})
            return out

        span = (
            self._span_digits(tt)
            if method == "jacobi"
            else self._span_digits(tt, QUADRATURE_SPAN_DIGITS, "the quadrature route")
        )
        cert = self._certify(compute, f"state at t={mpmath.nstr(tt, 15)}", span)
        v = cert.values
        return FreeBodyState(
            t=tt,
            p=v["p"],
            q=v["q"],
            r=v["r"],
            phi=v["phi"],
            psi=v["psi"],
            nu0=v["nu0"],
            lambda0=v["lambda0"],
            mu0=v["mu0"],
            quaternion0=tuple(v[f"q0{n}"] for n in "wxyz"),
            quaternion=tuple(v[f"q{n}"] for n in "wxyz"),
            errors=cert.errors,
        )

    def enclose(self, t: object) -> FreeBodyBounds:
        """The state at ``t`` with *proved* bounds, in Arb ball arithmetic (python-flint).

        The same closed form as :meth:`at` (Jacobi's functions from theta quotients, Π and F
        from Carlson's forms), evaluated in balls that provably hold the exact values of the
        inputs as given (a decimal string is enclosed, not rounded). Returns a
        :class:`~cayley_heyoka.rotation.enclosures.FreeBodyBounds`: ``values[name]`` and
        ``bounds[name]`` for ``p, q, r, phi, psi``, the space quaternion ``qw, qx, qy, qz``
        and ``lambda, mu, nu``, each bound below ``10**-dps`` (relative above 1). It is also
        the faster route: 0.11–0.18× the time of :meth:`at` for three distinct moments
        (validation/PROVED.md).

        Raises
        ------
        PrecisionNotReached
            When no bound that tight is proved up to 16× the first working precision; the
            message names the value and the bound reached.
        """
        from .enclosures import enclose

        with mpmath.workdps(self.dps + 20):
            # An exact time difference (a Fraction) as well as a number.
            tt = (
                mpmath.mpf(t.numerator) / t.denominator
                if isinstance(t, Fraction)
                else to_mpf(t, "t")
            )
        inputs = (*self._inputs[:2], self._attitude_spec)
        return enclose(
            inputs, self.kind, self._axis(), t, self.dps, self._extra + self._span_digits(tt)
        )

    def _axis(self) -> int | None:
        return getattr(self._constants(self.dps + 20), "sym_axis", None)

    def crossing_times(
        self, axis: str, t_start: object, t_stop: object, *, proved: bool = False
    ) -> list[Crossing]:
        """Every crossing of the invariable plane by a principal axis in [t_start, t_stop].

        Parameters
        ----------
        axis : {"x1", "y1", "z1"}
            The body axis; it lies in the invariable plane when p, q or r vanishes (§8).
        t_start, t_stop : number
            The window, ``t_start <= t_stop``.

        proved : bool
            Each ``Crossing.error`` a proved bound (Arb balls, as :meth:`enclose`) instead of
            the two-precision estimate.

        Returns
        -------
        list of Crossing
            In time order. The axis of the component that never vanishes (dn) has none; in a
            steady or symmetric motion the zeros are those of the rotating components.
        """
        if axis not in AXES:
            raise ValueError(f"axis must be one of {AXES}, got {axis!r}")
        with mpmath.workdps(self.dps + 20):
            t0, t1 = to_mpf(t_start, "t_start"), to_mpf(t_stop, "t_stop")
        if t1 < t0:
            raise ValueError(f"t_stop must be >= t_start, got [{t0}, {t1}]")
        index = AXES.index(axis)
        with mpmath.workdps(self.dps + 20):
            found = self._constants(self.dps + 20).crossing_indices(index, t0, t1)
        if proved:
            from ..core.balls import scaled_bound
            from .enclosures import enclose_crossings

            times = enclose_crossings(
                (*self._inputs[:2], self._attitude_spec),
                self.kind,
                self._axis(),
                index,
                [j for j, _ in found],
                self.dps,
                self._extra + self._span_digits(t1),
            )
            # Scaled as the estimates are: relative above 1.
            crossings = [
                Crossing(time, direction, axis, scaled_bound(time, bound), proved=True)
                for (time, bound), (_, direction) in zip(times, found, strict=True)
            ]
            return sorted((x for x in crossings if t0 <= x.time <= t1), key=lambda x: x.time)
        # One certified evaluation of them all: each time keeps its own error estimate, and the
        # per-call cost (two sets of constants looked up, a message built) is paid once.
        cert = self._certify(
            lambda c, _w: {str(j): c.crossing_time(index, j) for j, _ in found},
            f"crossings of {axis}",
            self._span_digits(t1),
        )
        crossings = [
            Crossing(cert.values[str(j)], direction, axis, cert.errors[str(j)])
            for j, direction in found
        ]
        return sorted((x for x in crossings if t0 <= x.time <= t1), key=lambda x: x.time)

    def psi_by_quadrature(
        self, t: object, form: Literal["time", "phi", "r"] = "time"
    ) -> tuple[mpmath.mpf, mpmath.mpf]:
        """Ψ(t) by one of Cayley's quadratures instead of Π: a cross-check of :meth:`at`.

        ``"time"``: ∫(h + kr)/(k + Cr) dt with r(t) from the Jacobi form; ``"phi"``: the φ-form
        4 tan⁻¹ν₀ = ∫(h + kr)dφ/((k + Cr)pqr) after the amplitude substitution; ``"r"``: the
        r-form C√(AB)∫(h + kr)/(k + Cr) dr/√(…) on the arcs where r is monotone. Whole periods
        are added as the same quadrature's per-period increment. Returns (Ψ, error estimate).
        """
        if self.kind != "asymmetric":
            raise ValueError("psi_by_quadrature needs three distinct moments (no steady rotation)")
        if form not in ("time", "phi", "r"):
            raise ValueError(f"form must be 'time', 'phi' or 'r', got {form!r}")
        with mpmath.workdps(self.dps + 20):
            tt = to_mpf(t, "t")
        cert = self._certify(
            lambda c, w: {"psi": c.psi_quadrature(to_mpf(t, "t"), form, w)},
            f"Ψ by the {form}-form quadrature",
            self._span_digits(tt, QUADRATURE_SPAN_DIGITS, "the quadrature route"),
        )
        return cert.values["psi"], cert.errors["psi"]


def _read_matrix(matrix: object) -> list[mpmath.mpf]:
    """The unit quaternion (w ≥ 0) of a rotation matrix, checked: 3 × 3, RᵀR = I to within
    1e-12, det R > 0."""
    if isinstance(matrix, str) or not isinstance(matrix, Sequence) or len(matrix) != 3:
        raise ValueError(f"matrix: expected 3 rows of 3 numbers, got {matrix!r}")
    R = [read_triple(row, f"matrix[{i}]") for i, row in enumerate(matrix)]
    defect = max(
        abs(sum(R[k][i] * R[k][j] for k in range(3)) - (1 if i == j else 0))
        for i in range(3)
        for j in range(3)
    )
    if defect > mpmath.mpf("1e-12") or mpmath.det(mpmath.matrix(R)) <= 0:
        raise ValueError(
            f"matrix: not a rotation (needs RᵀR = I to within 1e-12 and det R > 0; "
            f"max |RᵀR − I| = {mpmath.nstr(defect, 3)})"
        )
    return matrix_to_quaternion(R)


def free_rigid_body(
    inertia: Sequence[object],
    rates: Sequence[object],
    t: object,
    dps: int = 30,
    *,
    attitude: Sequence[object] | None = None,
) -> FreeBodyState:
    """The free rigid body at time ``t``: the stable entry point for users and checks.

    Returns the state with ``p, q, r, phi, psi, nu0, lambda0, mu0`` (mpmath numbers) in the
    conventions of docs/reference.md (φ(0) = 0, ν₀(0) = 0, ψ = 2 tan⁻¹ν₀
    unwrapped), with error estimates in ``state.errors``; see :class:`FreeRigidBody` for the
    parameters and for repeated evaluations (which reuse the constants).
    """
    return FreeRigidBody(inertia, rates, attitude=attitude, dps=dps).at(t)
