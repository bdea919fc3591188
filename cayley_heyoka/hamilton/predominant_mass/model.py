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
from collections.abc import Mapping
from typing import Any

import heyoka as hy

from ...core.model import Model, ParTable
from ...core.scene import Scene
from ..numbers import same_numbers
from ..outputs import select_monitors, user_events, wants_principal_function
from ..scene import Hamiltonian
from . import equations as pe
from .numbers import numbers, start_names

# Compiled without compact mode, the element equations (Kepler's equation and the gradient of
# H₂ through it) take ~25 s for two bodies against ~1 s in compact mode, at the same step
# cost; the canonical equations take 0.5 / 1.9 / 4.2 s for 2 / 3 / 4 bodies (12 s for 6) and
# step 1.3–2× faster than in compact mode, so they switch at 5 bodies.
_COMPACT_BODIES = 5
_AXES = ("x", "y", "z")


def build_model(scene: Scene) -> Model:
    """Turn a validated predominant-mass scene into a :class:`~cayley_heyoka.core.model.Model`,
    its numbers from :func:`~cayley_heyoka.hamilton.predominant_mass.numbers.numbers`."""
    ham: Hamiltonian = scene.model
    prec = scene.integrator.precision
    given = numbers(scene)
    n = len(ham.bodies)
    pars = ParTable(prec)
    c = pe.Coefficients(
        ham.constants["G"],
        ham.constants["central_mass"],
        [b.mass for b in ham.bodies],
        pars,
        prec,
        given.values,
    )
    outputs: dict[str, Any] = {}
    form = ham.form
    if not form.elements:
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
    if form.elements:
        system, outputs, monitors = _offsets(system, outputs, monitors, 6 * n, pars, given.values)
    monitors, conserved = select_monitors(scene, monitors, ("energy", "angular_momentum"))
    events = user_events(scene, outputs, pars)
    same_numbers(pars, given)
    model = Model(
        "hamiltonian",
        system,
        list(given.initial_state),
        pars,
        outputs,
        monitors,
        conserved,
        events,
        compact=form.compact or n >= _COMPACT_BODIES,
    )
    _provenance(model)
    return model


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


def _offsets(
    system: list, outputs: dict, monitors: dict, count: int, pars: ParTable, values: Mapping
) -> tuple[list, dict, dict]:
    """Integrate the elements' offsets δz = z − z₀ from their start values z₀ (parameters).

    The elements move by O(m/M) about z₀: a state holding z itself is rounded to ε|z| at every
    step, a walk of ε√steps that τ and μ turn into a drift of the phase; holding δz rounds to
    ε|δz|, O(m/M) of that. (Measured on N5 against z in the state: the position error 5×
    smaller at 100 orbits, 3× at 1000, where the rounding of the mean anomaly n(t − τ) takes
    over; docs/hamilton.md.)
    The equations, outputs and monitors are the same expressions with z = z₀ + δz; the first
    ``count`` variables of ``system`` are the elements (S, if integrated, follows them) and
    ``values`` holds z₀ (:func:`.numbers.numbers`).
    """
    names = [str(v) for v, _ in system[:count]]
    offsets = [hy.make_vars(f"delta_{name}") for name in names]
    table = {
        name: pars.add(key, values[key]) + d
        for name, d, key in zip(names, offsets, start_names(count // 6), strict=True)
    }
    rates = [(d, hy.subs(rhs, table)) for d, (_, rhs) in zip(offsets, system[:count], strict=True)]
    rates += [(v, hy.subs(rhs, table)) for v, rhs in system[count:]]
    outputs = {k: hy.subs(v, table) for k, v in outputs.items()}
    monitors = {
        k: [hy.subs(e, table) for e in v] if isinstance(v, list) else hy.subs(v, table)
        for k, v in monitors.items()
    }
    return rates, outputs, monitors
