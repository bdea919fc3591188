"""The whole attitude of a reduced body: the azimuth about the forces' direction, by quadrature.

The Euler–Poisson reduction (:mod:`.poisson`) integrates the rates and ``γ = Rᵀu``, the body
components of the one space direction ``u`` the forces see. The attitude is γ and one angle
about u, which the forces do not feel: with ``output.azimuth = true`` it is integrated beside
them by quadrature, as the azimuth ``φ`` of the horizontal projection of a body axis ``e``,
measured from a space axis X ⊥ u towards ``Y = u × X`` (X: that projection at the start, so
that φ(0) = 0)::

    dφ/dt = (γ·ω − (γ·e)(e·ω)) / (|γ|² − (γ·e)²)

(the rate of ``R e``'s azimuth, ``u·(s × ṡ)/|s_h|²`` with ``s = R e``, in body components).
It is singular where ``e`` is along ``u``: ``e`` is body x or body z, held in runtime
parameters as weights ``(a, b)`` of ``e₁`` and ``e₃``, and where ``(γ·e)² = κ²|γ|²``
(κ = 9/10) a terminal event switches to the other axis. φ then changes by the angle about γ
from the one axis' projection on the plane ⊥ γ to the other's, a function of γ alone
(a rotation about u turns both projections alike). The other axis is then far from u
(|γ·e| ≤ √(1 − κ²) ≈ 0.44), so the charts never switch back at once.

As Ψ (:mod:`.invariable_angle`), φ is kept small for heyoka's error control: the state is
``s = (φ − nC)/8`` with ``C`` = 2π in the run's precision and ``nC`` (exact) in a parameter;
a terminal event at ``|s| = C/8`` moves a turn. The attitude reported is

    R = P S(φ) Bᵀ,   P = [X Y u],   S(φ) = R₃(φ),   B = [b₁, γ × b₁, γ],
    b₁ = (e − (γ·e)γ) / |e − (γ·e)γ|

(B's columns are the body vectors that R carries to the horizontal direction of azimuth φ,
its perpendicular and u), as ``qw ≥ 0, qx, qy, qz`` (Shepperd's choice of the largest
diagonal term, by heyoka's ``select``) and λ, μ, ν = (qx, qy, qz)/qw. The azimuth feeds
nothing back into the rates and γ; they change only at round-off, heyoka choosing its steps for
every variable. Those steps are more than the quaternion formulation's (validation/POISSON.md):
a body axis' azimuth turns at up to the whole rate, where the quaternion turns at half of it,
and 1/(|γ|² − (γ·e)²) bounds the step near the switching cone; the chart is therefore the axis
whose azimuth turns slowest, among those well inside the cone.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from fractions import Fraction
from typing import Any

import heyoka as hy
import mpmath

from ..core.errors import SceneError
from ..core.exact import exact, exact_array
from ..core.model import ParTable, TerminalSpec
from ..core.precision import Precision, two_pi_parts
from . import attitude as att
from .formulations import Formulation

Expr = Any  # a heyoka expression
#: s = (φ − nC)/SCALE: a power of two, so that the scaling is exact.
SCALE = 8
#: The charts switch where |γ·e| reaches κ|γ|.
KAPPA = "0.9"
#: A chart is chosen only where |γ·e| < κ₀|γ|: never at once beside its switching cone.
KAPPA_START = 0.8


def wanted(options: dict[str, Any], formulation: Formulation) -> bool:
    """Whether the scene's ``output.azimuth`` asks for the attitude of a reduced body (one
    whose ``formulation`` is :attr:`~.formulations.Formulation.reduced`)."""
    value = options.get("azimuth", False)
    if not isinstance(value, bool):
        raise SceneError("output.azimuth", f"must be true or false, got {value!r}")
    if value and not formulation.reduced:
        raise SceneError(
            "output.azimuth",
            f"completes the attitude of formulation = 'poisson'; {formulation.name!r} reports "
            "it already (qw … qz, lambda, mu, nu)",
        )
    return value


class Azimuth:
    """The state ``s``, its equation, the charts, the turns and the attitude outputs.

    Parameters
    ----------
    pars
        The model's parameters; ``azimuth.*`` are allocated in it.
    precision
        The run's precision.
    u
        The forces' direction (unit, in the run's precision).
    q0
        The initial attitude (unit quaternion, in the run's precision).
    gamma0, rates0
        γ and the rates at the start (the reduced scene's initial state).
    state_index
        Position of ``s`` in the integrator's state; γ sits at ``gamma_index`` … + 2.
    """

    def __init__(
        self,
        pars: ParTable,
        precision: Precision,
        u: Sequence[Any],
        values: Mapping[str, Any],
        state_index: int,
        gamma_index: int,
    ) -> None:
        self.precision = precision
        self.state_index, self.gamma_index = state_index, gamma_index
        self._C, self._step = _two_pi(precision)
        self.e = [pars.add(f"azimuth.e{i + 1}", values[f"azimuth.e{i + 1}"]) for i in range(3)]
        self.bound = pars.add("azimuth.two_pi_scaled", values["azimuth.two_pi_scaled"])
        self.turns = pars.add("azimuth.turns", values["azimuth.turns"])
        self.X = [pars.add(f"azimuth.X[{i}]", values[f"azimuth.X[{i}]"]) for i in range(3)]
        self.Y = [pars.add(f"azimuth.Y[{i}]", values[f"azimuth.Y[{i}]"]) for i in range(3)]
        self.u = [hy.expression(precision.number(c)) for c in u]
        self._kappa2 = pars.constant(Fraction(KAPPA) ** 2)
        self._scale = pars.constant(SCALE)
        self._index = pars.index("azimuth.e1")
        self._turns_index = pars.index("azimuth.turns")

    # ------------------------------------------------------------------ equations
    def rhs(self, gamma: Sequence[Expr], rates: Sequence[Expr]) -> Expr:
        """ds/dt = dφ/dt / SCALE."""
        along, spin = _dot(self.e, gamma), _dot(self.e, rates)
        vertical = _dot(gamma, rates)
        return (vertical - along * spin) / (self._scale * (_dot(gamma, gamma) - along * along))

    def phi(self, s: Expr) -> Expr:
        """The azimuth of the current chart's axis."""
        return self._scale * s + self.turns

    def attitude(self, s: Expr, gamma: Sequence[Expr]) -> dict[str, Expr]:
        """qw ≥ 0, qx, qy, qz and λ, μ, ν of R = P S(φ) Bᵀ."""
        phi = self.phi(s)
        c, sn = hy.cos(phi), hy.sin(phi)
        e = self.e
        along = _dot(e, gamma)
        n2 = _dot(gamma, gamma)
        p = [e[i] - along * gamma[i] / n2 for i in range(3)]
        norm = hy.sqrt(_dot(p, p))
        b1 = [x / norm for x in p]
        gamma_unit = [x / hy.sqrt(n2) for x in gamma]
        b2 = _cross(gamma_unit, b1)
        # Space images of b₁, b₂, γ: the horizontal direction of azimuth φ, its perpendicular,
        # u; R = Σ image ⊗ b.
        S1 = [c * self.X[i] + sn * self.Y[i] for i in range(3)]
        S2 = [c * self.Y[i] - sn * self.X[i] for i in range(3)]
        R = [
            [S1[i] * b1[j] + S2[i] * b2[j] + self.u[i] * gamma_unit[j] for j in range(3)]
            for i in range(3)
        ]
        q = _quaternion_of(R, self.precision)
        out = dict(zip(("qw", "qx", "qy", "qz"), q, strict=True))
        out.update(zip(("lambda", "mu", "nu"), [x / q[0] for x in q[1:]], strict=True))
        return out

    def terminal(self, s: Expr, gamma: Sequence[Expr]) -> list[TerminalSpec]:
        """The chart switch and the turn."""
        along = _dot(self.e, gamma)
        chart = along * along - self._kappa2 * _dot(gamma, gamma)
        turn = s * s - self.bound * self.bound
        return [
            TerminalSpec(chart, 1, self.switch, "azimuth_charts"),
            TerminalSpec(turn, 1, self.turn, "azimuth_turns"),
        ]

    # ------------------------------------------------------------------ handlers
    def turn(self, ta: Any, pars: Any) -> None:
        """Move one turn of φ from the state into the parameters (exactly)."""
        k = self.state_index
        forwards = ta.state[k] > 0
        if forwards:
            ta.state[k] -= self._step
        else:
            ta.state[k] += self._step
        n = self._turns(pars) + (1 if forwards else -1)
        mc, ec = self._C
        pars[self._turns_index] = self.precision.dyadic(n * mc, ec)

    def switch(self, ta: Any, pars: Any) -> None:
        """Go over to the other body axis: φ plus the angle about γ between the projections."""
        prec = self.precision
        k, j = self.state_index, self.gamma_index
        with mpmath.workdps(prec.dps + 20):
            g = _mp(prec, ta.state[j : j + 3])
            s = exact(ta.state[k])
            n = self._turns(pars)
            mc, ec = self._C
            C = mpmath.ldexp(mc, ec)
            phi = SCALE * s + n * C
            current = next(i for i in range(3) if pars[self._index + i] != 0)
            axis = _chart(g, _mp(prec, ta.state[0:3]))
            old = [int(i == current) for i in range(3)]
            new = [int(i == axis) for i in range(3)]
            g2 = _dot(g, g)
            p_old = [old[i] - _dot(old, g) * g[i] / g2 for i in range(3)]
            p_new = [new[i] - _dot(new, g) * g[i] / g2 for i in range(3)]
            turn = mpmath.atan2(_dot(g, _cross(p_old, p_new)) / mpmath.sqrt(g2), _dot(p_old, p_new))
            phi += turn
            n = int(mpmath.nint(phi / C))
            s_text = mpmath.nstr((phi - n * C) / SCALE, prec.dps + 20, strip_zeros=False)
        ta.state[k] = prec.number(s_text)
        pars[self._turns_index] = prec.dyadic(n * mc, ec)
        one, zero = prec.number(1), prec.number(0)
        for i in range(3):
            pars[self._index + i] = one if i == axis else zero

    def _turns(self, pars: Any) -> int:
        """n from the parameter nC (exact: an integer times C)."""
        mc, ec = self._C
        value = exact(pars[self._turns_index])
        with mpmath.workprec(self.precision.bits + 64):
            return int(mpmath.nint(value / mpmath.ldexp(mc, ec)))


def values(
    precision: Precision,
    u: Sequence[Any],
    q0: Sequence[Any],
    gamma0: Sequence[Any],
    rates0: Sequence[Any],
) -> dict[str, Any]:
    """The azimuth's parameters at the start: the first chart's axis (the body axis farthest
    from γ), the horizontal frame X, Y its azimuth is measured in, no turn yet.

    ``u`` is the forces' direction, ``q0`` the initial attitude, ``gamma0`` and ``rates0`` γ
    and the rates at the start (all in the run's precision).
    """
    dps = precision.dps + 20
    with mpmath.workdps(dps):
        g = _mp(precision, gamma0)
        k = _chart(g, _mp(precision, rates0))
        e = [int(i == k) for i in range(3)]
        R0 = att.quaternion_to_matrix(_mp(precision, q0))
        uu = _mp(precision, u)
        s = [sum(R0[i][j] * e[j] for j in range(3)) for i in range(3)]
        along = _dot(s, uu)
        h = [s[i] - along * uu[i] for i in range(3)]
        norm = mpmath.sqrt(_dot(h, h))
        X = [c / norm for c in h]
        Y = _cross(uu, X)
        texts = {
            "X": [mpmath.nstr(c, dps, strip_zeros=False) for c in X],
            "Y": [mpmath.nstr(c, dps, strip_zeros=False) for c in Y],
        }
    one, zero = precision.number(1), precision.number(0)
    out = {f"azimuth.e{i + 1}": one if i == k else zero for i in range(3)}
    out["azimuth.two_pi_scaled"] = _two_pi(precision)[1]
    out["azimuth.turns"] = precision.dyadic(0, 0)
    out |= {f"azimuth.X[{i}]": texts["X"][i] for i in range(3)}
    out |= {f"azimuth.Y[{i}]": texts["Y"][i] for i in range(3)}
    return out


def _two_pi(precision: Precision) -> tuple[tuple[int, int], Any]:
    """C = 2π in the run's precision as (mantissa, exponent), and C/8 = C/SCALE (exact)."""
    mc, ec = C = two_pi_parts(precision)
    return C, precision.dyadic(mc, ec - 3)


def _quaternion_of(R: list[list[Expr]], precision: Precision) -> list[Expr]:
    """The unit quaternion (w ≥ 0) of a rotation matrix, from its largest diagonal term
    (Shepperd 1978): every candidate is computed, ``select`` keeps the well-conditioned one."""
    one = hy.expression(precision.number(1))
    quarter = hy.expression(precision.number("0.25"))
    half = hy.expression(precision.number("0.5"))
    t = R[0][0] + R[1][1] + R[2][2]
    d = [R[2][1] - R[1][2], R[0][2] - R[2][0], R[1][0] - R[0][1]]
    s = [R[0][1] + R[1][0], R[0][2] + R[2][0], R[1][2] + R[2][1]]
    w = half * hy.sqrt(one + t)
    x = half * hy.sqrt(one + R[0][0] - R[1][1] - R[2][2])
    y = half * hy.sqrt(one - R[0][0] + R[1][1] - R[2][2])
    z = half * hy.sqrt(one - R[0][0] - R[1][1] + R[2][2])
    candidates = [
        [w, quarter * d[0] / w, quarter * d[1] / w, quarter * d[2] / w],
        [quarter * d[0] / x, x, quarter * s[0] / x, quarter * s[1] / x],
        [quarter * d[1] / y, quarter * s[0] / y, y, quarter * s[2] / y],
        [quarter * d[2] / z, quarter * s[1] / z, quarter * s[2] / z, z],
    ]
    keys = [t, R[0][0], R[1][1], R[2][2]]

    def pick(i: int, j: int) -> tuple[Expr, list[Expr]]:
        better = hy.gt(keys[j], keys[i])
        return (
            hy.select(better, keys[j], keys[i]),
            [hy.select(better, a, b) for a, b in zip(candidates[j], candidates[i], strict=True)],
        )

    k01, q01 = pick(0, 1)
    k23, q23 = pick(2, 3)
    better = hy.gt(k23, k01)
    q = [hy.select(better, a, b) for a, b in zip(q23, q01, strict=True)]
    sign = hy.select(hy.lt(q[0], hy.expression(precision.number(0))), -one, one)
    return [sign * c for c in q]


def _chart(gamma: Sequence[Any], rates: Sequence[Any]) -> int:
    """The body axis whose azimuth turns slowest, among those well inside the switching cone
    (|γᵢ| < κ₀|γ|): a fast top's spin axis precesses slowly while the axes across it spin, and
    the rate's Taylor coefficients set heyoka's step."""
    g2 = _dot(gamma, gamma)
    vertical = _dot(gamma, rates)
    inside = [i for i in range(3) if gamma[i] ** 2 < KAPPA_START**2 * g2]
    return min(inside, key=lambda i: abs((vertical - gamma[i] * rates[i]) / (g2 - gamma[i] ** 2)))


def _mp(precision: Precision, values: Sequence[Any]) -> list[Any]:
    """Numbers of the run's type as mpmath numbers, exactly."""
    return exact_array(precision.array(list(values)))


def _dot(a: Sequence[Any], b: Sequence[Any]) -> Any:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _cross(a: Sequence[Any], b: Sequence[Any]) -> list[Any]:
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
