"""Build the heyoka system of a Hamiltonian scene.

The canonical equations come from H by heyoka's symbolic differentiation
(:func:`.canonical.canonical_equations`); with ``output.principal_function = true`` the
principal function S = ∫ (Σ ϖ η̇ − H) dt from the start time is one more state variable.
Results carry ``eta1 … etaN``, ``varpi1 … varpiN`` (and ``S``); the monitor ``energy`` is H,
conserved when H does not contain t.
"""

from __future__ import annotations

from fractions import Fraction
from typing import Any

import heyoka as hy

from ..errors import SceneError
from ..expressions import parse_expression
from ..model import EventSpec, Model, ParTable
from ..precision import exact_fraction, fraction_text
from ..scene import Scene
from .canonical import canonical_equations, principal_rate
from .scene import Hamiltonian


def build_model(scene: Scene) -> Model:
    """Turn a validated Hamiltonian scene into a :class:`~cayley_heyoka.model.Model`."""
    ham: Hamiltonian = scene.model
    prec = scene.integrator.precision
    n = ham.degrees
    eta = [hy.make_vars(f"eta{i + 1}") for i in range(n)]
    varpi = [hy.make_vars(f"varpi{i + 1}") for i in range(n)]
    pars = ParTable()
    if ham.model == "projectile":
        H = _projectile(eta, varpi, ham, pars, prec)
    else:
        symbols = {str(v): v for v in (*eta, *varpi)}
        H = parse_expression(ham.text, symbols, pars, "hamiltonian.H")
    system = canonical_equations(H, eta, varpi)
    initial: list[Any] = [*ham.eta, *ham.varpi]
    outputs = {str(v): v for v in (*eta, *varpi)}
    if _principal_function(scene):
        S = hy.make_vars("S")
        system.append((S, principal_rate(H, system, varpi)))
        initial.append(0)
        outputs["S"] = S
    monitors = {"energy": H}
    conserved = () if ham.time_dependent else ("energy",)
    wanted = scene.output.monitors
    if wanted is not None:
        unknown = [m for m in wanted if m not in monitors]
        if unknown:
            raise SceneError(
                "output.monitors", f"{unknown[0]!r} is not available here; available: ['energy']"
            )
        monitors = {k: v for k, v in monitors.items() if k in wanted}
        conserved = tuple(k for k in conserved if k in wanted)
    events = _events(scene, outputs, pars)
    return Model(
        "hamiltonian",
        system,
        [prec.number(v) for v in initial],
        pars,
        outputs,
        monitors,
        conserved,
        events,
    )


def _projectile(eta, varpi, ham: Hamiltonian, pars: ParTable, prec) -> Any:
    """H = ½|ϖ|² + g η₃ + ½{μ²(η₁² + η₂²) + ν² η₃²} (§5.1), with g, μ²/2, ν²/2 as parameters.

    The squares are taken exactly from the scene's numbers and rounded once, so that no
    expression of parameters alone is left for heyoka to evaluate at every Taylor order.
    """
    g = pars.add("projectile.g", ham.constants["g"])

    def half_square(key: str) -> Any:
        value = Fraction(exact_fraction(ham.constants[key])) ** 2 / 2
        return pars.add(f"projectile.{key}_squared_half", fraction_text(value, prec))

    mu2, nu2 = half_square("mu"), half_square("nu")
    kinetic = 0.5 * hy.sum([p * p for p in varpi])
    return kinetic + g * eta[2] + mu2 * (eta[0] * eta[0] + eta[1] * eta[1]) + nu2 * eta[2] ** 2


def _principal_function(scene: Scene) -> bool:
    value = scene.output.options.get("principal_function", False)
    if not isinstance(value, bool):
        raise SceneError("output.principal_function", f"must be true or false, got {value!r}")
    return value


def _events(scene: Scene, outputs: dict, pars: ParTable) -> list[EventSpec]:
    events = []
    for name in scene.output.events:
        if name not in scene.events:
            known = list(scene.events)
            raise SceneError("output.events", f"unknown event {name!r}; known: {known}")
        ev = scene.events[name]
        expr = parse_expression(ev.expression, outputs, pars, f"events.{name}.expression")
        events.append(EventSpec(name, name, expr, ev.direction))
    for name in scene.events:
        if name not in scene.output.events:
            raise SceneError(f"events.{name}", "is defined but not listed in output.events")
    return events
