"""Build the heyoka system of a ``model = "predominant_mass"`` scene, in either formulation.

* ``canonical``: the state is ξᵢ (``x1, y1, z1, …``) and pᵢ = mᵢx′ᵢ (``px1, …``), integrated
  by the canonical equations of H (F2.) (:func:`.equations.canonical_system`);
* ``elements``: the state is Hamilton's elements ``mu1, tau1, varpi1, lambda1, chi1, nu1, …``
  of every body, integrated by (S2.) from one H₂ (:func:`.equations.element_system`);
  ξ and x′ are reported through the undisturbed motion.

Results carry ξᵢ as ``x1, y1, z1`` and the centrobaric velocity x′ᵢ as ``vx1, vy1, vz1`` in
both; the monitors are H (F2.) (``energy``) and Σ ξᵢ × pᵢ (``angular_momentum``), both
conserved; ``output.principal_function`` adds S = ∫ (T + U) dt.
"""

from __future__ import annotations

import re
from typing import Any

import heyoka as hy
import mpmath

from ...core.errors import SceneError
from ...core.model import Model, ParTable
from ...core.precision import Number, Precision, scene_mpf
from ...core.scene import Scene
from ..outputs import select_monitors, user_events, wants_principal_function
from ..scene import Hamiltonian
from . import equations as pe
from . import system as planets

_GUARD_DIGITS = 15
# Compiled without compact mode, the element equations (Kepler's equation and the gradient of
# H₂ through it) take ~25 s for two bodies against ~1 s in compact mode, at the same step
# cost; the canonical equations take 0.5 / 1.9 / 4.2 s for 2 / 3 / 4 bodies (12 s for 6) and
# step 1.3–2× faster than in compact mode, so they switch at 5 bodies.
_COMPACT_BODIES = 5
_AXES = ("x", "y", "z")


def build_model(scene: Scene) -> Model:
    """Turn a validated predominant-mass scene into a :class:`~cayley_heyoka.core.model.Model`."""
    ham: Hamiltonian = scene.model
    prec = scene.integrator.precision
    n = len(ham.bodies)
    pars = ParTable(prec)
    c = pe.Coefficients(
        ham.constants["G"], ham.constants["central_mass"], [b.mass for b in ham.bodies], pars, prec
    )
    initial = initial_state(ham, _start_time(scene), prec.dps + _GUARD_DIGITS)
    outputs: dict[str, Any] = {}
    if ham.formulation == "canonical":
        xi = [list(hy.make_vars(*(f"{a}{i + 1}" for a in _AXES))) for i in range(n)]
        p = [list(hy.make_vars(*(f"p{a}{i + 1}" for a in _AXES))) for i in range(n)]
        system = pe.canonical_system(xi, p, c)
        xprime = [[q * c.inverse_mass(i) for q in p[i]] for i in range(n)]
    else:
        z = [list(hy.make_vars(*(f"{e}{i + 1}" for e in pe.ELEMENTS))) for i in range(n)]
        system = pe.element_system(z, c)
        states = [pe.state_from_elements(zi, i, c) for i, zi in enumerate(z)]
        xi = [s[0] for s in states]
        xprime = [s[1] for s in states]
        p = [[c.mass(i) * v for v in xprime[i]] for i in range(n)]
        outputs |= {str(v): v for zi in z for v in zi}
    for i in range(n):
        outputs |= {f"{a}{i + 1}": x for a, x in zip(_AXES, xi[i], strict=True)}
        outputs |= {f"v{a}{i + 1}": v for a, v in zip(_AXES, xprime[i], strict=True)}
    H = pe.hamiltonian(xi, p, c)
    monitors: dict[str, Any] = {"energy": H, "angular_momentum": pe.angular_momentum(xi, p)}
    if wants_principal_function(scene):
        # S' = Σ p·ξ̇ − H = 2T − H = T + U, since ξ̇ = ∂H/∂p = p/m + Σp/M.
        S = hy.make_vars("S")
        system.append((S, 2.0 * pe.kinetic_energy(p, c) - H))
        outputs["S"] = S
    if ham.formulation == "elements":
        system, outputs, monitors, initial = _offsets(system, outputs, monitors, initial, pars)
    if "S" in outputs:
        initial.append("0")
    monitors, conserved = select_monitors(scene, monitors, ("energy", "angular_momentum"))
    events = user_events(scene, outputs, pars)
    _check_apart(ham, prec)
    model = Model(
        "hamiltonian",
        system,
        [prec.number(v) for v in initial],
        pars,
        outputs,
        monitors,
        conserved,
        events,
        compact=ham.formulation == "elements" or n >= _COMPACT_BODIES,
    )
    _provenance(model)
    return model


