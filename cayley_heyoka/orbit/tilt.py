"""Cayley's angles near Φ = 0 and π: the hand-over to a tilted working frame and back.

Near the reference plane Θ and Σ are ill-defined and their equations carry cosec Φ
(docs/orbits.md, "Near-equatorial orbits"). Where sin Φ falls to ε/2, ε =
``orbit.equatorial_limit`` (not ε itself: the tilted stretch then starts clear of the
``equatorial`` event's zero, which a root search starting on it missed with the next one), a
terminal event hands the run over to a *working frame* W tilted by a quarter turn about the
reference plane's x₁ axis, ``W = R₁(β)`` with ``(cos β, sin β) = (c, s)`` held in runtime
parameters: the same equations, with Θ, Σ, Φ the angles of the orbit plane on W's xy-plane,
where the orbit is nearly perpendicular to it (sin Φ_W ≥ √(1 − 4ε²)). Where sin Φ on the
reference plane rises back to 2ε, a second event hands it back. The two thresholds differ so
that a plane hovering near ε does not switch at every step.

Each stretch compiles only what it needs (:class:`cayley_heyoka.core.model.Handover`): the run
starts with Cayley's equations on the reference plane, and the tilted variant is compiled the
first time a run reaches ε/2. Tilted, W's axes enter the equations (``R₁(β)`` on the orbit's
axes, and the reference plane's angular velocity A, B, C referred to W), which costs 1.25–1.35×
per step of the untilted equations with J₂ alone (``step_cost`` in
validation/orbit_passage.py); the untilted variant keeps its own code. Outputs, monitors and
events are the same expressions in both, of the parameters (c, s): ``x`` … ``vz``, ρ, h, r and
Φ stay continuous across a hand-over; Θ and Σ, which the tilted state does not carry on the
reference plane, are NaN there (``c/c``: 1 untilted, 0/0 tilted).
Back on the reference plane they resume within a whole turn of their values before the tilt,
a passage through Φ = 0 counted as a turn of Θ by +π (:func:`resumed`).

The hand-over itself is computed in mpmath at the run's precision plus guard digits, from the
state's round-trip text (finite: a state gone NaN stops the run before any event), and rounded
once into the run's type: it happens once per passage.
"""

from __future__ import annotations

from typing import Any

import mpmath

from ..core.model import Handover, ParTable
from ..core.precision import Precision
from ..mechanics import frames

#: The variants of a Cayley model: on the reference plane, and on the tilted working frame.
LEVEL, TILTED = "cayley", "tilted"
#: The frame of each variant: (cos β, sin β).
FRAME = {LEVEL: ("1", "0"), TILTED: ("0", "1")}
#: Where the state sits in Cayley's (r, ṙ, ρ, h, Θ, Σ, Φ).
_ANGLES = slice(4, 7)


def on_reference(v: list[Any], c: Any, s: Any) -> list[Any]:
    """``R₁(β) v``: components on W → components on the reference plane's frame 1."""
    return [v[0], c * v[1] - s * v[2], s * v[1] + c * v[2]]


def angles_of(M: list[list[Any]]) -> tuple[Any, Any, Any]:
    """Θ, Σ, Φ of the orbit frame ``M`` (sin Φ > 0), in mpmath."""
    Theta = mpmath.atan2(M[0][2], -M[1][2])
    Phi = mpmath.atan2(mpmath.hypot(M[0][2], M[1][2]), M[2][2])
    Sigma = mpmath.atan2(-M[2][0], M[2][1])
    return Theta, Sigma, Phi


def angles_in(frame: str, Theta: Any, Sigma: Any, Phi: Any, current: str = LEVEL) -> tuple:
    """Θ, Σ, Φ given on the ``current`` frame, referred to ``frame`` (mpmath)."""
    c0, s0 = (mpmath.mpf(v) for v in FRAME[current])
    c1, s1 = (mpmath.mpf(v) for v in FRAME[frame])
    M = frames.plane_matrix(Theta, Sigma, Phi)  # R₃(Θ) R₁(Φ) R₃(−Σ): the orbit frame
    on_plane = [on_reference([M[0][j], M[1][j], M[2][j]], c0, s0) for j in range(3)]
    # R₁(β₁)ᵀ: the inverse tilt, applied to each column.
    back = [on_reference(col, c1, -s1) for col in on_plane]
    return angles_of([[back[j][i] for j in range(3)] for i in range(3)])


