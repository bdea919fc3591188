"""A system with one predominant mass: Hamilton's elements and energies, in numbers.

Hamilton 1835 §31–§39 (Second Essay; docs/hamilton.md, "The system with one predominant mass"). A
central mass M and bodies mᵢ:

* ξᵢ — the position of mᵢ relative to M ("heliocentric");
* x′ᵢ — the velocity of mᵢ relative to the centre of gravity ("centrobaric");
* pᵢ = mᵢ x′ᵢ — the momentum conjugate to ξᵢ when the centre of gravity is at rest (E2.).

The Hamiltonian of the relative motion (F2.), with Newton's force function f = G/r, is

    H = Σ mᵢ|x′ᵢ|²/2 + |Σ mᵢx′ᵢ|²/(2M) − G M Σ mᵢ/rᵢ − G Σᵢ<ₖ mᵢmₖ/rᵢₖ,

and Hamilton splits it (H2.) into independent binaries and their mutual disturbance,

    H₁ = Σ [mᵢ(M + mᵢ)/(2M) |x′ᵢ|² − G M mᵢ/rᵢ],   H₂ = Σᵢ<ₖ mᵢmₖ [x′ᵢ·x′ₖ/M − G/rᵢₖ].

The undisturbed motion of each binary is a Kepler orbit of ξ with parameter K = G(M + m) and
orbital velocity (1 + m/M) x′ (§8.2). Hamilton's six elements of a body (§8.3) are

==========  =======================================================  =====================
element     meaning                                                  Newtonian value
==========  =======================================================  =====================
μ  ``mu``   energy of the binary per unit mass of the body, H₁ᵢ/mᵢ    −GM/(2a)
τ  ``tau``  time of pericentre passage                               t − ℓ/n
ϖ ``varpi`` longitude of the pericentre                              Ω + ω
λ ``lam``   |ξ × x′|: twice the areal velocity, reduced by M/(M+m)   M/(M+m) √(K a(1 − e²))
χ  ``chi``  λ times the versed sine of the inclination               λ(1 − cos i)
ν  ``nu``   longitude of the node                                    Ω
==========  =======================================================  =====================

with a, e, i, Ω, ω, ℓ the classical elements of the relative Kepler orbit (parameter K,
velocity (1 + m/M) x′) and n = √(K/a³). Their brackets are the unit ones (§8.4):
{μ, τ} = {ϖ, λ} = {χ, ν} = 1 in Hamilton's velocity brackets, so (μ, mτ), (ϖ, mλ), (χ, mν)
are canonical pairs with respect to (ξ, p).

**Numbers.** As in :mod:`cayley_heyoka.mechanics.kepler`: if any input is a ``str`` or an mpmath
number, every input is converted exactly and the result is computed in mpmath at the current
``mpmath.mp.dps``; otherwise in numpy doubles, arrays broadcast elementwise.

**Singular points.** ϖ and τ are undefined for a circular orbit (e = 0), ν for an orbit in the
reference plane (i = 0 or π; ν = 0 is taken there, as for the classical node). Only bound
relative orbits (μ < 0) have these elements; invalid input raises :class:`ValueError` naming
the parameter.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import mpmath
import numpy as np

from ...core.accuracy import to_mpf
from ...core.vectors import cross, dot
from ...mechanics import kepler as el

__all__ = [
    "HamiltonElements",
    "SplitEnergy",
    "angular_momentum",
    "barycentric",
    "classical_elements",
    "classical_from_hamilton",
    "classical_state",
    "energy",
    "hamilton_elements",
    "hamilton_state",
    "heliocentric",
]

Vector = list[Any]


@dataclass(frozen=True)
class HamiltonElements:
    """Hamilton's elements of one body (§8.3); see the module's table.

    Attributes
    ----------
    mu, tau, varpi, lam, chi, nu : number or array
        μ, τ, ϖ, λ, χ, ν (``lam`` is λ: ``lambda`` is a Python keyword).
    """

    mu: Any
    tau: Any
    varpi: Any
    lam: Any
    chi: Any
    nu: Any

    def as_tuple(self) -> tuple[Any, ...]:
        """(μ, τ, ϖ, λ, χ, ν), the order of the integrated state."""
        return (self.mu, self.tau, self.varpi, self.lam, self.chi, self.nu)


@dataclass(frozen=True)
class SplitEnergy:
    """H of (F2.) and Hamilton's split H = H₁ + H₂ (H2.)."""

    H: Any
    H1: Any
    H2: Any


