"""Osculating orbits three ways: Cartesian, Cayley's variables, classical elements.

A body moves about a central mass with gravitational parameter ``μ`` (``mu``). Its osculating
orbit — the Kepler orbit through its inertial position and velocity — is described here by

1. **Cartesian** position ``x`` and velocity ``v`` in the fixed frame 0;
2. **Cayley's state** ``(r, ṙ, ρ, h, Θ, Σ, Φ)`` (Cayley 1860, "A supplementary memoir on the
   problem of disturbed elliptic motion"; docs/orbits.md, "Conventions"): radius ``r`` and
   radial velocity ``ṙ``; departure ``ρ`` of the body (angle in the orbit plane from the
   departure point ``x₂``); angular momentum per unit mass ``h = r²ρ̇ = |x × v|``; node
   longitude ``Θ``, node departure ``Σ`` and inclination ``Φ`` of the orbit plane (frame 2)
   relative to the reference plane (frame 1). ``u = ρ − Σ`` is the argument of latitude;
3. **classical elements** ``(a, e, i, Ω, ω, M)`` referred to frame 1 (docs/orbits.md,
   "Converting states"): semi-major axis, eccentricity, inclination ``i = Φ``, longitude of the
   ascending node ``Ω = Θ``, argument of pericentre ``ω`` (with ``u = ω + f``, ``f`` the true
   anomaly) and mean anomaly ``M``.

Frame 1 is placed in frame 0 by ``frame = (θ′, σ′, φ′)`` — node longitude, node departure and
inclination, in that order, as in :func:`~cayley_heyoka.mechanics.frames.plane_matrix` —
evaluated at the epoch of the state; the default ``(0, 0, 0)`` makes frame 1 the fixed frame.
The osculating ellipse is defined by the *inertial* velocity; frame 1 only supplies the axes
the angles are measured on (no frame-rotation term is subtracted).

**The gauge Σ.** Only ``u = ρ − Σ`` is a function of the instantaneous state; ``Σ`` at the epoch
is chosen freely (argument ``sigma``, default 0: the departure point at the ascending node), and
``ρ = u + Σ``. At later epochs ``Σ`` comes from the integration, not from these functions.

**Numbers.** Every function accepts either

* mpmath numbers: if any input is an ``mpf`` or a ``str``, all inputs are converted exactly
  (decimal text at the current precision, floats and integers at their exact binary value) and
  the result is computed at the current ``mpmath.mp.dps``; or
* Python floats or numpy float arrays: double precision, inputs broadcast elementwise (a vector
  is a length-3 sequence whose components may be arrays).

**Conventions at the singular points.**

* ``Φ ∈ [0, π]`` from ``atan2(√(n₁² + n₂²), n₃)``, ``n̂ = H/|H|`` the orbit normal in frame 1;
  ``Θ = atan2(n₁, −n₂)``. When the plane coincides with the reference plane (``n₁ = n₂ = 0``,
  ``Φ = 0`` or ``π`` exactly) the node is undefined and ``Θ = 0`` is taken (node along ``x₁``);
  then only ``Θ + u`` (``Φ = 0``) or ``Θ − u`` (``Φ = π``) carries information. Near these
  points ``Θ`` and ``u`` are individually ill-conditioned (an error ε in ``n̂`` moves them by
  ~ε/sin Φ) but the position built from them is not.
* For ``e = 0`` exactly the pericentre is undefined: ``ω = 0`` and ``f = u``.
* Angles returned lie in ``(−π, π]`` — except ``ρ = u + Σ``, which is not reduced, and ``Σ``,
  which is the gauge value given. ``Φ`` and the inclination lie in ``[0, π]``.

Invalid input raises :class:`ValueError` naming the parameter: non-finite values, ``mu ≤ 0``,
``a ≤ 0``, ``e ∉ [0, 1)``, inclination (or ``Φ``) outside ``[0, π]``, a body at the centre
(``r = 0``), rectilinear motion (``h = 0``: no orbit plane), and — for the classical elements — an
osculating orbit that is not an ellipse.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import mpmath
import numpy as np

from ..core.accuracy import to_mpf
from ..core.vectors import cross, dot, matvec, transpose
from .frames import functions_for, orbit_axes, plane_matrix

__all__ = [
    "CayleyState",
    "Elements",
    "cartesian_to_cayley",
    "cartesian_to_elements",
    "cayley_to_cartesian",
    "cayley_to_elements",
    "elements_to_cartesian",
    "elements_to_cayley",
]

Vector = list[Any]
FIXED_FRAME = (0, 0, 0)

#: The keys of an element set in a scene (``[orbit.elements]``, a planet's ``elements``).
ELEMENT_KEYS = ("a", "e", "inclination", "node", "argument_of_pericentre", "mean_anomaly")


@dataclass(frozen=True)
class CayleyState:
    """Cayley's osculating-plane variables (Cayley 1860), frame 2 relative to frame 1.

    Attributes
    ----------
    r : number or array
        Radius ``|x|``.
    rdot : number or array
        Radial velocity ``ṙ = x·v/r``.
    rho : number or array
        Departure ``ρ`` of the body: angle in the orbit plane from the departure point ``x₂``.
    h : number or array
        Angular momentum per unit mass, ``h = r²ρ̇ = |x × v| > 0``.
    Theta : number or array
        ``Θ``, longitude of the ascending node of the orbit on the reference plane (from ``x₁``).
    Sigma : number or array
        ``Σ``, departure of that node (arc of the orbit from ``x₂`` to the node); a gauge at the
        epoch.
    Phi : number or array
        ``Φ``, inclination of the orbit plane to the reference plane, in ``[0, π]``.
    """

    r: Any
    rdot: Any
    rho: Any
    h: Any
    Theta: Any
    Sigma: Any
    Phi: Any


@dataclass(frozen=True)
class Elements:
    """Classical elliptic elements of the osculating orbit, angles referred to frame 1.

    Attributes
    ----------
    a : number or array
        Semi-major axis, ``> 0``.
    e : number or array
        Eccentricity, in ``[0, 1)``.
    inclination : number or array
        Inclination to the reference plane, in ``[0, π]`` (Cayley's ``Φ``).
    node : number or array
        Longitude of the ascending node on the reference plane, from ``x₁`` (Cayley's ``Θ``).
    argument_of_pericentre : number or array
        Arc of the orbit from the ascending node to the pericentre, ``ω = u − f``.
    mean_anomaly : number or array
        ``M = E − e sin E``.
    """

    a: Any
    e: Any
    inclination: Any
    node: Any
    argument_of_pericentre: Any
    mean_anomaly: Any


@dataclass(frozen=True)
class _Kind:
    """The arithmetic of one call: mpmath at the current precision, or numpy doubles."""

    multiprecision: bool
    sin: Callable[[Any], Any]
    cos: Callable[[Any], Any]
    cos_sin: Callable[[Any], tuple[Any, Any]]
    sqrt: Callable[[Any], Any]
    atan2: Callable[[Any, Any], Any]
    ceil: Callable[[Any], Any]
    sign: Callable[[Any], Any]
    pi: Any
    eps: Any
    bits: int

    def where(self, condition: Any, a: Any, b: Any) -> Any:
        if self.multiprecision:
            return a if condition else b
        return np.where(condition, a, b)[()]

    def first(self, condition: Any, values: Any) -> Any:
        """The first of ``values`` where ``condition`` holds (for error messages)."""
        if self.multiprecision:
            return values
        return np.broadcast_to(values, np.shape(condition))[condition].flat[0]

    def angle(self, y: Any, x: Any) -> Any:
        """``atan2(y, x)`` in ``(−π, π]``: adding 0 turns a −0.0 into +0.0, so never −π."""
        return self.atan2(y + 0, x)

    def reduce(self, x: Any) -> Any:
        """``x`` reduced modulo 2π into ``(−π, π]``; an angle already in range is unchanged.

        In mpmath a large angle is reduced with as many more bits as its integer part has, so
        that the result is right to the working precision (at the working precision alone,
        1e25 would come back as noise, and 1e400 out of range).
        """
        if self.multiprecision and mpmath.mag(x) > 3:
            with mpmath.workprec(mpmath.mp.prec + int(mpmath.mag(x)) + 10):
                two_pi = 2 * mpmath.pi
                x = x - two_pi * mpmath.ceil((x - mpmath.pi) / two_pi)
            x = +x
        two_pi = 2 * self.pi
        y = x - two_pi * self.ceil((x - self.pi) / two_pi)
        y = self.where(y > self.pi, y - two_pi, y)
        return self.where(y <= -self.pi, y + two_pi, y)


def _is_multiprecision(value: Any) -> bool:
    if isinstance(value, str) or type(value).__module__.startswith("mpmath"):
        return True
    if isinstance(value, Sequence):
        return any(_is_multiprecision(v) for v in value)
    return False


def _exact_mpf(value: Any, name: str) -> mpmath.mpf:
    """``value`` in mpmath, with the bits of its integer part on top of the working precision:
    an angle is reduced modulo 2π from it, and needs them (see :meth:`_Kind.reduce`)."""
    x = to_mpf(value, name)
    if isinstance(value, str) and mpmath.mag(x) > 3:
        with mpmath.workprec(mpmath.mp.prec + int(mpmath.mag(x)) + 10):
            x = to_mpf(value, name)
    return x


def _prepare(named: list[tuple[str, Any]]) -> tuple[_Kind, list[Any]]:
    """Choose the arithmetic for the inputs and convert them to it, checking finiteness."""
    if any(_is_multiprecision(value) for _, value in named):
        values = [_exact_mpf(value, name) for name, value in named]
        f = functions_for(mpmath.mpf(1))
        kind = _Kind(
            True,
            f.sin,
            f.cos,
            f.cos_sin,
            f.sqrt,
            f.atan2,
            mpmath.ceil,
            mpmath.sign,
            +mpmath.pi,
            mpmath.mp.eps,
            mpmath.mp.prec,
        )
        return kind, values
    arrays = []
    for name, value in named:
        array = np.asarray(value, dtype=float)
        finite = np.isfinite(array)
        if not np.all(finite):
            bad = array[~finite].flat[0] if array.ndim else array
            raise ValueError(f"{name}: must be finite, got {bad}")
        arrays.append(array)
    try:
        arrays = np.broadcast_arrays(*arrays)
    except ValueError as exc:
        shapes = ", ".join(
            f"{name} {np.shape(a)}" for (name, _), a in zip(named, arrays, strict=True)
        )
        raise ValueError(f"the input shapes do not broadcast together: {shapes}") from exc
    values = [a[()] for a in arrays]
    f = functions_for(np.float64(1))
    eps = float(np.finfo(float).eps)
    kind = _Kind(False, f.sin, f.cos, f.cos_sin, f.sqrt, f.atan2, np.ceil, np.sign, np.pi, eps, 53)
    return kind, values


def _vector(value: Any, name: str) -> list[tuple[str, Any]]:
    components = list(value)
    if len(components) != 3:
        raise ValueError(f"{name}: must have 3 components, got {len(components)}")
    return [(name, c) for c in components]


def _require(kind: _Kind, bad: Any, value: Any, message: str) -> None:
    """Raise ``ValueError(message, got …)`` if ``bad`` holds anywhere."""
    if bad if kind.multiprecision else np.any(bad):
        raise ValueError(f"{message}, got {kind.first(bad, value)}")


def _check_mu(kind: _Kind, mu: Any) -> None:
    _require(kind, mu <= 0, mu, "mu (gravitational parameter): must be positive")


def _require_ellipse(kind: _Kind, bad: Any, e: Any) -> None:
    if np.any(bad):
        raise ValueError(
            f"the osculating orbit is not an ellipse (e = {kind.first(bad, e)}); "
            "classical elliptic elements do not exist"
        )


def _true_anomaly(kind: _Kind, half: tuple[Any, Any], e: Any) -> Any:
    """``f`` from ``tan(f/2) = √((1 + e)/(1 − e)) tan(E/2)``, in ``(−π, π]`` for ``E`` there;
    ``half`` is (cos, sin) of E/2."""
    return 2 * kind.atan2(kind.sqrt(1 + e) * half[1], kind.sqrt(1 - e) * half[0])


def _solve_kepler(kind: _Kind, M: Any, e: Any) -> Any:
    """``E`` with ``E − e sin E = M`` for ``M ∈ (−π, π]``, ``0 ≤ e < 1``; ``E ∈ [−π, π]``.

    Newton's method safeguarded by bisection: ``g(E) = E − e sin E − M`` increases strictly
    (``g′ = 1 − e cos E ≥ 1 − e > 0``) and changes sign on ``[−π, π]``, so each iterate narrows a
    bracket of the root and a Newton step leaving it is replaced by the midpoint. Converged means
    the Newton correction is below the rounding noise of ``g`` divided by ``g′``,
    ``4 ε (|E| + |M|) / (1 − e cos E)``: near ``e → 1`` and ``E → 0`` that noise is what limits
    ``E`` whatever the method (Kepler's equation is conditioned like ``1/(1 − e cos E)``).
    Entries that have converged are frozen, so an array gives the same digits as its elements.
    """
    zero = 0 * M
    lo, hi = zero - kind.pi, zero + kind.pi
    start = kind.where(e < 0.8, M + e * kind.sin(M), M + 0.85 * e * kind.sign(M))
    E = kind.where(start > kind.pi, hi, kind.where(start < -kind.pi, lo, start))
    done = zero != 0
    previous = E
    for _ in range(100 + 2 * kind.bits):
        cos_E, sin_E = kind.cos_sin(E)
        g = E - e * sin_E - M
        lo = kind.where(g < 0, E, lo)
        hi = kind.where(g > 0, E, hi)
        slope = 1 - e * cos_E
        correction = g / slope
        newton = E - correction
        # Or Newton no longer moves E, or steps back to the E before: with subnormal E and M
        # (|M| ~ 1e-313) the noise bound 4ε(|E| + |M|) underflows to 0 while g keeps a residue
        # of one subnormal, and E alternates between two neighbours.
        converged = (
            (abs(correction) <= 4 * kind.eps * (abs(E) + abs(M)) / slope)
            | (newton == E)
            | (newton == previous)
        )
        previous = E
        inside = (newton >= lo) & (newton <= hi)
        # A converged step may leave the bracket by rounding (a root at ±π): keep E then.
        step = kind.where(inside, newton, kind.where(converged, E, (lo + hi) / 2))
        E = kind.where(done, E, step)
        done = done | converged
        if np.all(done):
            return E
    raise ArithmeticError(
        f"Kepler's equation did not converge for e = {kind.first(~np.asarray(done), e)}, "
        f"M = {kind.first(~np.asarray(done), M)}"
    )


def cartesian_to_cayley(
    position: Sequence[Any],
    velocity: Sequence[Any],
    sigma: Any = 0,
    frame: Sequence[Any] = FIXED_FRAME,
) -> CayleyState:
    """Cayley's state at the epoch from the Cartesian state (docs/orbits.md, "Converting states").

    Parameters
    ----------
    position, velocity : sequence of 3 numbers or arrays
        ``x`` and ``v`` in the fixed frame 0.
    sigma : number or array, optional
        The gauge ``Σ`` at the epoch (default 0: the departure point at the ascending node).
    frame : sequence of 3 numbers or arrays, optional
        ``(θ′, σ′, φ′)`` of the reference plane at the epoch; default: frame 1 = frame 0.

    Returns
    -------
    CayleyState
        ``Θ, u ∈ (−π, π]``, ``Φ ∈ [0, π]``, ``Σ = sigma``, ``ρ = u + Σ``.

    Raises
    ------
    ValueError
        Non-finite input; ``r = 0`` (body at the centre); ``h = 0`` (rectilinear motion).
    """
    named = _vector(position, "position") + _vector(velocity, "velocity")
    named += [("sigma", sigma)] + _vector(frame, "frame")
    k, values = _prepare(named)
    x, v, Sigma, angles = values[0:3], values[3:6], values[6], values[7:10]
    r = k.sqrt(dot(x, x))
    _require(k, r == 0, r, "position: r = |x| must be nonzero (the body is at the central mass)")
    X, V = _on_reference(k, angles, x), _on_reference(k, angles, v)
    H = cross(X, V)
    h = k.sqrt(dot(H, H))
    _require(
        k,
        h == 0,
        h,
        "h = |x × v|: must be nonzero (rectilinear motion: the orbit plane is undefined)",
    )
    n = [c / h for c in H]
    Phi = k.angle(k.sqrt(n[0] * n[0] + n[1] * n[1]), n[2])
    Theta = k.where((n[0] == 0) & (n[1] == 0), 0 * h, k.angle(n[0], -n[1]))
    node = [*k.cos_sin(Theta), 0 * h]
    u = k.angle(dot(X, cross(n, node)), dot(X, node))
    return CayleyState(r, dot(X, V) / r, u + Sigma, h, Theta, Sigma, Phi)


def _on_reference(kind: _Kind, frame: Sequence[Any], x: Sequence[Any]) -> Vector:
    """``M₀₁ᵀ x``: a vector of frame 0 in frame 1.

    In mpmath with ``frame`` = (0, 0, 0), M₀₁ is the identity exactly (cos 0 = 1, sin 0 = 0),
    and each component of ``M₀₁ᵀ x``, 0 + 1·x_i + 0·x_j + 0·x_k, is x_i rounded once to the
    working precision (x is finite): what unary + gives, without the six cosines and sines and
    the 27 products.
    """
    if kind.multiprecision and frame[0] == 0 and frame[1] == 0 and frame[2] == 0:
        return [+c for c in x]
    return matvec(transpose(plane_matrix(*frame)), x)


def cayley_to_cartesian(
    state: CayleyState, frame: Sequence[Any] = FIXED_FRAME
) -> tuple[Vector, Vector]:
    """Position and velocity in frame 0 from Cayley's state (docs/orbits.md, "Conventions").

    ``x = r M₀₁ M₁₂ (cos ρ, sin ρ, 0)ᵀ = r x̂₃`` and ``v = ṙ x̂₃ + (h/r) ŷ₃``, with ``x̂₃, ŷ₃`` of
    §5 (argument of latitude ``u = ρ − Σ``) carried to frame 0 by ``M₀₁(θ′, σ′, φ′)``.

    Parameters
    ----------
    state : CayleyState
    frame : sequence of 3 numbers or arrays, optional
        ``(θ′, σ′, φ′)`` of the reference plane at the state's epoch.

    Returns
    -------
    (position, velocity) : tuple of two 3-lists

    Raises
    ------
    ValueError
        Non-finite input; ``r ≤ 0``.
    """
    named = [(name, getattr(state, name)) for name in ("r", "rdot", "rho", "h")]
    named += [(name, getattr(state, name)) for name in ("Theta", "Sigma", "Phi")]
    k, values = _prepare(named + _vector(frame, "frame"))
    r, rdot, rho, h, Theta, Sigma, Phi = values[:7]
    _require(k, r <= 0, r, "r: must be positive")
    x3, y3, _ = orbit_axes(Theta, Phi, rho - Sigma)
    M01 = plane_matrix(*values[7:10])
    position = matvec(M01, [r * c for c in x3])
    velocity = matvec(M01, [rdot * a + (h / r) * b for a, b in zip(x3, y3, strict=True)])
    return position, velocity


def cayley_to_elements(state: CayleyState, mu: Any) -> Elements:
    """Classical elements of the osculating ellipse from Cayley's state (docs/orbits.md,
    "Converting states").

    ``1/a = 2/r − (ṙ² + h²/r²)/μ``; ``e cos E = 1 − r/a``, ``e sin E = rṙ/√(μa)``;
    ``tan(f/2) = √((1 + e)/(1 − e)) tan(E/2)``, ``M = E − e sin E``; ``i = Φ``, ``Ω = Θ``,
    ``ω = u − f`` with ``u = ρ − Σ``.

    These are the relations of §9.1 (``e cos f = h²/(μr) − 1``, ``e sin f = hṙ/μ``) taken in the
    other order: ``E`` first, then ``f`` from it. Going from ``f`` to ``E`` multiplies the rounding
    of ``e`` by ``1/(1 − e)`` in ``M`` (``√(1 − e)`` enters ``E``); at ``e = 0.999999`` that moved
    the round-tripped position by ~10⁵ ε·a against ~10² ε·a this way. ``f`` still comes with ``E``
    so that ``ω + f`` returns ``u`` however ill-defined the pericentre (``e → 0``).

    Parameters
    ----------
    state : CayleyState
        With ``r > 0``, ``h > 0`` and ``Φ ∈ [0, π]``.
    mu : number or array
        Gravitational parameter ``μ > 0``.

    Returns
    -------
    Elements
        Angles in ``(−π, π]``; ``ω = 0`` if ``e = 0`` exactly.

    Raises
    ------
    ValueError
        Invalid input, or an osculating orbit that is not an ellipse (energy ``≥ 0``).
    """
    named = [(name, getattr(state, name)) for name in ("r", "rdot", "rho", "h")]
    named += [(name, getattr(state, name)) for name in ("Theta", "Sigma", "Phi")]
    k, (r, rdot, rho, h, Theta, Sigma, Phi, mu) = _prepare(named + [("mu", mu)])
    _check_mu(k, mu)
    _require(k, r <= 0, r, "r: must be positive")
    _require(k, h <= 0, h, "h: must be positive (it is |x × v|)")
    _require(k, (Phi < 0) | (Phi > k.pi), Phi, "Phi: must be in [0, pi]")
    inverse_a = 2 / r - (rdot * rdot + (h / r) ** 2) / mu
    _require_ellipse(k, inverse_a <= 0, k.sqrt(abs(1 - h * h / mu * inverse_a)))
    e_cos_E = 1 - r * inverse_a
    e_sin_E = r * rdot * k.sqrt(inverse_a / mu)
    e = k.sqrt(e_cos_E * e_cos_E + e_sin_E * e_sin_E)
    _require_ellipse(k, e >= 1, e)
    u = k.reduce(rho - Sigma)
    E = k.where(e == 0, u, k.angle(e_sin_E, e_cos_E))
    f = k.where(e == 0, u, _true_anomaly(k, k.cos_sin(E / 2), e))
    return Elements(
        a=1 / inverse_a,
        e=e,
        inclination=Phi,
        node=k.reduce(Theta),
        argument_of_pericentre=k.reduce(u - f),
        mean_anomaly=k.reduce(E - e * k.sin(E)),
    )


def elements_to_cayley(elements: Elements, mu: Any, sigma: Any = 0) -> CayleyState:
    """Cayley's state from classical elements, with the gauge ``Σ = sigma`` (docs/orbits.md,
    "Converting states").

    ``E`` from Kepler's equation, ``tan(f/2) = √((1 + e)/(1 − e)) tan(E/2)``,
    ``r = a(1 − e cos E)``, ``ṙ = √(μa) e sin E / r``, ``h = √(μp)`` with ``p = a(1 − e²)``;
    ``Θ = Ω``, ``Φ = i``, ``u = ω + f`` and ``ρ = Σ + u``.

    Parameters
    ----------
    elements : Elements
        ``a > 0``, ``0 ≤ e < 1``, ``0 ≤ i ≤ π``; the other angles anywhere.
    mu : number or array
        Gravitational parameter ``μ > 0``.
    sigma : number or array, optional
        The gauge ``Σ`` at the epoch.

    Returns
    -------
    CayleyState
        ``Θ, u ∈ (−π, π]``, ``ρ = u + Σ``.

    Raises
    ------
    ValueError
        Invalid input.
    ArithmeticError
        Kepler's equation did not converge (not expected for ``e < 1``).
    """
    named = [("a", elements.a), ("e", elements.e), ("inclination", elements.inclination)]
    named += [("node", elements.node), ("argument_of_pericentre", elements.argument_of_pericentre)]
    named += [("mean_anomaly", elements.mean_anomaly), ("mu", mu), ("sigma", sigma)]
    k, (a, e, i, node, omega, M, mu, Sigma) = _prepare(named)
    _check_mu(k, mu)
    _require(k, a <= 0, a, "a (semi-major axis): must be positive")
    _require(
        k,
        (e < 0) | (e >= 1),
        e,
        "eccentricity: must be in [0, 1) for an elliptic element set",
    )
    _require(k, (i < 0) | (i > k.pi), i, "inclination: must be in [0, pi]")
    E = _solve_kepler(k, k.reduce(M), e)
    half = k.cos_sin(E / 2)
    f = _true_anomaly(k, half, e)
    # 1 − e cos E and 1 − e² rewritten so that nothing cancels as e → 1 near pericentre.
    half_sin = half[1]
    r = a * ((1 - e) + 2 * e * half_sin * half_sin)
    p = a * (1 - e) * (1 + e)
    u = k.reduce(omega + f)
    return CayleyState(
        r=r,
        rdot=k.sqrt(mu * a) * e * k.sin(E) / r,
        rho=Sigma + u,
        h=k.sqrt(mu * p),
        Theta=k.reduce(node),
        Sigma=Sigma,
        Phi=i,
    )


def cartesian_to_elements(
    position: Sequence[Any],
    velocity: Sequence[Any],
    mu: Any,
    frame: Sequence[Any] = FIXED_FRAME,
) -> Elements:
    """Classical elements, referred to frame 1, of the osculating ellipse of ``(x, v)``.

    :func:`cartesian_to_cayley` then :func:`cayley_to_elements` (which see for the conventions
    and errors).
    """
    return cayley_to_elements(cartesian_to_cayley(position, velocity, 0, frame), mu)


def elements_to_cartesian(
    elements: Elements, mu: Any, frame: Sequence[Any] = FIXED_FRAME
) -> tuple[Vector, Vector]:
    """Position and velocity in frame 0 from elements referred to frame 1.

    :func:`elements_to_cayley` then :func:`cayley_to_cartesian` (the gauge drops out).
    """
    return cayley_to_cartesian(elements_to_cayley(elements, mu), frame)
