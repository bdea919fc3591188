"""Disturbing functions Ω of the fixed frame's Cartesian coordinates, and the scene tables.

Ω is Cayley's disturbing function (Cayley 1860; docs/orbits.md): the force function is
``V = μ/r + Ω`` and the perturbing acceleration is ``+∇Ω`` (the sign of most modern texts, minus
Laplace's R). Each term below is written as a heyoka expression of the position ``x`` in frame 0
and of time. The equations use its gradient (:func:`force`): the zonal harmonics in closed form,
one power of r² per term over a shared r², the other terms by heyoka's symbolic differentiation
(:func:`gradient`); Cayley's partial derivatives follow from it by the chain rule through the
frame tables (:mod:`.equations`).
Only the terms a scene names are built, and their numbers are runtime parameters, so two
scenes differing only in numbers share one compiled integrator.

``[perturbations.zonal]``
    ``J2``, ``J3``, … (any subset), ``radius`` R, ``axis`` k (direction of the symmetry axis,
    normalised here; default +z). ``Ω = −μ Σₙ Jₙ Rⁿ Pₙ(k̂·x/r) / rⁿ⁺¹``.
``[perturbations.third_body]``
    ``gm``, semi-major axis ``a``, mean motion ``n``, ``eccentricity`` (default 0),
    ``inclination``, ``node``, ``argument_of_pericentre`` (defaults 0) and ``mean_anomaly0``
    (mean anomaly at t = 0) or ``mean_longitude0`` (node + argument of pericentre + mean
    anomaly at t = 0; one of the two): a prescribed Keplerian orbit about the central body.
    Direct plus indirect part ``Ω = Gm₃ (1/|x − x₃| − x·x₃/|x₃|³)``, exact; with
    ``degree = N`` its Legendre expansion ``Gm₃/r₃ Σ_{l=2..N} (r/r₃)ˡ Pₗ(cos ψ)``, valid only
    for a body inside the perturber's orbit.
``[perturbations.potential]``
    ``Omega``: text over ``x``, ``y``, ``z``, ``r`` and ``t`` (see :mod:`..expressions`).
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import heyoka as hy
import mpmath

from ..core import vectors
from ..core.errors import SceneError
from ..core.expressions import parse_expression, uses_time
from ..core.model import ParTable
from ..core.precision import Number, exact_fraction, exceeds_pi, rational_mpf
from ..core.scene import check_keys, expression_text, number, vector
from ..mechanics import frames

Expr = hy.expression
_MAX_DEGREE = 40


@dataclass
class Context:
    """What a disturbing term may use: μ (a parameter), the parameter table and the values of
    the terms' parameters.

    Numbers derived from several scene numbers (``μ Jₙ Rⁿ``, a unit axis, the perturber's
    orbit axes) are computed by each term's ``values`` in mpmath with ``dps`` digits, and enter
    the equations as one parameter each: heyoka evaluates an expression of parameters alone at
    every Taylor order of every step, which made the J2 system cost 1.7× the hand-written
    one; precomputed, it also carries one rounding instead of several. ``values`` holds them
    by parameter name (the model's numbers, :mod:`.numbers`); None: each term computes its
    own from μ's value in the table.
    """

    mu: Expr
    pars: ParTable
    dps: int = 40
    values: Mapping[str, Any] | None = None

    def values_for(self, term: Any) -> Mapping[str, Any]:
        """The values of ``term``'s parameters."""
        if self.values is not None:
            return self.values
        return term.values(self.mu_value, self.dps)

    def par(self, name: str, values: Mapping[str, Any]) -> Expr:
        """The parameter ``name``, allocated on first use with its value from ``values``."""
        if name in self.pars.names:
            return hy.par[self.pars.index(name)]
        return self.pars.add(name, values[name])

    @property
    def mu_value(self) -> Number:
        return self.pars.values[self.pars.index("mu")]


def _exact(value: Number) -> mpmath.mpf:
    """A scene number as an mpmath number, at the current precision."""
    return rational_mpf(exact_fraction(value))


def _text(value: Any, dps: int) -> str:
    """A parameter's value as decimal text with ``dps`` digits."""
    return mpmath.nstr(value, dps, strip_zeros=False)


def legendre_scaled(n: int, s: Expr, r2: Expr) -> Expr:
    """``n! rⁿ Pₙ(s/r)`` as a polynomial in s and r² with integer coefficients.

    Bonnet's recurrence multiplied by k!: ``T₍ₖ₊₁₎ = (2k + 1) s Tₖ − k² r² T₍ₖ₋₁₎``. No division
    by r, and no literal such as 1/3 that a double could not hold: in a quad or multiprecision
    run every literal of the equations is a double, so the 1/n! goes into a parameter computed
    in the run's precision instead.
    """
    t_prev, t = hy.expression(1.0), s
    if n == 0:
        return t_prev
    for k in range(1, n):
        t_prev, t = t, (2 * k + 1) * s * t - k * k * r2 * t_prev
    return t


@dataclass(frozen=True)
class Zonal:
    """Zonal harmonics of an axisymmetric central body (oblateness J2 and higher)."""

    coefficients: tuple[tuple[int, Number], ...]
    radius: Number
    axis: tuple[Number, Number, Number] = (0, 0, 1)
    time_dependent = False

    @classmethod
    def parse(cls, table: Mapping[str, Any], where: str) -> Zonal:
        keys = (
            [k for k in table if re.fullmatch(r"J[1-9]\d*", k)]
            if isinstance(table, Mapping)
            else []
        )
        check_keys(table, ["radius", "axis", *keys, "J2", "J3", "J4"], where)
        coeffs = []
        for key in sorted(keys, key=lambda k: int(k[1:])):
            degree = int(key[1:])
            if not 2 <= degree <= _MAX_DEGREE:
                raise SceneError(f"{where}.{key}", f"degree must be in 2..{_MAX_DEGREE}")
            coeffs.append((degree, number(table[key], f"{where}.{key}")))
        if not coeffs:
            raise SceneError(where, "names no coefficient; give J2 (and J3, J4, … if wanted)")
        if "radius" not in table:
            raise SceneError(f"{where}.radius", "is required: the central body's radius R")
        radius = number(table["radius"], f"{where}.radius", positive=True)
        axis = vector(table.get("axis", [0, 0, 1]), f"{where}.axis", 3)
        if all(exact_fraction(c) == 0 for c in axis):
            raise SceneError(f"{where}.axis", "must be a nonzero vector (the symmetry axis)")
        return cls(tuple(coeffs), radius, axis)

    def coordinate_axis(self) -> int | None:
        """The coordinate the symmetry axis lies along (0, 1, 2), or None if oblique."""
        nonzero = [i for i, c in enumerate(self.axis) if exact_fraction(c) != 0]
        return nonzero[0] if len(nonzero) == 1 else None

    def _axial(self, x: Sequence[Expr], ctx: Context) -> Expr:
        """``s = k̂·x``; along a coordinate axis (the default +z) no parameter is compiled."""
        i = self.coordinate_axis()
        if i is not None:
            return x[i] if exact_fraction(self.axis[i]) > 0 else -x[i]
        return vectors.dot(self.unit_axis(ctx), x)

    def unit_axis(self, ctx: Context) -> list[Expr]:
        """k̂ as three parameters (``zonal.axis_unit[i]``), allocated on first use (Ω and its
        gradient share them)."""
        values = ctx.values_for(self)
        return [ctx.par(f"zonal.axis_unit[{i}]", values) for i in range(3)]

    def values(self, mu: Number, dps: int) -> dict[str, str]:
        """The parameters' values, in mpmath with ``dps`` digits: k̂ normalised (an oblique
        axis only) and ``zonal.Cn`` = −μ Jₙ Rⁿ / n!."""
        out = {}
        with mpmath.workdps(dps):
            if self.coordinate_axis() is None:
                k = [_exact(c) for c in self.axis]
                for i in range(3):
                    out[f"zonal.axis_unit[{i}]"] = _text(k[i] / mpmath.norm(k), dps)
            m, R = _exact(mu), _exact(self.radius)
            for n, J in self.coefficients:
                out[f"zonal.C{n}"] = _text(-m * _exact(J) * R**n / mpmath.factorial(n), dps)
        return out

    def omega(self, x: Sequence[Expr], ctx: Context) -> Expr:
        r2 = vectors.dot(x, x)
        s = self._axial(x, ctx)
        values = ctx.values_for(self)
        terms = []
        for n, _ in self.coefficients:
            Cn = ctx.par(f"zonal.C{n}", values)  # −μ Jₙ Rⁿ / n!
            # Cₙ (n! rⁿ Pₙ(s/r)) / r²ⁿ⁺¹, with r²ⁿ⁺¹ as a power of r² (cheap in Taylor form).
            terms.append(Cn * legendre_scaled(n, s, r2) * r2 ** (-(n + 0.5)))
        return _sum(terms)

    def gradient(
        self,
        x: Sequence[Expr],
        r2: Expr | None,
        ctx: Context,
        radius: Expr | None = None,
    ) -> Gradient:
        """∇Ω in closed form, with one power of r per term (after :meth:`omega`, whose
        parameters it uses).

        With ``Tₙ = n! rⁿ Pₙ(s/r)`` and ``Uₙ = ∂Tₙ/∂s`` at fixed r, and ``Cₙ = −μ Jₙ Rⁿ/n!``::

            ∇(Cₙ Tₙ / r²ⁿ⁺¹) = Cₙ (Uₙ k̂ / r²ⁿ⁺¹ − Wₙ x / r²ⁿ⁺³),   Wₙ = (n + 1) Tₙ + s Uₙ

        (from ``∇Ωₙ ∝ r⁻ⁿ⁻² (Pₙ′(w) k̂ − Pₙ₊₁′(w) x̂)``, w = s/r, and
        ``Pₙ₊₁′ = (n + 1) Pₙ + w Pₙ′``), with ``Uₖ₊₁ = (k + 1)((k + 1) Tₖ + s Uₖ)``: integer
        coefficients, no division, and Bonnet's recurrence for Tₖ, stable at any degree.
        heyoka's symbolic gradient of :meth:`omega` keeps three powers of r² per term and the
        derivative of r² spelt out for each coordinate (Kepler + J2: 55 entries in heyoka's
        decomposition against 40 for the system written by hand; this form, 37).

        ``x`` is the position and ``r2 = |x|²``; or, with ``radius`` r given, ``x`` is the
        unit vector x̂ (r2 unused) and the same sums are written in w = k̂·x̂ with r = 1,
        times ``Cₙ r⁻ⁿ⁻²``; then the part along x̂ is given as ∂Ω/∂r = −(n + 1) Ωₙ/r
        (``radial``, :class:`Gradient`), which needs no Wₙ. For n = 2 the product
        ``Cₙ r⁻⁴ s`` serves both parts, ``Cₙ r⁻⁴ T₂ = (Cₙ r⁻⁴ s) s − Cₙ r⁻⁴``.
        """
        s = self._axial(x, ctx)
        C = {n: hy.par[ctx.pars.index(f"zonal.C{n}")] for n, _ in self.coefficients}
        central, along, radial = [], [], []
        t_prev, t, u = None, s, None  # T₀ = 1, T₁ = s, U₁ = 1 (None: the number 1)
        for k in range(1, max(C) + 1):
            if k in C:
                if radius is None:
                    # s U₂ = 6 s²: the s·s of |x|², not a product of its own.
                    w = (k + 1) * t + (6 * (s * s) if k == 2 else s * u)
                    along.append(C[k] * u * r2 ** (-(k + 0.5)))
                    central.append(C[k] * w * r2 ** (-(k + 1.5)))
                elif k == 2:
                    scale = C[k] * radius ** (-(k + 2))
                    shared = scale * s
                    along.append(6 * shared)
                    radial.append(-3 * (3 * (shared * s) - scale))
                else:
                    scale = C[k] * radius ** (-(k + 2))
                    along.append(scale * u)
                    radial.append(scale * (-(k + 1) * t))
            # Tₖ₊₁ = (2k + 1) s Tₖ − k² r² Tₖ₋₁ and Uₖ₊₁, written so that s·s and r² are
            # the ones of |x|² (heyoka shares equal subexpressions).
            if radius is not None:  # r = 1
                below = hy.expression(1.0) if t_prev is None else k * k * t_prev
            else:
                below = r2 if t_prev is None else k * k * (r2 * t_prev)
            u = 6 * s if k == 1 else (k + 1) * ((k + 1) * t + s * u)
            t_prev, t = t, (2 * k + 1) * (s * t) - below
        axis = self.coordinate_axis()
        if axis is None:
            g = _sum(along)
            vector = [[g * c] for c in self.unit_axis(ctx)]
        else:
            sign = exact_fraction(self.axis[axis]) > 0
            g = _sum(along) if sign else -_sum(along)
            vector = [[g] if i == axis else [] for i in range(3)]
        return Gradient(central, vector, radial if radius is not None else None)


@dataclass(frozen=True)
class ThirdBody:
    """A perturbing mass on a prescribed Keplerian orbit about the central body."""

    gm: Number
    a: Number
    n: Number
    eccentricity: Number = 0
    inclination: Number = 0
    node: Number = 0
    argument_of_pericentre: Number = 0
    mean_anomaly0: Number = 0
    mean_longitude0: Number | None = None
    degree: int | None = None

    @property
    def time_dependent(self) -> bool:
        """A perturber at rest (n = 0) makes a static field, which conserves the energy."""
        return exact_fraction(self.n) != 0

    @classmethod
    def parse(cls, table: Mapping[str, Any], where: str) -> ThirdBody:
        optional = [
            "eccentricity",
            "inclination",
            "node",
            "argument_of_pericentre",
            "mean_anomaly0",
            "mean_longitude0",
            "degree",
        ]
        check_keys(table, ["gm", "a", "n", *optional], where)
        for key in ("gm", "a", "n"):
            if key not in table:
                raise SceneError(f"{where}.{key}", "is required")
        e = number(table.get("eccentricity", 0), f"{where}.eccentricity", nonneg=True)
        if exact_fraction(e) >= 1:
            raise SceneError(
                f"{where}.eccentricity", f"must be in [0, 1) for an elliptic orbit, got {e}"
            )
        inc = number(table.get("inclination", 0), f"{where}.inclination")
        if exact_fraction(inc) < 0 or exceeds_pi(inc):
            raise SceneError(f"{where}.inclination", f"must be in [0, π], got {inc}")
        if "mean_anomaly0" in table and "mean_longitude0" in table:
            raise SceneError(
                f"{where}.mean_longitude0",
                "give either mean_anomaly0 or mean_longitude0 (= node + argument_of_pericentre "
                "+ mean anomaly), not both",
            )
        longitude = table.get("mean_longitude0")
        if longitude is not None:
            longitude = number(longitude, f"{where}.mean_longitude0")
        degree = table.get("degree")
        if degree is not None and (
            isinstance(degree, bool) or not isinstance(degree, int) or not 2 <= degree <= 40
        ):
            raise SceneError(f"{where}.degree", f"must be an integer in 2..40, got {degree!r}")
        return cls(
            number(table["gm"], f"{where}.gm", positive=True),
            number(table["a"], f"{where}.a", positive=True),
            number(table["n"], f"{where}.n"),
            e,
            inc,
            number(table.get("node", 0), f"{where}.node"),
            number(table.get("argument_of_pericentre", 0), f"{where}.argument_of_pericentre"),
            number(table.get("mean_anomaly0", 0), f"{where}.mean_anomaly0"),
            longitude,
            degree,
        )

    @property
    def circular(self) -> bool:
        return exact_fraction(self.eccentricity) == 0

    @property
    def pericentre(self) -> mpmath.mpf:
        """a(1 − e) at the current mpmath precision (a float overflows past 1e308)."""
        q = exact_fraction(self.a) * (1 - exact_fraction(self.eccentricity))
        return rational_mpf(q)

    def axes(self) -> tuple[list, list]:
        """P̂ (towards the pericentre) and Q̂ (90° ahead) of the perturber's orbit, in mpmath
        at the current precision; for a circular orbit P̂ points to the node (ω is counted in
        the phase instead)."""
        node, i = _exact(self.node), _exact(self.inclination)
        rot = vectors.matmul(frames.rotation_z(node), frames.rotation_x(i))
        if not self.circular:
            rot = vectors.matmul(rot, frames.rotation_z(_exact(self.argument_of_pericentre)))
        return [row[0] for row in rot], [row[1] for row in rot]

    def normal(self, ctx: Context) -> list[Expr]:
        """Unit normal of the perturber's orbit, P̂ × Q̂, as parameters (for monitors)."""
        values = ctx.values_for(self)
        return [ctx.par(f"third_body.normal[{i}]", values) for i in range(3)]

    def mean_anomaly(self) -> mpmath.mpf:
        """M₀, from ``mean_anomaly0`` or ``mean_longitude0 − node − ω`` (current precision)."""
        if self.mean_longitude0 is None:
            return _exact(self.mean_anomaly0)
        return (
            _exact(self.mean_longitude0) - _exact(self.node) - _exact(self.argument_of_pericentre)
        )

    def values(self, mu: Number, dps: int) -> dict[str, Any]:
        """The parameters' values, in mpmath with ``dps`` digits: every product of scene
        numbers :meth:`position` and :meth:`omega` use, and the orbit normal a circular
        perturber's Jacobi monitor uses (:meth:`normal`)."""
        out: dict[str, Any] = {"third_body.n": self.n}
        with mpmath.workdps(dps):
            P, Q = self.axes()
            a, e = _exact(self.a), _exact(self.eccentricity)
            b = a * mpmath.sqrt(1 - e * e)
            M0 = self.mean_anomaly()
            for i in range(3):
                out[f"third_body.aP[{i}]"] = _text(a * P[i], dps)
            for i in range(3):
                out[f"third_body.bQ[{i}]"] = _text(b * Q[i], dps)
            if self.circular:
                w = _exact(self.argument_of_pericentre)
                out["third_body.phase0"] = _text(w + M0, dps)
            else:
                out["third_body.eccentricity"] = _text(e, dps)
                out["third_body.mean_anomaly0"] = _text(M0, dps)
                for i in range(3):
                    out[f"third_body.centre[{i}]"] = _text(-e * a * P[i], dps)
            if self.degree is None:
                out["third_body.gm"] = self.gm
            else:
                gm = _exact(self.gm)
                for k in range(2, self.degree + 1):
                    out[f"third_body.gm_over_factorial[{k}]"] = _text(gm / mpmath.factorial(k), dps)
            if self.circular:
                n = vectors.cross(P, Q)
                for i in range(3):
                    out[f"third_body.normal[{i}]"] = _text(n[i], dps)
        return out

    def position(self, ctx: Context) -> list[Expr]:
        """``x₃(t) = R₃(node) R₁(i) R₃(ω) (in-plane position)``, Kepler's equation by heyoka.

        Circular: ``a (P̂ cos λ + Q̂ sin λ)``, λ = ω + M₀ + n t. Elliptic:
        ``−e a P̂ + a P̂ cos E + a √(1 − e²) Q̂ sin E``, E − e sin E = M₀ + n t. Every product of
        scene numbers is one parameter (:meth:`values`).
        """
        values = ctx.values_for(self)
        n = ctx.par("third_body.n", values)
        aP = [ctx.par(f"third_body.aP[{i}]", values) for i in range(3)]
        bQ = [ctx.par(f"third_body.bQ[{i}]", values) for i in range(3)]
        if self.circular:
            phase = ctx.par("third_body.phase0", values) + n * hy.time
            c, s = hy.cos(phase), hy.sin(phase)
            return [aP[i] * c + bQ[i] * s for i in range(3)]
        E = hy.kepE(
            ctx.par("third_body.eccentricity", values),
            ctx.par("third_body.mean_anomaly0", values) + n * hy.time,
        )
        centre = [ctx.par(f"third_body.centre[{i}]", values) for i in range(3)]
        c, s = hy.cos(E), hy.sin(E)
        return [centre[i] + aP[i] * c + bQ[i] * s for i in range(3)]

    def omega(self, x: Sequence[Expr], ctx: Context) -> Expr:
        x3 = self.position(ctx)
        r3sq = vectors.dot(x3, x3)
        values = ctx.values_for(self)
        if self.degree is None:
            gm = ctx.par("third_body.gm", values)
            d = [x[i] - x3[i] for i in range(3)]
            direct = vectors.dot(d, d) ** -0.5
            indirect = vectors.dot(x, x3) * r3sq**-1.5
            return gm * (direct - indirect)
        # Legendre series of the direct part; l = 0 is constant in x, l = 1 cancels the
        # indirect part: Ω = Gm₃ Σ_{l≥2} rˡ Pₗ(cos ψ) / r₃ˡ⁺¹, cos ψ = x·x₃/(r r₃).
        r2 = vectors.dot(x, x)
        s = vectors.dot(x, x3) * r3sq**-0.5
        terms = []
        for k in range(2, self.degree + 1):
            ck = ctx.par(f"third_body.gm_over_factorial[{k}]", values)  # Gm₃/k!
            terms.append(ck * legendre_scaled(k, s, r2) * r3sq ** (-(k + 1) / 2))
        return _sum(terms)


@dataclass(frozen=True)
class UserPotential:
    """A disturbing function written as text over ``x, y, z, r, t`` (and ``mu``, ``pi``)."""

    text: str
    time_dependent: bool = False

    @classmethod
    def parse(cls, table: Mapping[str, Any], where: str) -> UserPotential:
        check_keys(table, ["Omega"], where)
        if "Omega" not in table:
            raise SceneError(f"{where}.Omega", "is required: Ω as text over x, y, z, r, t, mu")
        text = expression_text(table["Omega"], f"{where}.Omega")
        return cls(text, uses_time(text))

    def values(self, mu: Number, dps: int) -> dict[str, Any]:
        """None of its own: the literals of its text are the structure's (``FIELD#k``)."""
        return {}

    def omega(self, x: Sequence[Expr], ctx: Context) -> Expr:
        symbols = dict(zip("xyz", x, strict=True))
        symbols["r"] = hy.sqrt(vectors.dot(x, x))
        symbols["mu"] = ctx.mu
        return parse_expression(self.text, symbols, ctx.pars, "perturbations.potential.Omega")


PERTURBATIONS = {"zonal": Zonal, "third_body": ThirdBody, "potential": UserPotential}


def perturbation_key(term: Any) -> str:
    """The ``[perturbations.KEY]`` table of a parsed term."""
    return next(key for key, cls in PERTURBATIONS.items() if isinstance(term, cls))


def parse_perturbations(table: Mapping[str, Any]) -> tuple:
    """The ``[perturbations.*]`` tables, in a fixed order so equal scenes compile equally."""
    check_keys(table, list(PERTURBATIONS), "perturbations")
    return tuple(
        PERTURBATIONS[k].parse(table[k], f"perturbations.{k}") for k in PERTURBATIONS if k in table
    )


def disturbing_function(terms: Sequence[Any], x: Sequence[Expr], ctx: Context) -> Expr | None:
    """Ω(x, t) of the given terms, or None when there is none (pure Kepler motion)."""
    if not terms:
        return None
    return _sum(term_functions(terms, x, ctx))


def term_functions(terms: Sequence[Any], x: Sequence[Expr], ctx: Context) -> list[Expr]:
    """Each term's Ω(x, t), allocating its parameters."""
    return [term.omega(x, ctx) for term in terms]


def gradient(Omega: Expr, x: Sequence[Expr]) -> list[Expr]:
    """∇Ω with respect to the Cartesian variables ``x`` (symbolic, by heyoka)."""
    return [hy.diff(Omega, xi) for xi in x]


@dataclass
class Gradient:
    """∇Ω as the equations use it: ``−Σ central · x + Σ vector`` (x̂ for x where the
    position is given as r x̂: :func:`force`).

    The part along the position is kept apart, so that the equations add it to the Kepler
    term's ``μ/r³`` and multiply x once (Cartesian and Encke), or drop it where the position
    is perpendicular (Cayley's ∂Ω/∂ρ and Ω_β).

    Attributes
    ----------
    central
        Scalar terms whose sum multiplies −x.
    vector
        For each coordinate, the terms to add (an empty list for none).
    radial
        On the unit sphere (:func:`force` with the radius given): ∂Ω/∂r = x̂·∇Ω as terms to
        add, complete (``central`` is then empty); None otherwise.
    """

    central: list[Expr]
    vector: list[list[Expr]]
    radial: list[Expr] | None = None

    def component(self, i: int) -> Expr | None:
        """The vector part's coordinate ``i``, or None where it is zero."""
        return _sum(self.vector[i]) if self.vector[i] else None


def force(
    terms: Sequence[Any],
    omegas: Sequence[Expr],
    X: Sequence[Expr],
    x: Sequence[Expr],
    r2: Expr | None,
    ctx: Context,
    radius: Expr | None = None,
) -> Gradient:
    """∇Ω at the position ``x`` (with ``r2 = |x|²`` as the formulation writes it), or, with
    ``radius`` r given, at ``r x`` for the unit vector ``x``, with ∂Ω/∂r in ``radial``
    (:meth:`Zonal.gradient`).

    ``omegas`` are the terms' Ω on the Cartesian placeholders ``X`` (built once, for the
    monitors): a term without a closed-form gradient is differentiated by heyoka and composed
    with the position.
    """
    total = Gradient([], [[], [], []], None if radius is None else [])
    position = list(x) if radius is None else [radius * c for c in x]
    subs = None if position == list(X) else {str(a): b for a, b in zip(X, position, strict=True)}
    for term, omega in zip(terms, omegas, strict=True):
        if hasattr(term, "gradient"):
            g = term.gradient(x, r2, ctx, radius)
        else:
            parts = gradient(omega, X)
            if subs is not None:
                parts = [hy.subs(p, subs) for p in parts]
            g = Gradient([], [[p] for p in parts])
            if radius is not None:
                g.radial = [_sum([c * p for c, p in zip(x, parts, strict=True)])]
        total.central += g.central
        if total.radial is not None:
            total.radial += g.radial
        for i in range(3):
            total.vector[i] += g.vector[i]
    return total


def _sum(terms: Sequence[Expr]) -> Expr:
    return terms[0] if len(terms) == 1 else hy.sum(list(terms))