class _Arithmetic:
    """mpmath at the current precision when any input asks for it, else numpy doubles."""

    def __init__(self, *values: Any) -> None:
        self.mp = any(_is_multiprecision(v) for v in values)
        if self.mp:
            self.sqrt, self.atan2, self.sin, self.cos = (
                mpmath.sqrt,
                mpmath.atan2,
                mpmath.sin,
                mpmath.cos,
            )
        else:
            self.sqrt, self.atan2, self.sin, self.cos = np.sqrt, np.arctan2, np.sin, np.cos

    def number(self, value: Any, name: str) -> Any:
        if self.mp:
            return to_mpf(value, name)
        array = np.asarray(value, dtype=float)
        if not np.all(np.isfinite(array)):
            raise ValueError(f"{name}: must be finite, got {value!r}")
        return array[()]

    def vector(self, value: Any, name: str) -> Vector:
        components = list(value)
        if len(components) != 3:
            raise ValueError(f"{name}: must have 3 components, got {len(components)}")
        return [self.number(c, name) for c in components]

    def where(self, condition: Any, a: Any, b: Any) -> Any:
        if self.mp:
            return a if condition else b
        return np.where(condition, a, b)[()]

    def reduce(self, angle: Any) -> Any:
        """The angle in (−π, π]."""
        return self.atan2(self.sin(angle), self.cos(angle))


def _is_multiprecision(value: Any) -> bool:
    if isinstance(value, str) or type(value).__module__.startswith("mpmath"):
        return True
    if isinstance(value, Sequence) and not isinstance(value, str):
        return any(_is_multiprecision(v) for v in value)
    return False


def _positive(value: Any, name: str) -> None:
    if np.any(np.asarray(value <= 0)):
        raise ValueError(f"{name}: must be positive, got {value}")


def hamilton_elements(
    position: Sequence[Any],
    velocity: Sequence[Any],
    t: Any,
    mass: Any,
    central_mass: Any,
    G: Any,
) -> HamiltonElements:
    """Hamilton's elements (§8.3) of a body at time ``t`` from its state.

    The classical elements of the Kepler orbit of (ξ, (1 + m/M) x′) with parameter
    K = G(M + m) give ω and ℓ; then μ, λ, χ, ν by Hamilton's direct formulas,
    ϖ = ν + ω and τ = t − ℓ/n (the reverse of (Q2.), (186.), (V2.)).

    Parameters
    ----------
    position : sequence of 3 numbers or arrays
        ξ, relative to the central mass.
    velocity : sequence of 3 numbers or arrays
        x′, relative to the centre of gravity (centrobaric).
    t : number or array
        The epoch.
    mass, central_mass, G : number or array
        m, M > 0 and the constant of gravitation G > 0.

    Returns
    -------
    HamiltonElements
        ν and ϖ in (−π, π]; τ within half a period of t (ℓ ∈ (−π, π]).

    Raises
    ------
    ValueError
        Invalid input; ξ = 0; rectilinear motion (λ = 0); an unbound relative orbit (μ ≥ 0).
    """
    k = _Arithmetic(position, velocity, t, mass, central_mass, G)
    x, xp = k.vector(position, "position"), k.vector(velocity, "velocity")
    t, m = k.number(t, "t"), k.number(mass, "mass")
    M, G = k.number(central_mass, "central_mass"), k.number(G, "G")
    for value, name in ((m, "mass"), (M, "central_mass"), (G, "G")):
        _positive(value, name)
    ratio = 1 + m / M
    K = G * (M + m)
    r = k.sqrt(dot(x, x))
    _positive(r, "position: r = |ξ| (the body is at the central mass)")
    mu = ratio * dot(xp, xp) / 2 - G * M / r
    if np.any(np.asarray(mu >= 0)):
        raise ValueError(
            f"velocity: the relative orbit is not bound (μ = {mu} ≥ 0): Hamilton's elliptic "
            "elements do not exist"
        )
    classical = el.cartesian_to_elements(x, [ratio * c for c in xp], K)
    L = cross(x, xp)
    lam = k.sqrt(dot(L, L))
    # λ − L_z cancels for small inclinations; (L_x² + L_y²)/(λ + L_z) is the same number.
    chi = k.where(L[2] > 0, (L[0] ** 2 + L[1] ** 2) / (lam + abs(L[2])), lam - L[2])
    nu = classical.node
    n = k.sqrt(K / classical.a**3)
    return HamiltonElements(
        mu=mu,
        tau=t - classical.mean_anomaly / n,
        varpi=k.reduce(nu + classical.argument_of_pericentre),
        lam=lam,
        chi=chi,
        nu=nu,
    )


