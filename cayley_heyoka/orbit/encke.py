"""Encke's formulation: the deviation δ from an osculating Kepler orbit, rectified every orbit.

The body is written ``x = y + δ``, where ``y`` is a Kepler ellipse known in closed form and
``δ`` is integrated. At every apocentre a terminal event *rectifies*: the handler forms
``x = y + δ`` and ``v = ẏ + δ̇`` in extended precision, puts ``y`` on the osculating ellipse of
that state and sets δ to the difference, of the order of the rounding. Between rectifications
``|δ|`` stays of the order of the perturbation's effect over one orbit (~10⁻⁴ of the orbit for
J2 = 10⁻³), so the rounding of the integrated state, which limits the Cartesian formulation,
is that much smaller.

The ellipse. With ``A = a P̂``, ``B = a√(1 − e²) Q̂`` and its eccentric anomaly E::

    y = (cos E − e) A + sin E B,        ẏ = Ė (cos E B − sin E A),
    Ė = n/D,   D = 1 − e cos E,         ÿ = −(n²/D³) y,

the last exactly, for *any* vectors A, B: the curve the equations use is the one the rounded
parameters define, whether or not it is exactly a Kepler orbit of μ. E is integrated, as
``ψ = E/2`` beside δ, rather than solved from Kepler's equation: heyoka's ``kepE`` forms
``1 − e cos E`` in the Taylor recurrences of E, which at the pericentre of an eccentric orbit
loses ε/(1 − e) of it, and a phase ``n (t − t₀)`` would carry the rounding of t, which heyoka
hands its equations as the leading double of its double-length time (~4·10⁻¹² near
t = 6·10⁴). The half angle ψ keeps ``cos E − e = (1 − e) − 2 sin²ψ`` and
``D = (1 − e) + 2e sin²ψ`` accurate there too. An error in ψ moves x and v together along the
ellipse, so it changes neither the energy nor the period (to first order in δ): it does not
feed the Kepler shear.

The equation of δ (Battin's form, no difference of nearly equal forces)::

    δ̈ = μ/(ρ³S³) (F(q) y − δ) − (n²/D³) F(p) y + ∇Ω(y + δ),

with ``ρ = |y|``, ``q = (2 y·δ + δ·δ)/ρ²``, ``S = √(1 + q)``, ``F(q) = (1 + q)^{3/2} − 1``
written as ``q (1 + S + S²)/(1 + S)``, and ``p = (α u² + β w² − 2γ u w)/ρ²``
(``u = cos E − e``, ``w = sin E``) the mismatch, exactly known, between the rounded parameters
and a Kepler orbit of μ: ``α = k² − |A|²``, ``β = k²(1 − e²) − |B|²``, ``γ = A·B``,
``k³ = μ/n²``. p is of the order of the run's ε (times 1/(1 − e²)² at most), so
``F(p) = 3p/2`` to O(p²). Ω is the family's Cartesian disturbing function
(:mod:`.disturbing`) evaluated at ``y + δ``.

The rectification happens where E reaches π (a terminal event ``ψ = π/2``): the ellipse's
apocentre, where the motion is slowest. heyoka scales its tolerance by the largest of the
state's and the event functions' values, so the event is on ψ (|ψ − π/2| ≤ 9π/8), not on t;
of the scalings of E tried (E … E/256), E/2 was the most accurate (docs/orbits.md).

Extended precision. The handler reads the state and the parameters exactly, rounds each new
parameter once to the run's precision, and computes δ from the curve those rounded parameters
define, so that ``y + δ`` is continuous across a rectification to the extended precision. For
double runs on x86-64 the extended precision is the 80-bit long double and the handler's
formulas are compiled by heyoka in it (two functions, the rounding to double between them:
~15 µs a rectification against 40–60 µs as numpy scalars); elsewhere, and for quad and
multiprecision runs, it is mpmath with 64 guard bits. An osculating orbit that is not an
ellipse (e ≥ 1) ends the run there.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping, Sequence
from typing import Any

import heyoka as hy
import mpmath
import numpy as np

from ..core import vectors
from ..core.model import ParTable
from ..core.precision import Precision
from ..core.vectors import dot

Expr = Any  # a heyoka expression
STATE = ("dx", "dy", "dz", "dvx", "dvy", "dvz", "psi")
#: Runtime parameters of the osculating ellipse (``encke.*``), in the order they are allocated.
PARAMETERS = (
    "e",
    "one_minus_e",
    "n",
    "A[0]",
    "A[1]",
    "A[2]",
    "B[0]",
    "B[1]",
    "B[2]",
    "alpha",
    "beta",
    "gamma",
    "n2",
    "next",
    "k2",
    "kappa",
    "k2_lo",
)
#: Those that place a point on the ellipse (what the handler reads back).
_CURVE = ("e", "one_minus_e", "n", "A[0]", "A[1]", "A[2]", "B[0]", "B[1]", "B[2]")
_LONG_DOUBLE_BITS = 63  # significand bits of x87 extended precision, without the leading one
_GUARD_BITS = 64


class Unbound(ArithmeticError):
    """The osculating orbit is not an ellipse (e ≥ 1): Encke's reference orbit is undefined."""

    def __init__(self, e: Any) -> None:
        # 1 − e as well: e = 1 − 10⁻³⁶ prints as 1 to any digits a message can show.
        if isinstance(e, mpmath.mpf):
            shown = f"{mpmath.nstr(e, 20)}, 1 − e = {mpmath.nstr(1 - e, 3)}"
        else:
            shown = f"{float(e):.17g}"
        super().__init__(f"the osculating orbit is not an ellipse (e = {shown})")
        self.e = e


