"""A system with one predominant mass as heyoka expressions: (F2.) and Hamilton's elements.

Symbols and the two formulations (Hamilton 1835, Second Essay §31–39; docs/hamilton.md; the numbers
and the table of elements are in :mod:`.system`):

* **canonical** — the state is (ξᵢ, pᵢ = mᵢx′ᵢ) and the equations are the canonical equations
  of H (F2.), taken by heyoka (:func:`canonical_system`);
* **elements** — the state is Hamilton's six elements (μ, τ, ϖ, λ, χ, ν) of every body; ξ and
  x′ are the undisturbed Kepler motion through them (:func:`state_from_elements`, with
  ``heyoka.kepE``), H₂ (H2.) is one expression of all the elements and t, and every body's
  rates come from it by heyoka's symbolic differentiation (S2.) (:func:`element_system`):

      m dμ/dt = ∂H₂/∂τ,  m dτ/dt = −∂H₂/∂μ,  m dϖ/dt = ∂H₂/∂λ,  m dλ/dt = −∂H₂/∂ϖ,
      m dχ/dt = ∂H₂/∂ν,  m dν/dt = −∂H₂/∂χ.

Every number enters through :class:`Coefficients`: each combination of G, M and the masses
that the equations need (G M mᵢ, 1/(2mᵢ), √(G(M + mᵢ)), …) is computed once from the exact
inputs and rounded once, so no product of constants is left for heyoka to evaluate (and round)
at every Taylor order.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from fractions import Fraction

import heyoka as hy
import mpmath

from ...core.model import ParTable
from ...core.precision import Number, Precision, exact_fraction, fraction_text
from ...core.vectors import dot
from ..canonical import canonical_equations

Expr = hy.expression

#: Hamilton's elements of one body, in the order of the state and of the result names.
ELEMENTS = ("mu", "tau", "varpi", "lambda", "chi", "nu")
_GUARD_DIGITS = 15


class Coefficients:
    """The constants of the system as heyoka expressions, each made on first use.

    Parameters
    ----------
    G, central_mass, masses
        G, M and m₁ … m_N (scene numbers: decimal text is read exactly).
    pars
        Where to allocate them as runtime parameters (named ``predominant_mass.<name>``);
        None makes them numeric constants of the expressions.
    precision
        The precision their values are rounded to.
    values
        Their values by parameter name (:meth:`values`, computed for the scene by
        :func:`~cayley_heyoka.hamilton.predominant_mass.numbers.numbers`), taken instead of
        computed; a coefficient missing from it is a fault (``KeyError``).

    Rational combinations are computed exactly and rounded once; the square roots are
    computed in mpmath with guard digits and rounded once.
    """

    def __init__(
        self,
        G: Number,
        central_mass: Number,
        masses: Sequence[Number],
        pars: ParTable | None = None,
        precision: Precision | None = None,
        values: Mapping[str, str] | None = None,
    ) -> None:
        self.G = exact_fraction(G)
        self.M = exact_fraction(central_mass)
        self.m = [exact_fraction(m) for m in masses]
        self.pars = pars
        self.precision = precision or Precision()
        self._given = values
        self._made: dict[str, Expr] = {}
        self._texts: dict[str, str] = {}

    @property
    def count(self) -> int:
        """Number of bodies N."""
        return len(self.m)

    def values(self, elements: bool) -> dict[str, str]:
        """The value of every coefficient the model uses, by parameter name
        (``predominant_mass.<name>``), computed without building the equations; ``elements``:
        the model of Hamilton's elements
        (:attr:`~cayley_heyoka.hamilton.formulations.Formulation.elements`).

        The lists are the equations': :func:`hamiltonian` and the velocities x′ = p/m of the
        canonical model, and for the elements also :func:`state_from_elements`,
        :func:`disturbing_function` and p = m x′ (the build refuses a model whose coefficients
        are not exactly these).
        """
        n = self.count
        pairs = [(i, k) for i in range(n) for k in range(i + 1, n)]
        self.half_inverse_central()
        for i in range(n):
            self.half_inverse_mass(i)
            self.attraction(i)
            self.inverse_mass(i)
        for i, k in pairs:
            self.mutual(i, k)
        if elements:
            self.inverse_semi_major()
            for i in range(n):
                self.root_kepler(i)
                self.eccentricity_factor(i)
                self.velocity_factor(i)
                self.mass(i)
            for i, k in pairs:
                self.indirect(i, k)
        return {f"predominant_mass.{name}": text for name, text in self._texts.items()}

    def _make(self, name: str, value: Callable[[], Fraction | mpmath.mpf]) -> Expr:
        if name not in self._made:
            text = self._text(name, value)
            if self.pars is None:
                self._made[name] = hy.expression(self.precision.number(text))
            else:
                self._made[name] = self.pars.add(f"predominant_mass.{name}", text)
        return self._made[name]

    def _text(self, name: str, value: Callable[[], Fraction | mpmath.mpf]) -> str:
        if self._given is not None:
            return self._given[f"predominant_mass.{name}"]
        prec = self.precision
        with mpmath.workdps(prec.dps + _GUARD_DIGITS):
            v = value()
            if isinstance(v, Fraction):
                text = fraction_text(v, prec)
            else:
                text = mpmath.nstr(v, prec.dps + _GUARD_DIGITS - 5, strip_zeros=False)
        self._texts[name] = text
        return text

    @staticmethod
    def _sqrt(value: Fraction) -> mpmath.mpf:
        return mpmath.sqrt(mpmath.mpf(value.numerator) / value.denominator)

    # (F2.) in (ξ, p)
    def half_inverse_mass(self, i: int) -> Expr:
        """1/(2mᵢ)."""
        return self._make(f"half_inverse_m{i + 1}", lambda: 1 / (2 * self.m[i]))

    def half_inverse_central(self) -> Expr:
        """1/(2M)."""
        return self._make("half_inverse_M", lambda: 1 / (2 * self.M))

    def attraction(self, i: int) -> Expr:
        """G M mᵢ."""
        return self._make(f"GMm{i + 1}", lambda: self.G * self.M * self.m[i])

    def mutual(self, i: int, k: int) -> Expr:
        """G mᵢ mₖ."""
        return self._make(f"Gm{i + 1}m{k + 1}", lambda: self.G * self.m[i] * self.m[k])

    def inverse_central(self) -> Expr:
        """1/M (the indirect coupling of H₂ in momenta)."""
        return self._make("inverse_M", lambda: 1 / self.M)

    def reduced_half_inverse(self, i: int) -> Expr:
        """(M + mᵢ)/(2mᵢM) (H₁ in momenta)."""
        return self._make(
            f"half_inverse_reduced{i + 1}", lambda: (self.M + self.m[i]) / (2 * self.m[i] * self.M)
        )

    def inverse_mass(self, i: int) -> Expr:
        """1/mᵢ."""
        return self._make(f"inverse_m{i + 1}", lambda: 1 / self.m[i])

    def mass(self, i: int) -> Expr:
        """mᵢ."""
        return self._make(f"m{i + 1}", lambda: self.m[i])

    # Hamilton's elements
    def indirect(self, i: int, k: int) -> Expr:
        """mᵢmₖ/M (H₂ in velocities)."""
        return self._make(f"m{i + 1}m{k + 1}_over_M", lambda: self.m[i] * self.m[k] / self.M)

    def inverse_semi_major(self) -> Expr:
        """2/(GM): 1/a = −(2/(GM)) μ."""
        return self._make("two_over_GM", lambda: 2 / (self.G * self.M))

    def eccentricity_factor(self, i: int) -> Expr:
        """2(M + mᵢ)/(G²M³): 1 − e² = −(this) μ λ²."""
        return self._make(
            f"eccentricity_factor{i + 1}",
            lambda: 2 * (self.M + self.m[i]) / (self.G**2 * self.M**3),
        )

    def root_kepler(self, i: int) -> Expr:
        """√K = √(G(M + mᵢ)): n = √K a^(−3/2)."""
        return self._make(f"root_K{i + 1}", lambda: self._sqrt(self.G * (self.M + self.m[i])))

    def velocity_factor(self, i: int) -> Expr:
        """M √(G/(M + mᵢ)) = M/(M + mᵢ) √K: x′ = (this) a^(−1/2) (perifocal rate)."""
        return self._make(
            f"velocity_factor{i + 1}",
            lambda: self.M * self._sqrt(self.G / (self.M + self.m[i])),
        )


def _difference(a: Sequence[Expr], b: Sequence[Expr]) -> list[Expr]:
    return [x - y for x, y in zip(a, b, strict=True)]


def _distance(a: Sequence[Expr], b: Sequence[Expr] | None = None) -> Expr:
    d = list(a) if b is None else _difference(a, b)
    return hy.sqrt(dot(d, d))


def hamiltonian(xi: Sequence[Sequence[Expr]], p: Sequence[Sequence[Expr]], c: Coefficients) -> Expr:
    """H of (F2.) in canonical heliocentric coordinates: ξᵢ and pᵢ = mᵢx′ᵢ (3-lists each).

    H = Σ |pᵢ|²/(2mᵢ) + |Σ pᵢ|²/(2M) − Σ G M mᵢ/rᵢ − Σᵢ<ₖ G mᵢmₖ/rᵢₖ.
    """
    n = len(xi)
    terms = [kinetic_energy(p, c)]
    terms += [-c.attraction(i) / _distance(xi[i]) for i in range(n)]
    terms += [-c.mutual(i, k) / _distance(xi[i], xi[k]) for i in range(n) for k in range(i + 1, n)]
    return hy.sum(terms)


def kinetic_energy(p: Sequence[Sequence[Expr]], c: Coefficients) -> Expr:
    """T = Σ |pᵢ|²/(2mᵢ) + |Σ pᵢ|²/(2M) (178.), the centre of gravity at rest."""
    n = len(p)
    total = [hy.sum([p[i][j] for i in range(n)]) for j in range(3)]
    terms = [c.half_inverse_mass(i) * dot(p[i], p[i]) for i in range(n)]
    terms.append(c.half_inverse_central() * dot(total, total))
    return hy.sum(terms)


def split(
    xi: Sequence[Sequence[Expr]], p: Sequence[Sequence[Expr]], c: Coefficients
) -> tuple[Expr, Expr]:
    """(H₁, H₂) of (H2.) in (ξ, p): H₁ = Σ [(M + mᵢ)/(2mᵢM)|pᵢ|² − G M mᵢ/rᵢ],
    H₂ = Σᵢ<ₖ [pᵢ·pₖ/M − G mᵢmₖ/rᵢₖ]."""
    n = len(xi)
    H1 = hy.sum(
        [
            c.reduced_half_inverse(i) * dot(p[i], p[i]) - c.attraction(i) / _distance(xi[i])
            for i in range(n)
        ]
    )
    pairs = [
        c.inverse_central() * dot(p[i], p[k]) - c.mutual(i, k) / _distance(xi[i], xi[k])
        for i in range(n)
        for k in range(i + 1, n)
    ]
    return H1, hy.sum(pairs) if pairs else hy.expression(0.0)


def canonical_system(
    xi: Sequence[Sequence[Expr]], p: Sequence[Sequence[Expr]], c: Coefficients
) -> list[tuple[Expr, Expr]]:
    """The canonical equations of (F2.): dξ/dt = ∂H/∂p, dp/dt = −∂H/∂ξ (ξ first, then p,
    body by body), differentiated by heyoka."""
    flat_xi = [v for body in xi for v in body]
    flat_p = [v for body in p for v in body]
    return canonical_equations(hamiltonian(xi, p, c), flat_xi, flat_p)


def state_from_elements(
    z: Sequence[Expr], i: int, c: Coefficients, t: Expr = hy.time
) -> tuple[list[Expr], list[Expr]]:
    """ξ and x′ of body ``i`` from its elements z = (μ, τ, ϖ, λ, χ, ν) at time ``t`` (§8.3).

    With s = 1/a = −2μ/(GM), n = √K s^(3/2), √(1 − e²) = λ √(−2μ(M + m)/(G²M³)),
    ℓ = n(t − τ) and E = kepE(e, ℓ):

        ξ = a[(cos E − e) P + √(1 − e²) sin E Q],
        x′ = M/(M + m) · n a/(1 − e cos E) · [−sin E P + √(1 − e²) cos E Q],

    P, Q the columns of R₃(ν)R₁(i)R₃(ϖ − ν) written as Hamilton's (V2.), with the versed sine
    χ/λ = 1 − cos i: P = (cos ϖ + (χ/λ) sin ν sin ω, sin ϖ − (χ/λ) cos ν sin ω, sin i sin ω),
    ω = ϖ − ν, and Q the same at ϖ + π/2, ω + π/2; sin i = √(χ(2λ − χ))/λ. No cos i is
    formed, so nothing cancels at small inclinations.
    """
    mu, tau, varpi, lam, chi, nu = z
    s = -c.inverse_semi_major() * mu
    root_s = hy.sqrt(s)
    n = c.root_kepler(i) * s * root_s
    b = lam * hy.sqrt(-c.eccentricity_factor(i) * mu)  # √(1 − e²)
    e = hy.sqrt(1.0 - b * b)
    E = hy.kepE(e, n * (t - tau))
    cE, sE = hy.cos(E), hy.sin(E)
    versed = chi / lam
    sin_i = hy.sqrt(chi * (2.0 * lam - chi)) / lam
    omega = varpi - nu
    cw, sw = hy.cos(omega), hy.sin(omega)
    cn, sn = hy.cos(nu), hy.sin(nu)
    cp, sp = hy.cos(varpi), hy.sin(varpi)
    P = [cp + versed * sn * sw, sp - versed * cn * sw, sin_i * sw]
    Q = [versed * sn * cw - sp, cp - versed * cn * cw, sin_i * cw]
    X, Y = (cE - e) / s, b * sE / s
    xi = [X * u + Y * w for u, w in zip(P, Q, strict=True)]
    k = c.velocity_factor(i) * root_s / (1.0 - e * cE)
    xprime = [k * (b * cE * w - sE * u) for u, w in zip(P, Q, strict=True)]
    return xi, xprime


def disturbing_function(
    xi: Sequence[Sequence[Expr]], xprime: Sequence[Sequence[Expr]], c: Coefficients
) -> Expr:
    """H₂ of (H2.) in velocities: Σᵢ<ₖ [(mᵢmₖ/M) x′ᵢ·x′ₖ − G mᵢmₖ/rᵢₖ] (0 for one body)."""
    n = len(xi)
    pairs = [
        c.indirect(i, k) * dot(xprime[i], xprime[k]) - c.mutual(i, k) / _distance(xi[i], xi[k])
        for i in range(n)
        for k in range(i + 1, n)
    ]
    return hy.sum(pairs) if pairs else hy.expression(0.0)


def element_system(
    z: Sequence[Sequence[Expr]], c: Coefficients, t: Expr = hy.time
) -> list[tuple[Expr, Expr]]:
    """(S2.): the rates of every body's elements from one H₂(z₁, …, z_N, t).

    ``z[i]`` are body i's six element variables (μ, τ, ϖ, λ, χ, ν). H₂ is composed with
    :func:`state_from_elements` and its gradient in all 6N elements is taken at once by
    heyoka (reverse mode, shared subexpressions); body i's rates are that gradient over mᵢ,
    paired as (μ, τ), (ϖ, λ), (χ, ν).
    """
    states = [state_from_elements(zi, i, c, t) for i, zi in enumerate(z)]
    H2 = disturbing_function([s[0] for s in states], [s[1] for s in states], c)
    flat = [v for zi in z for v in zi]
    if len(z) == 1:
        gradient = [hy.expression(0.0)] * len(flat)
    else:
        gradient = hy.diff_tensors([H2], diff_args=flat, diff_order=1).gradient
    system = []
    for i, zi in enumerate(z):
        g = dict(zip(ELEMENTS, gradient[6 * i : 6 * i + 6], strict=True))
        w = c.inverse_mass(i)
        rates = {
            "mu": w * g["tau"],
            "tau": -w * g["mu"],
            "varpi": w * g["lambda"],
            "lambda": -w * g["varpi"],
            "chi": w * g["nu"],
            "nu": -w * g["chi"],
        }
        system += [(v, rates[name]) for v, name in zip(zi, ELEMENTS, strict=True)]
    return system


def angular_momentum(xi: Sequence[Sequence[Expr]], p: Sequence[Sequence[Expr]]) -> list[Expr]:
    """Σ ξᵢ × pᵢ (conserved by (F2.): see :func:`.system.angular_momentum`)."""
    from ...core.vectors import cross

    rows = [cross(list(x), list(q)) for x, q in zip(xi, p, strict=True)]
    return [hy.sum([r[j] for r in rows]) for j in range(3)]