def classical_from_hamilton(
    elements: HamiltonElements, t: Any, mass: Any, central_mass: Any, G: Any
) -> el.Elements:
    """The classical elements (a, e, i, Ω, ω, ℓ at ``t``) of Hamilton's elements (§8.3, step 1).

    a = −GM/(2μ), 1 − e² = −2μλ²(M + m)/(G²M³), cos i = 1 − χ/λ, Ω = ν, ω = ϖ − ν,
    ℓ = n(t − τ) (not reduced).

    Raises
    ------
    ValueError
        μ ≥ 0, λ ≤ 0, χ outside [0, 2λ], or 1 − e² outside (0, 1].
    """
    z = elements.as_tuple()
    k = _Arithmetic(*z, t, mass, central_mass, G)
    names = ("mu", "tau", "varpi", "lam", "chi", "nu")
    mu, tau, varpi, lam, chi, nu = (k.number(v, n) for v, n in zip(z, names, strict=True))
    t, m = k.number(t, "t"), k.number(mass, "mass")
    M, G = k.number(central_mass, "central_mass"), k.number(G, "G")
    for value, name in ((m, "mass"), (M, "central_mass"), (G, "G"), (-mu, "-mu"), (lam, "lam")):
        _positive(value, name)
    if np.any(np.asarray((chi < 0) | (chi > 2 * lam))):
        raise ValueError(f"chi: must be in [0, 2 lam] (1 − cos i = chi/lam), got {chi}")
    one_minus_e2 = -2 * mu * lam * lam * (M + m) / (G * G * M**3)
    if np.any(np.asarray((one_minus_e2 <= 0) | (one_minus_e2 > 1))):
        raise ValueError(f"lam: 1 − e² = {one_minus_e2} is not in (0, 1] for this mu")
    a = -G * M / (2 * mu)
    n = k.sqrt(G * (M + m) / a**3)
    sin_i = k.sqrt(chi * (2 * lam - chi)) / lam
    return el.Elements(
        a=a,
        e=k.sqrt(1 - one_minus_e2),
        inclination=k.atan2(sin_i, 1 - chi / lam),
        node=nu,
        argument_of_pericentre=varpi - nu,
        mean_anomaly=n * (t - tau),
    )


def hamilton_state(
    elements: HamiltonElements, t: Any, mass: Any, central_mass: Any, G: Any
) -> tuple[Vector, Vector]:
    """Position ξ and centrobaric velocity x′ at ``t`` from Hamilton's elements.

    The Newtonian recipe of §8.3: the classical elements (:func:`classical_from_hamilton`),
    Kepler's equation, the perifocal state rotated by R₃(Ω)R₁(i)R₃(ω), and x′ = M/(M + m) v.
    """
    classical = classical_from_hamilton(elements, t, mass, central_mass, G)
    return classical_state(classical, mass, central_mass, G)


def classical_state(
    elements: el.Elements, mass: Any, central_mass: Any, G: Any
) -> tuple[Vector, Vector]:
    """ξ and x′ of a body whose relative orbit has the given classical elements.

    The elements are those of Hamilton's meaning (§8.3): the Kepler orbit of ξ with parameter
    K = G(M + m) and orbital velocity v = (1 + m/M) x′; so x′ = M/(M + m) v.
    """
    k = _Arithmetic(*vars(elements).values(), mass, central_mass, G)
    m, M, G = k.number(mass, "mass"), k.number(central_mass, "central_mass"), k.number(G, "G")
    for value, name in ((m, "mass"), (M, "central_mass"), (G, "G")):
        _positive(value, name)
    if k.mp:
        elements = el.Elements(**{f: to_mpf(v, f) for f, v in vars(elements).items()})
    x, v = el.elements_to_cartesian(elements, G * (M + m))
    return x, [M / (M + m) * c for c in v]


def classical_elements(
    position: Sequence[Any], velocity: Sequence[Any], mass: Any, central_mass: Any, G: Any
) -> el.Elements:
    """Classical elements of the relative orbit in Hamilton's meaning (inverse of
    :func:`classical_state`): those of (ξ, (1 + m/M) x′) with parameter G(M + m)."""
    k = _Arithmetic(position, velocity, mass, central_mass, G)
    x, xp = k.vector(position, "position"), k.vector(velocity, "velocity")
    m, M, G = k.number(mass, "mass"), k.number(central_mass, "central_mass"), k.number(G, "G")
    return el.cartesian_to_elements(x, [(1 + m / M) * c for c in xp], G * (M + m))