class Encke:
    """The parameters, equations and rectification of Encke's formulation for one structure.

    The handler reads every number from the parameter vector it is given (μ and the
    ellipse), so that it serves every scene of its structure.

    Parameters
    ----------
    pars
        The model's parameter table; ``encke.*`` parameters are allocated in it.
    precision
        The run's precision.
    mu
        The parameter holding μ (named ``mu`` in ``pars``).
    values
        The ``encke.*`` parameters' values: the initial osculating ellipse (:func:`start`).
    """

    def __init__(
        self, pars: ParTable, precision: Precision, mu: Expr, values: Mapping[str, Any]
    ) -> None:
        self.precision = precision
        self.arith = _MpArithmetic(precision)
        self._compiled = _compiles(precision)
        self.mu = mu
        self._mu_index = pars.index("mu")
        self.par = {name: pars.add(f"encke.{name}", values[f"encke.{name}"]) for name in PARAMETERS}
        self.index = {name: pars.index(f"encke.{name}") for name in PARAMETERS}
        self._curve_slots = np.array([self.index[name] for name in _CURVE])
        self._set_slots = np.array([self.index[name] for name in _SET])

    # ------------------------------------------------------------------ equations
    def curve(self, psi: Expr) -> tuple[list[Expr], list[Expr], dict[str, Expr]]:
        """y, ẏ, ψ̇ and the pieces the equation of δ reuses, as expressions of ψ = E/2."""
        y, ydot, parts = self.ellipse(hy.sin(psi), hy.cos(psi))
        parts["psi_rate"] = 0.5 * parts["rate"]
        return y, ydot, parts

    def ellipse(self, s: Expr, c: Expr) -> tuple[list[Expr], list[Expr], dict[str, Expr]]:
        """y, ẏ and the pieces of the equation of δ from s = sin(E/2), c = cos(E/2)."""
        p = self.par
        e, one_minus_e = p["e"], p["one_minus_e"]
        # cos E − e = (1 − e) − 2 sin²(E/2) and D = 1 − e cos E = (1 − e) + 2e sin²(E/2) keep
        # their relative accuracy at the pericentre of an eccentric orbit, where the direct
        # forms lose ε/(1 − e).
        h2 = 2.0 * s * s
        u, w = one_minus_e - h2, 2.0 * s * c  # cos E − e, sin E
        cE = 1.0 - h2
        D = one_minus_e + e * h2
        A = [p[f"A[{i}]"] for i in range(3)]
        B = [p[f"B[{i}]"] for i in range(3)]
        y = [u * A[i] + w * B[i] for i in range(3)]
        rate = p["n"] / D  # Ė
        ydot = [rate * (cE * B[i] - w * A[i]) for i in range(3)]
        return y, ydot, {"u": u, "w": w, "D": D, "rate": rate}

    def acceleration(
        self,
        y: Sequence[Expr],
        d: Sequence[Expr],
        parts: dict[str, Expr],
        central: Expr | None = None,
    ) -> list[Expr]:
        """The Kepler part of δ̈, μ/(ρ³S³) (F(q) y − δ) − (n²/D³) F(p) y (Battin), plus
        ``−central (y + δ)`` (the part of ∇Ω along the position, :class:`.disturbing.Gradient`).

        ρ² = |y|² is taken as k²D² − p ρ² (p ρ² = αu² + βw² − 2γuw, computed anyway)
        rather than y·y: exact, and no product of vectors. It must be |y|² to the run's
        precision, not merely to O(p): an error η of ρ² moves F(q) y by ~3η|δ|, which near
        the pericentre of an eccentric orbit is not small against ε times the central force
        (k²D² alone lost 11× at e = 0.99, where p reaches ~10³ ε). And k² is held as two
        parameters, k² and its remainder: k² rounded once is a bias of up to ε/2 in ρ², the
        same at every step (e = 0.5 with J2, 2000 orbits at tolerance 1e-18: 7.2e-14 of a
        against 7.7e-15 with the remainder; the rounding of D², like that of y·y, varies from
        step to step). Also
        ``2 y·δ + δ·δ = (2y + δ)·δ``, ``1 + S + S² = 2 + q + S`` and
        ``ρ³S³ = (ρ² + (2y + δ)·δ)^{3/2}``, one power shared with the disturbing force.
        """
        p, D = self.par, parts["D"]
        if "r2" not in parts:
            self.distance(y, d, parts)
        rho2, N, r2, mismatch = parts["rho2"], parts["N"], parts["r2"], parts["mismatch"]
        q = N / rho2
        S = hy.sqrt(1.0 + q)
        Fq = q * (2.0 + q + S) / (1.0 + S)
        c1 = self.mu * r2**-1.5
        # (n²/D³) F(p) = (3n²/2k²) mismatch / D⁵, κ = 3n²/2k² one parameter.
        c2 = p["kappa"] * mismatch * D**-5.0
        on_y = c1 * Fq - c2
        on_d = c1
        if central is not None:
            on_y, on_d = on_y - central, on_d + central
        return [on_y * y[i] - on_d * d[i] for i in range(3)]

    def distance(self, y: Sequence[Expr], d: Sequence[Expr], parts: dict[str, Expr]) -> Expr:
        """|y + δ|² = ρ² + (2y + δ)·δ, with ρ² = k²D² − p ρ² (:meth:`acceleration`); sets
        ``parts`` ``"mismatch"`` (p ρ²), ``"rho2"``, ``"N"`` and ``"r2"``; returns the last."""
        p, u, w, D = self.par, parts["u"], parts["w"], parts["D"]
        mismatch = p["alpha"] * (u * u) + p["beta"] * (w * w) - 2.0 * p["gamma"] * (u * w)
        parts["mismatch"] = mismatch
        D2 = D * D
        parts["rho2"] = p["k2"] * D2 + (p["k2_lo"] * D2 - mismatch)
        parts["N"] = hy.sum([(2.0 * y[i] + d[i]) * d[i] for i in range(3)])  # 2 y·δ + δ·δ
        parts["r2"] = parts["rho2"] + parts["N"]
        return parts["r2"]

    def event(self, psi: Expr) -> Expr:
        """Zero where ψ reaches the next apocentre, E = π (crossed upwards)."""
        return psi - self.par["next"]

    # --------------------------------------------------------------- rectification
    def anomaly(self, ta: Any, pars: Any) -> Any:
        """The ellipse's eccentric anomaly E = 2ψ at the integrator's state, in the handler's
        extended precision (long double where the rectification is compiled, else mpmath)."""
        if self._compiled:
            return 2 * (_ZERO + ta.state[6])
        return 2 * self.arith.scalar(ta.state[6])

    def __call__(self, ta: Any, pars: Any) -> str | None:
        """Terminal-event handler: rectify on the state reached (δ to round-off, ψ to the new
        ellipse's anomaly)."""
        if self._compiled and _rectify_compiled(self, ta, pars):
            return None
        ar = self.arith
        with ar.context():
            mu = ar.scalar(pars[self._mu_index])
            old = {name: ar.scalar(pars[self.index[name]]) for name in _CURVE}
            st = ta.state
            E = self.anomaly(ta, pars)
            if isinstance(E, np.longdouble):  # a compiled run's rare case (e = 0, unbound)
                E = ar.scalar(float(E)) + ar.scalar(float(E - _LD(float(E))))
            y, ydot = ellipse_state(ar, old, E)
            X = [y[i] + ar.scalar(st[i]) for i in range(3)]
            V = [ydot[i] + ar.scalar(st[3 + i]) for i in range(3)]
            try:
                values, state = _rectify(ar, mu, X, V)
            except Unbound as exc:
                return (
                    f"{exc} at t = {ta.time}: formulation = 'encke' follows an osculating "
                    "ellipse and cannot go on. Results are kept up to here; continue with "
                    "formulation = 'cartesian'"
                )
            for name, value in values.items():
                pars[self.index[name]] = ar.run(value)
            for i, value in enumerate(state):
                st[i] = ar.run(value)
        return None


