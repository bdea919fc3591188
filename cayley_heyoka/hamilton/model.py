"""Build the heyoka system of a Hamiltonian scene.

The canonical equations come from H by heyoka's symbolic differentiation
(:func:`.canonical.canonical_equations`); with ``output.principal_function = true`` the
principal function S = ∫ (Σ ϖ η̇ − H) dt from the start time is one more state variable.
Results carry ``eta1 … etaN``, ``varpi1 … varpiN`` (and ``S``); the monitor ``energy`` is H,
conserved when H does not contain t. With ``formulation = "elements"`` the state is Hamilton's
varying elements ``chi1 … chiN``, ``lambda1 … lambdaN`` of the split H = H₁ + H₂
(:mod:`.elements`), and η, ϖ are reported through the flow of H₁.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import heyoka as hy
import numpy as np

from ..core.expressions import parse_expression
from ..core.model import Model, ParTable
from ..core.precision import exact_fraction
from ..core.scene import Scene
from .canonical import canonical_equations, principal_rate, shared_canonical_equations
from .elements import check_flow, compose, element_equations
from .numbers import numbers, same_numbers
from .outputs import select_monitors, user_events, wants_principal_function
from .scene import Hamiltonian


def build_model(scene: Scene) -> Model:
    """Turn a validated Hamiltonian scene into a :class:`~cayley_heyoka.core.model.Model`, its
    numbers from :func:`~cayley_heyoka.hamilton.numbers.numbers`."""
    ham: Hamiltonian = scene.model
    if ham.model == "predominant_mass":
        from .predominant_mass.model import build_model as build_predominant_mass

        return build_predominant_mass(scene)
    prec = scene.integrator.precision
    given = numbers(scene)
    n = ham.degrees
    eta = [hy.make_vars(f"eta{i + 1}") for i in range(n)]
    varpi = [hy.make_vars(f"varpi{i + 1}") for i in range(n)]
    pars = ParTable(prec)
    H1, H2 = _split(ham, eta, varpi, pars, given.values)
    H = H1 if H2 is None else H1 + H2
    form = ham.form
    decomposition = None
    if form.elements:
        system, outputs, energy, rate_of_S = _elements(ham, eta, varpi, H1, H2, pars)
        state_varpi = None
    else:
        system, decomposition = _canonical(ham, H, eta, varpi, pars)
        outputs = {str(v): v for v in (*eta, *varpi)}
        energy, state_varpi = H, varpi
        rate_of_S = None
    if wants_principal_function(scene):
        S = hy.make_vars("S")
        if rate_of_S is None:
            rate_of_S = principal_rate(H, system, state_varpi)
        system.append((S, rate_of_S))
        outputs["S"] = S
    monitors = {"energy": energy}
    conserved = () if ham.time_dependent else ("energy",)
    monitors, conserved = select_monitors(scene, monitors, conserved)
    events = user_events(scene, outputs, pars)
    same_numbers(pars, given)
    # (χ, λ) start at (η, ϖ): the flow of H₁ is the identity at t = 0.
    fields = {f"{form.coordinates}{i + 1}": f"initial.eta[{i}]" for i in range(n)}
    fields |= {f"{form.momenta}{i + 1}": f"initial.varpi[{i}]" for i in range(n)}
    fields["S"] = "output.principal_function"
    return Model(
        "hamiltonian",
        system,
        list(given.initial_state),
        pars,
        outputs,
        monitors,
        conserved,
        events,
        initial_fields=fields,
        decomposition=decomposition,
    )


def _split(ham: Hamiltonian, eta, varpi, pars: ParTable, values: Mapping) -> tuple[Any, Any]:
    """(H₁, H₂) of the scene; H₂ is None for a single user Hamiltonian."""
    symbols = {str(v): v for v in (*eta, *varpi)}
    if ham.model == "projectile":
        return _projectile(eta, varpi, pars, values)
    if ham.text is not None:
        return parse_expression(ham.text, symbols, pars, "hamiltonian.H"), None
    H1 = parse_expression(ham.split[0], symbols, pars, "hamiltonian.H1")
    H2 = parse_expression(ham.split[1], symbols, pars, "hamiltonian.H2")
    return H1, H2


def _canonical(ham: Hamiltonian, H, eta, varpi, pars: ParTable) -> tuple[list, int | None]:
    """(A.) of the scene's H: from its texts with the shared subexpressions of
    :func:`.canonical.shared_canonical_equations`, the projectile's by heyoka; and the
    decomposition's length where it is counted."""
    if ham.model == "projectile":
        return canonical_equations(H, eta, varpi), None
    if ham.text is not None:
        texts = [(ham.text, "hamiltonian.H")]
    else:
        texts = list(zip(ham.split or (), ("hamiltonian.H1", "hamiltonian.H2"), strict=True))
    symbols = {str(v): v for v in (*eta, *varpi)}
    return shared_canonical_equations(H, texts, symbols, pars, eta, varpi)


