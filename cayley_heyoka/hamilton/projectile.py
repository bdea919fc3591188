"""Hamilton's projectile (Second Essay, 1835, §24–27) in closed form, at any precision.

Symbols, as in Hamilton (1835), *Second Essay on a General Method in Dynamics*, §24–27
(docs/hamilton.md, "The projectile in closed form"):

* ``η = (η₁, η₂, η₃)`` — rectangular coordinates of the point, η₃ vertical (upwards);
  ``ϖ = (ϖ₁, ϖ₂, ϖ₃)`` — the conjugate momenta (velocities, unit mass).
* ``e, p`` — the values of η, ϖ at t = 0 (the initial data).
* ``g`` — the constant downward acceleration; ``μ, ν`` ≥ 0 — the horizontal and vertical
  frequencies of the disturbing force, so that

  ``H = ½|ϖ|² + gη₃ + ½{μ²(η₁² + η₂²) + ν²η₃²}``,  ``U = −gη₃ − ½{μ²(η₁² + η₂²) + ν²η₃²}``,

  ``η̇ = ϖ``, ``ϖ̇₁,₂ = −μ²η₁,₂``, ``ϖ̇₃ = −g − ν²η₃`` (Hamilton's (110.)–(112.)).
* ``S = ∫₀ᵗ (T + U) dt`` — Hamilton's principal function, taken along the motion; as a function
  of the end points ``S(η, e, t)`` it is (120.), with ∂S/∂η = ϖ, ∂S/∂e = −p, ∂S/∂t = −H.

Two entry points:

* :func:`projectile_solution` — the motion from its initial data (113.)–(114.) and S along it.
* :func:`principal_function` — S(η, e, t) of (120.) and its partial derivatives (122.)–(123.).

Both are regular at and near μ = 0 and ν = 0 (the parabola of §5.4). Hamilton's arrangement
of (120.) is not: its ``cot μt``, ``(η₃ + g/ν²)(e₃ + g/ν²) tan ½νt`` and ``g²t/2ν²`` terms are
each infinite as ν → 0 and cancel. So every formula here is written with the even, regular
functions of x = μt or νt (and y = x/2)

    x cot x,   tan y / y,   (tan y − y)/y³,   sin x / x,   (x − sin x)/x³,

the last two differences evaluated with the digits their cancellation costs added (or by their
leading terms when x is below the working precision). With them (120.) is S_v plus S_h
summed over the two horizontal components, with x = μt in S_h and x = νt in S_v:

    S_h = (η − e)²/(2t) · x cot x − ηe · μ²t/2 · tan y/y,
    S_v = (η₃ − e₃)²/(2t) · x cot x − (ν²η₃e₃ + g(η₃ + e₃)) · t/2 · tan y/y
         − g²t³/8 · (tan y − y)/y³,

which tend to (130.) as μ, ν → 0. Along the motion, T + U = ½ d(η·ϖ)/dt − ½gη₃ (since
ϖ̇·η = 2U + gη₃), so S(t; e, p) = ½[η·ϖ]₀ᵗ − ½g∫₀ᵗη₃ dt, written out in (e, p, t) without
the cancellation of η·ϖ − e·p at small t.

Every value is computed at two working precisions (:mod:`..reference.accuracy`) and carries
its error estimate (absolute for ``|value| ≤ 1``, relative above); a request that cannot be met
raises :class:`~cayley_heyoka.reference.PrecisionNotReached`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import mpmath

from ..core.accuracy import Certified, certify, shown, shown_error, to_mpf
from ..core.inputs import check_dps, read_triple

__all__ = ["PrincipalFunction", "ProjectileSolution", "principal_function", "projectile_solution"]

_VEC = tuple[mpmath.mpf, mpmath.mpf, mpmath.mpf]


@dataclass(frozen=True, repr=False)
class ProjectileSolution:
    """The projectile at time t from its initial data (e, p).

    Attributes
    ----------
    eta : tuple of 3 mpf
        Coordinates η(t) (113.).
    varpi : tuple of 3 mpf
        Momenta ϖ(t) (114.).
    S : mpf
        The principal function ∫₀ᵗ(T + U) dt along the motion, i.e. S(η(t), e, t) of (120.).
    errors : dict
        Error estimate of each quantity, keyed ``eta1 … eta3``, ``varpi1 … varpi3``, ``S``
        (absolute if ``|value| ≤ 1``, else relative).
    """

    eta: _VEC
    varpi: _VEC
    S: mpmath.mpf
    errors: dict[str, mpmath.mpf] = field(repr=False)

    @property
    def error(self) -> mpmath.mpf:
        """The worst error estimate."""
        return max(self.errors.values())

    def __repr__(self) -> str:
        """One line: η, ϖ, S and the worst error estimate (t, g, μ, ν are the caller's: the
        solution does not keep them)."""
        return (
            f"<ProjectileSolution η = ({shown(*self.eta)}), ϖ = ({shown(*self.varpi)}), "
            f"S = {shown(self.S)}, error {shown_error(self.error)}>"
        )


@dataclass(frozen=True, repr=False)
class PrincipalFunction:
    """Hamilton's principal function S(η, e, t) (120.) and its partial derivatives.

    Attributes
    ----------
    S : mpf
        The principal function.
    d_eta : tuple of 3 mpf
        ∂S/∂η, the final momenta ϖ (122.).
    d_e : tuple of 3 mpf
        ∂S/∂e, minus the initial momenta p (123.).
    d_t : mpf
        ∂S/∂t, minus the energy H.
    errors : dict
        Error estimate of each quantity, keyed ``S``, ``d_eta1 … d_eta3``, ``d_e1 … d_e3``,
        ``d_t`` (absolute if ``|value| ≤ 1``, else relative).
    """

    S: mpmath.mpf
    d_eta: _VEC
    d_e: _VEC
    d_t: mpmath.mpf
    errors: dict[str, mpmath.mpf] = field(repr=False)

    @property
    def error(self) -> mpmath.mpf:
        """The worst error estimate."""
        return max(self.errors.values())

    def __repr__(self) -> str:
        """One line: S, its partial derivatives and the worst error estimate (η, e, t are the
        caller's: the result does not keep them)."""
        return (
            f"<PrincipalFunction S = {shown(self.S)}, ∂S/∂η = ({shown(*self.d_eta)}), "
            f"∂S/∂e = ({shown(*self.d_e)}), ∂S/∂t = {shown(self.d_t)}, "
            f"error {shown_error(self.error)}>"
        )


# -- regular functions of x = ωt --------------------------------------------------------------


def _cancelling(x: mpmath.mpf, f: Callable[[mpmath.mpf], mpmath.mpf], lead, second):
    """f(x) = lead + second·x² + O(x⁴), an even function whose formula cancels ~x² near 0.

    The formula is evaluated with the bits it loses added; below the working precision the
    two leading terms are exact to it.
    """
    if x == 0:
        return mpmath.mpf(lead)
    prec = mpmath.mp.prec
    lost = max(0, -2 * int(mpmath.mag(x)))
    if lost > prec + 10:
        return mpmath.mpf(lead) + mpmath.mpf(second) * x * x
    with mpmath.workprec(prec + lost + 20):
        value = f(x)
    return +value


def _x_minus_sin(x: mpmath.mpf) -> mpmath.mpf:
    """(x − sin x)/x³, 1/6 at x = 0."""
    return _cancelling(
        x, lambda u: (u - mpmath.sin(u)) / u**3, mpmath.mpf(1) / 6, -mpmath.mpf(1) / 120
    )


def _tan_minus(y: mpmath.mpf) -> mpmath.mpf:
    """(tan y − y)/y³, 1/3 at y = 0."""
    return _cancelling(
        y, lambda u: (mpmath.tan(u) - u) / u**3, mpmath.mpf(1) / 3, mpmath.mpf(2) / 15
    )


def _sinc(x: mpmath.mpf) -> mpmath.mpf:
    """sin x / x."""
    return mpmath.mpf(1) if x == 0 else mpmath.sin(x) / x


def _tanc(y: mpmath.mpf) -> mpmath.mpf:
    """tan y / y."""
    return mpmath.mpf(1) if y == 0 else mpmath.tan(y) / y


def _xcot(x: mpmath.mpf) -> mpmath.mpf:
    """x cot x."""
    return mpmath.mpf(1) if x == 0 else x * mpmath.cos(x) / mpmath.sin(x)


# -- reading the inputs -----------------------------------------------------------------------


def read_parameters(g: object, mu: object, nu: object, t: object) -> dict[str, mpmath.mpf]:
    """g, μ, ν, t at the current precision: finite, μ, ν ≥ 0; errors name the parameter."""
    values = {name: to_mpf(x, name) for name, x in (("g", g), ("mu", mu), ("nu", nu), ("t", t))}
    for name in ("mu", "nu"):
        if values[name] < 0:
            raise ValueError(
                f"{name}: the frequency must be >= 0, got {values[name]} (the sign of {name} "
                f"is immaterial; only {name}² enters H)"
            )
    return values


def _span_digits(*xs: mpmath.mpf) -> int:
    """Digits that rounding x = ωt costs in cos x, sin x when |x| is large."""
    with mpmath.workprec(64):  # a count of digits: never mpmath's global precision's
        return int(mpmath.log10(1 + max(abs(x) for x in xs))) + 1


def _run(compute: Callable[[int], Mapping[str, mpmath.mpf]], dps: int, extra: int, what: str):
    hint = f"{what} at dps={dps}: increase dps"
    return certify(compute, dps, guard=12 + extra, hint=hint)


# -- the motion from its initial data ---------------------------------------------------------


class Elementary(NamedTuple):
    """The functions :func:`motion` needs, for one kind of number."""

    cos: Callable[[Any], Any]
    sinc: Callable[[Any], Any]  # sin x / x
    x_minus_sin: Callable[[Any], Any]  # (x − sin x)/x³
    zero: Any


MPMATH = Elementary(mpmath.cos, _sinc, _x_minus_sin, mpmath.mpf(0))


def motion(g, mu, nu, e, p, t, f: Elementary = MPMATH) -> dict[str, Any]:
    """η(t), ϖ(t) (113.)–(114.) and S(t; e, p), at the current precision, in the numbers of
    ``f`` (mpmath's here; Arb balls in :mod:`.projectile_bounds`)."""
    out: dict[str, Any] = {}
    S = f.zero
    # Horizontal: η = ec + ps, ϖ = pc − μ²es with c = cos μt, s = sin μt/μ;
    # ½(ηϖ − ep) = ½[(p² − μ²e²)cs − 2μ²eps²] since c² − 1 = −μ²s².
    x = mu * t
    c, s = f.cos(x), t * f.sinc(x)
    m2 = mu * mu
    for i in (0, 1):
        out[f"eta{i + 1}"] = e[i] * c + p[i] * s
        out[f"varpi{i + 1}"] = p[i] * c - m2 * e[i] * s
        S += ((p[i] ** 2 - m2 * e[i] ** 2) * c * s - 2 * m2 * e[i] * p[i] * s * s) / 2
    # Vertical: with v = (1 − cos νt)/ν² = ½t²(sin ½νt / ½νt)² and q = ν²e₃ + g,
    # η₃ = e₃c + p₃s − gv, ϖ₃ = p₃c − qs, ∫₀ᵗη₃ = e₃s + p₃v − gw, w = t³(x − sin x)/x³.
    x = nu * t
    c, s = f.cos(x), t * f.sinc(x)
    v = t * t * f.sinc(x / 2) ** 2 / 2
    w = t**3 * f.x_minus_sin(x)
    n2 = nu * nu
    e3, p3 = e[2], p[2]
    q = n2 * e3 + g
    out["eta3"] = e3 * c + p3 * s - g * v
    out["varpi3"] = p3 * c - q * s
    # ½(η₃ϖ₃ − e₃p₃), expanded with c² − 1 = −ν²s², and −½g∫η₃.
    S += (
        (p3 * p3 - e3 * q) * c * s
        - 2 * n2 * e3 * p3 * s * s
        - g * p3 * (s * s + v * c)
        + g * q * v * s
        - g * (e3 * s + p3 * v - g * w)
    ) / 2
    out["S"] = S
    return out


def projectile_solution(
    g: object,
    mu: object,
    nu: object,
    e: object,
    p: object,
    t: object,
    dps: int = 30,
) -> ProjectileSolution:
    """The projectile at time ``t`` from its initial data, with the principal function.

    Parameters
    ----------
    g : number
        Constant downward acceleration (any sign).
    mu, nu : number
        Horizontal and vertical frequencies μ, ν ≥ 0; 0 is allowed (μ = ν = 0 is the parabola
        of §5.4) and the result is continuous there.
    e, p : sequence of 3 numbers
        Initial coordinates η(0) and momenta ϖ(0) (a list or tuple).
    t : number
        Time (any sign).
    dps : int
        Decimal digits to certify (≥ 5).

    Numbers are read exactly: decimal strings (recommended) at every working precision, floats
    at their exact binary value, ints and mpf as they are.

    Returns
    -------
    ProjectileSolution
        η(t), ϖ(t) (113.)–(114.) and S = ∫₀ᵗ(T + U) dt along the motion, with error estimates.

    Raises
    ------
    ValueError
        On non-finite input, μ < 0 or ν < 0, or a vector that is not of length 3; the message
        names the parameter.
    PrecisionNotReached
        When ``dps`` digits cannot be certified.
    """
    dps = check_dps(dps)
    with mpmath.workdps(dps + 20):
        par = read_parameters(g, mu, nu, t)
        read_triple(e, "e")
        read_triple(p, "p")
        extra = _span_digits(par["mu"] * par["t"], par["nu"] * par["t"])

    def compute(_wdps: int) -> dict[str, mpmath.mpf]:
        r = read_parameters(g, mu, nu, t)
        return motion(r["g"], r["mu"], r["nu"], read_triple(e, "e"), read_triple(p, "p"), r["t"])

    cert: Certified = _run(compute, dps, extra, "projectile_solution")
    v = cert.values
    return ProjectileSolution(
        eta=tuple(v[f"eta{i}"] for i in (1, 2, 3)),
        varpi=tuple(v[f"varpi{i}"] for i in (1, 2, 3)),
        S=v["S"],
        errors=cert.errors,
    )


# -- the principal function of the end points -------------------------------------------------


def _conjugate_distance(x: mpmath.mpf) -> mpmath.mpf:
    """Distance of x from the nearest nonzero multiple of π (inf if none is nearer than 0)."""
    k = mpmath.nint(x / mpmath.pi)
    if k == 0:
        return mpmath.inf
    return abs(x - k * mpmath.pi)


def _principal(g, mu, nu, eta, e, t) -> dict[str, mpmath.mpf]:
    """S(η, e, t) (120.), ∂S/∂η (122.), ∂S/∂e (123.), ∂S/∂t, at the current precision."""
    out: dict[str, mpmath.mpf] = {}
    S = mpmath.mpf(0)
    d_t = mpmath.mpf(0)
    for i, w in ((0, mu), (1, mu), (2, nu)):
        x = w * t
        y = x / 2
        K = _xcot(x)  # x cot x
        half = w * w * t * _tanc(y) / 2  # ω tan ½ωt
        sec2 = 1 / mpmath.cos(y) ** 2
        ratio = mpmath.mpf(1) if x == 0 else x / mpmath.sin(x)
        d = eta[i] - e[i]
        # ω d cot ωt − ω e tan ½ωt, and −ω d cot ωt − ω η tan ½ωt (the g-terms below).
        out[f"d_eta{i + 1}"] = d / t * K - e[i] * half
        out[f"d_e{i + 1}"] = -d / t * K - eta[i] * half
        S += d * d / (2 * t) * K - eta[i] * e[i] * half
        d_t += -d * d / (2 * t * t) * ratio**2 - w * w * eta[i] * e[i] * sec2 / 2
    # The g-terms of the vertical: −ν(η₃ + g/ν²)(e₃ + g/ν²) tan ½νt + g²t/2ν², less their
    # ηe part above, is −g(η₃ + e₃)·t/2·tan y/y − g²t³/8·(tan y − y)/y³ (y = ½νt).
    y = nu * t / 2
    tq = _tanc(y)
    out["d_eta3"] -= g * t * tq / 2
    out["d_e3"] -= g * t * tq / 2
    S += -g * (eta[2] + e[2]) * t * tq / 2 - g * g * t**3 * _tan_minus(y) / 8
    # ∂/∂t: −½ν²(η₃e₃ + (g/ν²)(η₃ + e₃) + g²/ν⁴)sec²y + g²/2ν², less the ηe part above.
    d_t += -g * (eta[2] + e[2]) / (2 * mpmath.cos(y) ** 2) - g * g * t * t * tq**2 / 8
    out["S"] = S
    out["d_t"] = d_t
    return out


def principal_function(
    eta: object,
    e: object,
    t: object,
    g: object,
    mu: object,
    nu: object,
    dps: int = 30,
) -> PrincipalFunction:
    """Hamilton's principal function S(η, e, t) (120.) and its partial derivatives.

    S is the action ∫₀ᵗ(T + U) dt of the motion that leaves ``e`` at time 0 and arrives at
    ``eta`` at time ``t``; its derivatives are the integrals (122.)–(123.):
    ∂S/∂η = ϖ, ∂S/∂e = −p, and ∂S/∂t = −H.

    Parameters
    ----------
    eta, e : sequence of 3 numbers
        Final and initial coordinates (a list or tuple).
    t : number
        Time of flight, nonzero (any sign).
    g : number
        Constant downward acceleration (any sign).
    mu, nu : number
        Horizontal and vertical frequencies μ, ν ≥ 0. μ = 0 and ν = 0 are allowed: the
        formulas are written in regular functions of μt, νt and tend to (130.) there.
    dps : int
        Decimal digits to certify (≥ 5).

    Numbers are read exactly: decimal strings (recommended) at every working precision, floats
    at their exact binary value, ints and mpf as they are.

    Returns
    -------
    PrincipalFunction
        ``S``, ``d_eta``, ``d_e``, ``d_t`` with error estimates.

    Raises
    ------
    ValueError
        On invalid input (the message names the parameter); for t = 0, where S is singular;
        and at a conjugate point, where sin μt = 0 or sin νt = 0 (μt or νt a nonzero multiple
        of π to the working precision): there S does not exist, the end points being joined
        by no motion or by infinitely many.
    PrecisionNotReached
        When ``dps`` digits cannot be certified.

    Notes
    -----
    Close to a conjugate point the terms of S grow like ``1/|sin μt|`` (S itself does for a
    generic η) and the digits lost there are added to the working precision.
    """
    dps = check_dps(dps)
    probe = dps + 30
    with mpmath.workdps(probe):
        par = read_parameters(g, mu, nu, t)
        read_triple(eta, "eta")
        read_triple(e, "e")
        if par["t"] == 0:
            raise ValueError("t: must be nonzero; S(η, e, t) is singular at t = 0")
        extra = 0
        for name in ("mu", "nu"):
            x = par[name] * par["t"]
            gap = _conjugate_distance(x)
            if gap <= abs(x) * mpmath.mpf(10) ** -(dps + 20):
                raise ValueError(
                    f"{name}: sin({name}·t) = 0 to {dps + 20} digits ({name}·t = "
                    f"{mpmath.nstr(x / mpmath.pi, 10)}·π): a conjugate point, where the "
                    "principal function S(η, e, t) does not exist"
                )
            if mpmath.isfinite(gap):
                # cot x and tan ½x lose log10(|x|/gap) digits, and the terms they multiply,
                # each ~|x|/gap times larger than S at a moderate η, cancel as many again.
                extra = max(extra, 2 * int(mpmath.ceil(mpmath.log10(abs(x) / gap))) + 1)
        extra += _span_digits(par["mu"] * par["t"], par["nu"] * par["t"])

    def compute(_wdps: int) -> dict[str, mpmath.mpf]:
        r = read_parameters(g, mu, nu, t)
        return _principal(
            r["g"], r["mu"], r["nu"], read_triple(eta, "eta"), read_triple(e, "e"), r["t"]
        )

    cert = _run(compute, dps, extra, "principal_function")
    v = cert.values
    return PrincipalFunction(
        S=v["S"],
        d_eta=tuple(v[f"d_eta{i}"] for i in (1, 2, 3)),
        d_e=tuple(v[f"d_e{i}"] for i in (1, 2, 3)),
        d_t=v["d_t"],
        errors=cert.errors,
    )