def _check_apart(ham: Hamiltonian, precision: Precision) -> None:
    """Refuse bodies apart in the scene (its check is exact) but closer than the run's
    precision resolves their positions: their distance would round to 0 or to its rounding
    error, and H is singular there."""
    with mpmath.workdps(precision.dps + _GUARD_DIGITS):
        G, M = ham.constants["G"], ham.constants["central_mass"]
        points = [body.state(M, G)[0] for body in ham.bodies]
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


def _provenance(model: Model) -> None:
    """The scene fields of the state (each body's variables come from its table) and of the
    parameters (:meth:`Model.initial_field`, :attr:`ParTable.fields`)."""

    def body(name: str) -> str | None:
        digits = re.search(r"(\d+)(?:_start)?$", name)
        return f"hamiltonian.bodies[{int(digits.group(1)) - 1}]" if digits else None

    model.initial_fields = {v: body(v) or "output.principal_function" for v in model.state_names}
    pars = model.pars
    for i, name in enumerate(pars.names):
        if pars.fields[i] is None and name.startswith("predominant_mass."):
            start = body(name) if name.endswith("_start") else None
            pars.fields[i] = start or "hamiltonian.G, hamiltonian.central_mass, hamiltonian.bodies"


def _offsets(system: list, outputs: dict, monitors: dict, initial: list[str], pars: ParTable):
    """Integrate the elements' offsets δz = z − z₀ from their start values z₀ (parameters).

    The elements move by O(m/M) about z₀: a state holding z itself is rounded to ε|z| at every
    step, a walk of ε√steps that τ and μ turn into a drift of the phase; holding δz rounds to
    ε|δz|, O(m/M) of that. (Measured on N5 against z in the state: the position error 5×
    smaller at 100 orbits, 3× at 1000, where the rounding of the mean anomaly n(t − τ) takes
    over; docs/hamilton.md.)
    The equations, outputs and monitors are the same expressions with z = z₀ + δz.
    """
    count = len(initial)  # the elements; S, if integrated, follows them
    names = [str(v) for v, _ in system[:count]]
    offsets = [hy.make_vars(f"delta_{name}") for name in names]
    table = {
        name: pars.add(f"predominant_mass.{name}_start", value) + d
        for name, d, value in zip(names, offsets, initial, strict=True)
    }
    rates = [(d, hy.subs(rhs, table)) for d, (_, rhs) in zip(offsets, system[:count], strict=True)]
    rates += [(v, hy.subs(rhs, table)) for v, rhs in system[count:]]
    outputs = {k: hy.subs(v, table) for k, v in outputs.items()}
    monitors = {
        k: [hy.subs(e, table) for e in v] if isinstance(v, list) else hy.subs(v, table)
        for k, v in monitors.items()
    }
    return rates, outputs, monitors, ["0"] * count


def initial_state(ham: Hamiltonian, t: Number, dps: int) -> list[str]:
    """The formulation's state at the start time ``t`` as decimal text with ``dps`` digits.

    canonical: ξ of every body, then pᵢ = mᵢx′ᵢ; elements: (μ, τ, ϖ, λ, χ, ν) of every body,
    by the reverse conversion of §8.3 (:func:`.system.hamilton_elements`). Computed in mpmath
    from the scene's exact numbers, so a real128 or multiprecision run starts exactly.
    """
    with mpmath.workdps(dps):
        G, M = scene_mpf(ham.constants["G"]), scene_mpf(ham.constants["central_mass"])
        states = [
            body.state(ham.constants["central_mass"], ham.constants["G"]) for body in ham.bodies
        ]
        if ham.formulation == "canonical":
            values = [v for x, _ in states for v in x]
            values += [
                scene_mpf(b.mass) * v
                for b, (_, xp) in zip(ham.bodies, states, strict=True)
                for v in xp
            ]
        else:
            values = []
            for k, (body, (x, xp)) in enumerate(zip(ham.bodies, states, strict=True)):
                try:
                    z = planets.hamilton_elements(x, xp, scene_mpf(t), scene_mpf(body.mass), M, G)
                except ValueError as exc:  # the scene's checks refuse these first
                    raise SceneError(f"hamiltonian.bodies[{k}]", str(exc)) from None
                values += list(z.as_tuple())
        return [mpmath.nstr(v, dps, strip_zeros=False) for v in values]


def _start_time(scene: Scene) -> Number:
    out = scene.output
    return out.times[0] if out.times is not None else out.grid[0]
