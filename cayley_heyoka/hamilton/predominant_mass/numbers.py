"""The numbers of a predominant-mass model, and the structure they fill.

:func:`numbers` is the one place the numbers of a ``model = "predominant_mass"`` model are
computed — the coefficients of the equations (:meth:`.equations.Coefficients.values`: G M mᵢ,
1/(2mᵢ), √(G(M + mᵢ)), …), the starting state (ξ, p, or Hamilton's elements at the start
time and their offsets), and the check that the run's precision tells the bodies apart — so
that :func:`cayley_heyoka.hamilton.predominant_mass.model.build_model` and a scene of an
already built structure (:mod:`cayley_heyoka.core.structures`) take the same values.
:func:`masked` names what the build compiles: every number of the system is a parameter or an
initial value, so only the shape of the scene is kept (the formulation, how many bodies, and
whether each is given by elements or by position and velocity).
"""

from __future__ import annotations

from typing import Any

import mpmath

from ...core.errors import SceneError
from ...core.model import Numbers
from ...core.precision import Number, Precision, scene_mpf
from ...core.scene import Scene
from ..outputs import wants_principal_function
from ..scene import Hamiltonian
from . import equations as pe
from . import system as planets

#: Digits beyond the run's precision of the starting state computed in mpmath.
GUARD_DIGITS = 15
_MASK = "#"


def masked(table: dict[str, Any]) -> dict[str, Any]:
    """The ``[hamiltonian]`` table of a predominant-mass scene with its numbers masked."""
    table = dict(table)
    for key in ("G", "central_mass"):
        if key in table:
            table[key] = _MASK
    bodies = table.get("bodies")
    if isinstance(bodies, list):
        table["bodies"] = [_mask(body) for body in bodies]
    return table


def _mask(value: Any) -> Any:
    """``value`` with every leaf masked, its tables' keys and its lists' lengths kept."""
    if isinstance(value, dict):
        return {k: _mask(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_mask(v) for v in value]
    return _MASK


def numbers(scene: Scene) -> Numbers:
    """The initial state and every parameter value of a predominant-mass scene's model.

    Raises
    ------
    SceneError
        Bodies closer than the run's precision resolves (``hamiltonian.bodies[k]``), a state
        Hamilton's elements cannot describe, a number the precision cannot hold.
    """
    ham: Hamiltonian = scene.model
    prec = scene.integrator.precision
    G, M = ham.constants["G"], ham.constants["central_mass"]
    c = pe.Coefficients(G, M, [b.mass for b in ham.bodies], None, prec)
    values: dict[str, Any] = c.values(ham.form.elements)
    dps = prec.dps + GUARD_DIGITS
    with mpmath.workdps(dps):
        states = [body.state(M, G) for body in ham.bodies]
    initial = initial_state(ham, _start_time(scene), dps, states)
    if ham.form.elements:
        # The state holds the offsets δz = z − z₀ (model._offsets): z₀ are parameters.
        names = start_names(len(ham.bodies))
        values |= dict(zip(names, initial, strict=True))
        initial = ["0"] * len(initial)
    if wants_principal_function(scene):
        initial.append("0")
    _check_apart(states, prec)
    return Numbers([prec.number(v) for v in initial], values)


def start_names(count: int) -> list[str]:
    """The parameters holding the elements z₀ at the start time, in the order of the state."""
    return [f"predominant_mass.{e}{i + 1}_start" for i in range(count) for e in pe.ELEMENTS]


def _check_apart(states: list[tuple[list, list]], precision: Precision) -> None:
    """Refuse bodies apart in the scene (its check is exact) but closer than the run's
    precision resolves their positions (``states``: (ξ, x′) of every body, computed with
    :data:`GUARD_DIGITS`): their distance would round to 0 or to its rounding error, and H is
    singular there."""
    with mpmath.workdps(precision.dps + GUARD_DIGITS):
        points = [x for x, _ in states]
        resolution = mpmath.mpf(2) ** (1 - precision.bits)
        for k, x in enumerate(points):
            for i in range(k):
                d = mpmath.norm([a - b for a, b in zip(x, points[i], strict=True)])
                scale = max(mpmath.norm(x), mpmath.norm(points[i]))
                if d <= resolution * scale:
                    raise SceneError(
                        f"hamiltonian.bodies[{k}]",
                        f"starts {mpmath.nstr(d, 3)} from hamiltonian.bodies[{i}], within "
                        f"{precision.name}'s rounding of their positions: H is singular where "
                        "they meet; move them apart or choose a wider precision",
                    )


def initial_state(
    ham: Hamiltonian, t: Number, dps: int, states: list[tuple[list, list]] | None = None
) -> list[str]:
    """The formulation's state at the start time ``t`` as decimal text with ``dps`` digits
    (from ``states``, (ξ, x′) of every body computed with ``dps`` digits, when given).

    canonical: ξ of every body, then pᵢ = mᵢx′ᵢ; elements: (μ, τ, ϖ, λ, χ, ν) of every body,
    by the reverse conversion of §8.3 (:func:`.system.hamilton_elements`). Computed in mpmath
    from the scene's exact numbers, so a real128 or multiprecision run starts exactly.
    """
    with mpmath.workdps(dps):
        G, M = scene_mpf(ham.constants["G"]), scene_mpf(ham.constants["central_mass"])
        if states is None:
            states = [
                body.state(ham.constants["central_mass"], ham.constants["G"]) for body in ham.bodies
            ]
        if ham.form.elements:
            values = []
            for k, (body, (x, xp)) in enumerate(zip(ham.bodies, states, strict=True)):
                try:
                    z = planets.hamilton_elements(x, xp, scene_mpf(t), scene_mpf(body.mass), M, G)
                except ValueError as exc:  # the scene's checks refuse these first
                    raise SceneError(f"hamiltonian.bodies[{k}]", str(exc)) from None
                values += list(z.as_tuple())
        else:
            values = [v for x, _ in states for v in x]
            values += [
                scene_mpf(b.mass) * v
                for b, (_, xp) in zip(ham.bodies, states, strict=True)
                for v in xp
            ]
        return [mpmath.nstr(v, dps, strip_zeros=False) for v in values]


def _start_time(scene: Scene) -> Number:
    out = scene.output
    return out.times[0] if out.times is not None else out.grid[0]