def start(
    precision: Precision, mu_value: Any, x: Sequence[Any], v: Sequence[Any]
) -> tuple[dict[str, str], list[str]]:
    """Rectify on the initial state (mpmath numbers): the ``encke.*`` parameters' values and
    the initial (δ, ψ), as decimal text.

    Raises
    ------
    Unbound
        The osculating orbit is not an ellipse in the run's precision.
    """
    ar = _MpArithmetic(precision)
    with ar.context():
        X = [ar.exact(c) for c in x]
        V = [ar.exact(c) for c in v]
        values, state = _rectify(ar, ar.scalar(precision.number(mu_value)), X, V)
    return {f"encke.{name}": ar.text(value) for name, value in values.items()}, [
        ar.text(c) for c in state
    ]


# ---------------------------------------------------------------------- extended arithmetic
_LD = np.longdouble
# Adding a float to a long double zero converts it exactly, at a seventh of the cost of
# np.longdouble(value) (~60 ns against ~400 ns).
_ZERO = _LD(0)


class _MpArithmetic:
    """mpmath with the run's bits plus guard bits (quad and multiprecision runs, the initial
    rectification of every run, and a double run's rare case the compiled handler leaves)."""

    pi: Any = None

    def __init__(self, precision: Precision) -> None:
        self.precision = precision
        self.bits = precision.bits
        self.sqrt, self.sin, self.cos, self.atan2 = (
            mpmath.sqrt,
            mpmath.sin,
            mpmath.cos,
            mpmath.atan2,
        )
        self.cbrt = mpmath.cbrt

    def context(self) -> Any:
        return _Workprec(self)

    def positive(self, value: Any) -> bool:
        return value > 0

    @staticmethod
    def ellipse(e: Any, inv_a: Any, h: Any) -> None:
        """Raise :class:`Unbound` unless e < 1, 1/a > 0 and |h| > 0."""
        if not e < 1 or not inv_a > 0 or not h > 0:
            raise Unbound(e)

    def scalar(self, value: Any) -> mpmath.mpf:
        """A number of the run's type, exactly: as a sum of doubles (Sterbenz: each remainder
        ``r − float(r)`` is exact), since its decimal text is only round-trip accurate."""
        if isinstance(value, float | int):
            return mpmath.mpf(value)
        total, rest = mpmath.mpf(0), value
        for _ in range(self.bits // 53 + 3):
            d = float(rest)
            if d == 0.0:
                break
            total += mpmath.mpf(d)
            rest = rest - d
        return total

    def exact(self, value: Any) -> mpmath.mpf:
        return mpmath.mpf(value)

    def rounded(self, value: Any) -> mpmath.mpf:
        """``value`` rounded to the run's precision (nearest), kept as an mpmath number."""
        with mpmath.workprec(self.bits):
            return +value

    def on_unit_grid(self, value: Any) -> mpmath.mpf:
        """``value`` in [0, 1) rounded to a multiple of 2^−bits."""
        return mpmath.ldexp(mpmath.nint(mpmath.ldexp(value, self.bits)), -self.bits)

    def text(self, value: Any) -> str:
        return mpmath.nstr(value, self.precision.dps + 10, strip_zeros=False)

    def run(self, value: Any) -> Any:
        return self.precision.number(self.text(value))


class _Workprec:
    def __init__(self, ar: _MpArithmetic) -> None:
        self.ar = ar
        self._ctx = mpmath.workprec(ar.bits + _GUARD_BITS)

    def __enter__(self) -> None:
        self._ctx.__enter__()
        self.ar.pi = +mpmath.pi

    def __exit__(self, *exc: Any) -> None:
        self._ctx.__exit__(*exc)


def _compiles(precision: Precision) -> bool:
    """A double run's handler is compiled in long double where that is the 80-bit format."""
    return precision.kind == "double" and np.finfo(_LD).nmant >= _LONG_DOUBLE_BITS


# ---------------------------------------------------------------------- the ellipse
def _rectify(ar: Any, mu: Any, X: list, V: list) -> tuple[dict[str, Any], list]:
    """The osculating ellipse of (X, V), its parameters rounded to the run's precision, and
    the state (δ, ψ) = (X − y, V − ẏ, E₀/2) on the curve the rounded parameters define."""
    o = _osculating(ar, mu, X, V)
    E0 = o["E0"]
    if E0 > 3 * ar.pi / 4:
        # Just before apocentre: count from the previous one, so that the next rectification,
        # at E = π, is at least a quarter of the anomaly ahead and the pericentre is at E = 0.
        E0 -= 2 * ar.pi

    out: dict[str, Any] = {}
    # e on the grid of multiples of ε/2, so that 1 − e is exact in the run's precision too.
    out["e"] = ar.on_unit_grid(o["e"])
    if not out["e"] < 1:
        raise Unbound(o["e"])
    out["one_minus_e"] = 1 - out["e"]
    out["n"] = ar.rounded(o["n"])
    for i in range(3):
        out[f"A[{i}]"], out[f"B[{i}]"] = ar.rounded(o["A"][i]), ar.rounded(o["B"][i])
    k2 = ar.cbrt(mu / (out["n"] * out["n"])) ** 2  # k³ = μ/n²
    for name, value in _derived(out, k2).items():
        out[name] = ar.rounded(value)
    out["next"] = ar.rounded(ar.pi / 2)
    out["k2"] = ar.rounded(k2)
    out["k2_lo"] = ar.rounded(k2 - out["k2"])
    psi = ar.rounded(E0 / 2)
    return out, _deviation(ar, out, X, V, 2 * psi) + [psi]


def _osculating(ar: Any, mu: Any, X: Sequence[Any], V: Sequence[Any]) -> dict[str, Any]:
    """The osculating ellipse of (X, V), exact in ``ar``'s arithmetic: e, 1/a, |h|, the axes
    A = a P̂ and B = b Q̂, the eccentric anomaly E₀ (in (−π, π]) and the mean motion n."""
    r = ar.sqrt(dot(X, X))
    v2 = dot(V, V)
    xv = dot(X, V)
    H = vectors.cross(X, V)
    h = ar.sqrt(dot(H, H))
    inv_a = 2 / r - v2 / mu
    ev = [((v2 - mu / r) * X[i] - xv * V[i]) / mu for i in range(3)]
    e = ar.sqrt(dot(ev, ev))
    ar.ellipse(e, inv_a, h)
    a = 1 / inv_a
    # e = 0 exactly leaves the pericentre undefined: any axis of the plane serves.
    circular = not ar.positive(e)
    P = [c / r for c in X] if circular else [c / e for c in ev]
    Q = [c / h for c in vectors.cross(H, P)]
    b = a * ar.sqrt((1 - e) * (1 + e))
    E0 = 0 * e if circular else ar.atan2(xv / ar.sqrt(mu * a), 1 - r / a)
    n = ar.sqrt(mu * inv_a) * inv_a
    return {
        "e": e,
        "inv_a": inv_a,
        "h": h,
        "A": [a * c for c in P],
        "B": [b * c for c in Q],
        "E0": E0,
        "n": n,
    }


def _derived(p: dict[str, Any], k2: Any) -> dict[str, Any]:
    """The parameters that follow from the rounded ``e``, ``n``, A and B (and k² = (μ/n²)^⅔),
    before their own rounding: the mismatch's α, β, γ, n² and κ = 3n²/2k²."""
    A = [p[f"A[{i}]"] for i in range(3)]
    B = [p[f"B[{i}]"] for i in range(3)]
    e, n = p["e"], p["n"]
    return {
        "alpha": k2 - dot(A, A),
        "beta": k2 * (1 - e) * (1 + e) - dot(B, B),
        "gamma": dot(A, B),
        "n2": n * n,
        "kappa": 3 * n * n / (2 * k2),
    }


def _deviation(ar: Any, p: dict[str, Any], X: Sequence[Any], V: Sequence[Any], E: Any) -> list:
    """δ = (X − y, V − ẏ) from the ellipse of the parameters ``p`` at the anomaly E."""
    y, ydot = ellipse_state(ar, p, E)
    return [X[i] - y[i] for i in range(3)] + [V[i] - ydot[i] for i in range(3)]


# ---------------------------------------------------------------------- compiled handler
class _Symbolic:
    """The arithmetic of :func:`_osculating`, :func:`_derived` and :func:`_deviation` on heyoka
    expressions, to compile them (:func:`_rectifiers`)."""

    sqrt, sin, cos, atan2 = hy.sqrt, hy.sin, hy.cos, hy.atan2

    # No branch in compiled code: an orbit that is not an ellipse, or e = 0 exactly, gives
    # values the handler checks, and sends to mpmath (_rectify_compiled).
    @staticmethod
    def positive(value: Any) -> bool:
        return True

    @staticmethod
    def ellipse(e: Any, inv_a: Any, h: Any) -> None:
        return None


@functools.cache
def _rectifiers() -> tuple[Any, Any]:
    """Two functions compiled by heyoka in long double (once a process; heyoka's caches serve
    later builds), the rounding of the new parameters to double between them:

    * ``(E, δ, e, 1 − e, n, A, B, μ) → (X, V, e, 1/a, |h|, A, B, E₀, n, their sum)``: the
      state on the old ellipse and its osculating elements (:func:`ellipse_state`,
      :func:`_osculating`);
    * ``(X, V, ψ, e, 1 − e, n, A, B, k²) → (α, β, γ, n², κ, δ)`` on the rounded ellipse
      (:func:`_derived`, :func:`_deviation`).
    """
    ar = _Symbolic()
    E, psi, k2, mu = hy.make_vars("E", "psi", "k2", "mu")
    d = list(hy.make_vars(*(f"d{i}" for i in range(6))))
    X = list(hy.make_vars(*(f"X{i}" for i in range(6))))
    curve = dict(zip(_CURVE, hy.make_vars(*(f"c{i}" for i in range(len(_CURVE)))), strict=True))
    y, ydot = ellipse_state(ar, curve, E)
    state = [y[i] + d[i] for i in range(3)] + [ydot[i] + d[3 + i] for i in range(3)]
    o = _osculating(ar, mu, state[:3], state[3:])
    first = state + [o["e"], o["inv_a"], o["h"], *o["A"], *o["B"], o["E0"], o["n"]]
    first.append(hy.sum(first))  # finite if all are: one check for the handler
    second = list(_derived(curve, k2).values()) + _deviation(ar, curve, X[:3], X[3:], 2 * psi)
    compile_ = functools.partial(hy.cfunc, fp_type=_LD)
    return (
        compile_(first, [E, *d, *curve.values(), mu]),
        compile_(second, [*X, psi, *curve.values(), k2]),
    )


_PI = np.arccos(_LD(-1))
_GRID = _LD(2.0**53)  # e on the multiples of 2⁻⁵³ (the double ε/2)
#: The parameters the compiled handler sets, in the order it computes them.
_SET = (*_CURVE, "alpha", "beta", "gamma", "n2", "kappa", "k2", "k2_lo")


def _rectify_compiled(enc: Encke, ta: Any, pars: Any) -> bool:
    """:func:`_rectify` of a double run in long double, compiled; False (nothing changed) in
    the cases it leaves to mpmath: an orbit not an ellipse (the error message), e = 0 exactly."""
    first, second = _rectifiers()
    st = ta.state
    args = np.empty(len(_CURVE) + 8, dtype=_LD)  # E, δ, the curve, μ
    args[0] = enc.anomaly(ta, pars)
    args[1:7] = st[:6]
    args[7:-1] = pars[enc._curve_slots]
    args[-1] = mu = _ZERO + pars[enc._mu_index]
    o = first(args)
    e, inv_a, h, E0, finite = o[6], o[7], o[8], o[15], o[17]
    if not (0 < e < 1 and inv_a > 0 and h > 0 and finite - finite == 0):
        return False
    if E0 > 3 * _PI / 4:  # as in _rectify
        E0 -= 2 * _PI
    e = np.rint(e * _GRID) / _GRID  # a multiple of ε/2: 1 − e exact
    if not e < 1:
        return False
    new = np.empty(len(_SET))
    new[0], new[1], new[2] = e, 1 - e, o[16]
    new[3:9] = o[9:15]  # A, B rounded
    n = _ZERO + new[2]
    k = np.cbrt(mu / (n * n))  # k³ = μ/n²
    k2 = k * k
    psi = float(E0 / 2)
    args[:6] = o[:6]  # X, V
    args[6] = psi
    args[7:16] = new[:9]
    args[16] = k2
    o2 = second(args)
    new[9:14] = o2[:5]
    new[14] = k2
    new[15] = k2 - (_ZERO + new[14])
    pars[enc._set_slots] = new
    st[:6] = o2[5:]
    st[6] = psi
    return True


def ellipse_state(ar: Any, p: dict[str, Any], E: Any) -> tuple[list, list]:
    """y and ẏ at the anomaly E, of the parameters ``p`` (exact values), in extended
    precision, by the formulas of :meth:`Encke.curve`."""
    s, c = ar.sin(E / 2), ar.cos(E / 2)
    h2 = 2 * s * s
    u, w, cE = p["one_minus_e"] - h2, 2 * s * c, 1 - h2
    rate = p["n"] / (p["one_minus_e"] + p["e"] * h2)
    y = [u * p[f"A[{i}]"] + w * p[f"B[{i}]"] for i in range(3)]
    ydot = [rate * (cE * p[f"B[{i}]"] - w * p[f"A[{i}]"]) for i in range(3)]
    return y, ydot