class EquatorialHandover:
    """Terminal-event handler: refer Θ, Σ, Φ to the other working frame and hand over.

    Parameters
    ----------
    to
        The variant the run goes on with (:data:`LEVEL` or :data:`TILTED`).
    pars
        The model's parameter table, holding ``orbit.frame_cos``, ``orbit.frame_sin`` and Θ, Σ
        before the tilt (``orbit.theta_before``, ``orbit.sigma_before``).
    precision
        The run's precision.
    """

    def __init__(self, to: str, pars: ParTable, precision: Precision) -> None:
        self.to = to
        self.precision = precision
        self._frame = pars.index("orbit.frame_cos")
        self._before = pars.index("orbit.theta_before")

    def __call__(self, ta: Any, pars: Any) -> Handover:
        prec = self.precision
        state = ta.state
        with mpmath.workdps(prec.dps + 20):
            Theta, Sigma, Phi = (mpmath.mpf(t) for t in prec.to_text(state[_ANGLES]))
            current = LEVEL if self.to == TILTED else TILTED
            new = list(angles_in(self.to, Theta, Sigma, Phi, current))
            j = self._before
            if self.to == TILTED:
                values = [Theta, Sigma]
            else:
                before = [mpmath.mpf(t) for t in prec.to_text(pars[j : j + 2])]
                new[0], new[1] = resumed(before, new)
                values = before
            texts = [mpmath.nstr(v, prec.dps + 20, strip_zeros=False) for v in new]
            kept = [mpmath.nstr(v, prec.dps + 20, strip_zeros=False) for v in values]
        k = _ANGLES.start
        for i, text in enumerate(texts):
            state[k + i] = prec.number(text)
        c, s = FRAME[self.to]
        pars[self._frame], pars[self._frame + 1] = prec.number(c), prec.number(s)
        pars[j], pars[j + 1] = prec.number(kept[0]), prec.number(kept[1])
        return Handover(self.to)


def resumed(before: list[Any], new: list[Any]) -> tuple[Any, Any]:
    """Θ, Σ back on the reference plane (``new``: Θ, Σ, Φ there, any turn) within a turn of
    their values ``before`` the tilt (mpmath, at the working precision).

    Passing through Φ = 0 turns the node by about π (only Θ − Σ is continuous; through
    Φ = π only Θ + Σ), an approach that does not pass through it by little. Read as the
    nearest turn, a passage would be a tie between +π and −π that the round-off of each run
    decides (a double and a quad run would then differ by 2π). So each change is taken in
    (−π/2, 3π/2]: a passage turns Θ by +π, an approach by its small change; Σ's change is
    taken in the same window prograde (Θ − Σ continuous) and in the mirrored one, (−3π/2,
    π/2], retrograde (Θ + Σ continuous).
    """
    pi = mpmath.pi
    retrograde = new[2] > pi / 2
    lows = (-pi / 2, -3 * pi / 2 if retrograde else -pi / 2)
    out = []
    for b, n, low in zip(before, new[:2], lows, strict=True):
        change = n - b
        change += 2 * pi * mpmath.floor((low + 2 * pi - change) / (2 * pi))
        out.append(b + change)
    return out[0], out[1]


def reference_normal(Theta: Any, Phi: Any, c: Any, s: Any) -> list[Any]:
    """The orbit normal on frame 1 from the angles on W (expressions)."""
    f = frames.functions_for(Theta, Phi)
    n = [f.sin(Theta) * f.sin(Phi), -f.cos(Theta) * f.sin(Phi), f.cos(Phi)]
    return on_reference(n, c, s)


def sin2_on_reference(Theta: Any, Phi: Any, c: Any, s: Any) -> Any:
    """sin²Φ on the reference plane: the squared length of the normal's part in it."""
    n = reference_normal(Theta, Phi, c, s)
    return n[0] * n[0] + n[1] * n[1]