def _projectile(eta, varpi, pars: ParTable, values: Mapping) -> tuple[Any, Any]:
    """H₁ = ½|ϖ|² + g η₃ (free fall) and H₂ = ½{μ²(η₁² + η₂²) + ν² η₃²} (§5.1, §6), with g,
    μ²/2, ν²/2 as parameters (their values: :func:`.numbers.numbers`)."""
    g = pars.add("projectile.g", values["projectile.g"], "hamiltonian.g")
    mu2, nu2 = (
        pars.add(
            f"projectile.{key}_squared_half",
            values[f"projectile.{key}_squared_half"],
            f"hamiltonian.{key}",
        )
        for key in ("mu", "nu")
    )
    H1 = 0.5 * hy.sum([p * p for p in varpi]) + g * eta[2]
    H2 = mu2 * (eta[0] * eta[0] + eta[1] * eta[1]) + nu2 * eta[2] ** 2
    return H1, H2


def _projectile_flow(chi, lam, pars: ParTable) -> tuple[list, list]:
    """Free fall (149.): η₁,₂ = χ + λt, η₃ = χ₃ + λ₃t − ½gt², ϖ₁,₂ = λ, ϖ₃ = λ₃ − gt."""
    g, t = hy.par[pars.index("projectile.g")], hy.time
    flow_eta = [chi[0] + lam[0] * t, chi[1] + lam[1] * t, chi[2] + lam[2] * t - 0.5 * g * t * t]
    flow_varpi = [lam[0], lam[1], lam[2] - g * t]
    return flow_eta, flow_varpi


def _elements(ham: Hamiltonian, eta, varpi, H1, H2, pars: ParTable):
    """Hamilton's varying elements χ, λ of the split (:mod:`.elements`): the system, the
    outputs (χ, λ and η, ϖ through the flow), H along the flow and dS/dt. (They start at
    t = 0, where they are η, ϖ: :func:`.numbers.numbers` refuses another start.)"""
    n = ham.degrees
    chi = [hy.make_vars(f"chi{i + 1}") for i in range(n)]
    lam = [hy.make_vars(f"lambda{i + 1}") for i in range(n)]
    if ham.model == "projectile":
        flow_eta, flow_varpi = _projectile_flow(chi, lam, pars)
    else:
        symbols = {str(v): v for v in (*chi, *lam)}
        flow_eta = [
            parse_expression(ham.flow[f"eta{i + 1}"], symbols, pars, f"hamiltonian.flow.eta{i + 1}")
            for i in range(n)
        ]
        flow_varpi = [
            parse_expression(
                ham.flow[f"varpi{i + 1}"], symbols, pars, f"hamiltonian.flow.varpi{i + 1}"
            )
            for i in range(n)
        ]
    values = np.array([float(exact_fraction(v)) for v in pars.values])
    check_flow(H1, eta, varpi, flow_eta, flow_varpi, chi, lam, values, "hamiltonian.flow")
    system = element_equations(H2, eta, varpi, flow_eta, flow_varpi, chi, lam)
    outputs = {str(v): v for v in (*chi, *lam)}
    outputs |= {str(v): f for v, f in zip((*eta, *varpi), (*flow_eta, *flow_varpi), strict=True)}
    H = H1 + H2
    energy = compose(H, eta, varpi, flow_eta, flow_varpi)
    # dS/dt = Σ ϖ η̇ − H on the true motion, η̇ = ∂H/∂ϖ at the state the flow gives.
    eta_rates = [rhs for _, rhs in canonical_equations(H, eta, varpi)[:n]]
    lagrangian = hy.sum([p * r for p, r in zip(varpi, eta_rates, strict=True)]) - H
    return system, outputs, energy, compose(lagrangian, eta, varpi, flow_eta, flow_varpi)