def energy(
    positions: Sequence[Sequence[Any]],
    velocities: Sequence[Sequence[Any]],
    masses: Sequence[Any],
    central_mass: Any,
    G: Any,
) -> SplitEnergy:
    """H (F2.) and its split H₁ + H₂ (H2.) from heliocentric ξᵢ and centrobaric x′ᵢ.

    ``positions[i]`` and ``velocities[i]`` are 3-sequences (of numbers or arrays, e.g. the
    columns of a result); ``masses[i]`` is mᵢ.
    """
    k = _Arithmetic(positions, velocities, masses, central_mass, G)
    xs = [k.vector(p, f"positions[{i}]") for i, p in enumerate(positions)]
    vs = [k.vector(v, f"velocities[{i}]") for i, v in enumerate(velocities)]
    ms = [k.number(m, f"masses[{i}]") for i, m in enumerate(masses)]
    M, G = k.number(central_mass, "central_mass"), k.number(G, "G")
    H1 = 0
    for x, v, m in zip(xs, vs, ms, strict=True):
        H1 = H1 + m * (M + m) / (2 * M) * dot(v, v) - G * M * m / k.sqrt(dot(x, x))
    H2 = 0
    for i in range(len(xs)):
        for j in range(i + 1, len(xs)):
            d = [a - b for a, b in zip(xs[i], xs[j], strict=True)]
            H2 = H2 + ms[i] * ms[j] * (dot(vs[i], vs[j]) / M - G / k.sqrt(dot(d, d)))
    return SplitEnergy(H1 + H2, H1, H2)


def angular_momentum(
    positions: Sequence[Sequence[Any]], velocities: Sequence[Sequence[Any]], masses: Sequence[Any]
) -> Vector:
    """Σ mᵢ ξᵢ × x′ᵢ = Σ ξᵢ × pᵢ: the angular momentum about the centre of gravity (at rest).

    The change (barycentric) → (ξ, centre of gravity) is a linear point transformation
    commuting with rotations, so Σ X × P keeps its form; with the centre of gravity at rest
    only Σ ξᵢ × pᵢ remains.
    """
    total: Vector = [0, 0, 0]
    for x, v, m in zip(positions, velocities, masses, strict=True):
        total = [a + m * b for a, b in zip(total, cross(list(x), list(v)), strict=True)]
    return total


def barycentric(
    positions: Sequence[Sequence[Any]],
    velocities: Sequence[Sequence[Any]],
    masses: Sequence[Any],
    central_mass: Any,
) -> tuple[list[Vector], list[Vector]]:
    """Barycentric positions and velocities of (M, m₁, …) from (ξᵢ, x′ᵢ), the centre of
    gravity at rest at the origin: X₀ = −Σ mᵢξᵢ/(M + Σm), Xᵢ = X₀ + ξᵢ, V₀ = −Σ mᵢx′ᵢ/M,
    Vᵢ = x′ᵢ."""
    total = central_mass + sum(masses)
    X0 = [-sum(m * x[j] for m, x in zip(masses, positions, strict=True)) / total for j in range(3)]
    V0 = [
        -sum(m * v[j] for m, v in zip(masses, velocities, strict=True)) / central_mass
        for j in range(3)
    ]
    X = [X0] + [[a + b for a, b in zip(X0, x, strict=True)] for x in positions]
    V = [V0] + [list(v) for v in velocities]
    return X, V


def heliocentric(
    positions: Sequence[Sequence[Any]], velocities: Sequence[Sequence[Any]], masses: Sequence[Any]
) -> tuple[list[Vector], list[Vector]]:
    """(ξᵢ, x′ᵢ) of bodies 1… from barycentric (or any inertial) positions and velocities of
    (M, m₁, …), ``masses[0]`` = M: ξᵢ = Xᵢ − X₀, x′ᵢ = Vᵢ − V_G."""
    total = sum(masses)
    VG = [sum(m * v[j] for m, v in zip(masses, velocities, strict=True)) / total for j in range(3)]
    X0 = positions[0]
    xs = [[a - b for a, b in zip(x, X0, strict=True)] for x in positions[1:]]
    vs = [[a - b for a, b in zip(v, VG, strict=True)] for v in velocities[1:]]
    return xs, vs
