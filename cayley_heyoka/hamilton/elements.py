"""Hamilton's varying elements: H = H₁ + H₂, the flow of H₁ known, the elements integrated.

Symbols (Hamilton 1835, Second Essay, §8–9 and §13–18; docs/hamilton.md): H₁ the undisturbed
Hamiltonian, whose motion is known in closed form, and H₂ the disturbing part. The elements χᵢ, λᵢ
are the initial data that the undisturbed motion would need to pass through the current state
(70.)–(73.):

    ηᵢ = φᵢ(χ, λ, t),    ϖᵢ = ψᵢ(χ, λ, t)         (the flow of H₁, with φ = χ, ψ = λ at t = 0).

By Hamilton's theorem the brackets of such elements are free of t and canonical,
(χᵢ, λₖ) = δᵢₖ, (χᵢ, χₖ) = (λᵢ, λₖ) = 0 (§4.3–§4.4), so in the disturbed motion

    dχᵢ/dt = ∂H₂/∂λᵢ,      dλᵢ/dt = −∂H₂/∂χᵢ,      H₂ = H₂(φ(χ, λ, t), ψ(χ, λ, t), t)   (G′.).

:func:`check_flow` verifies, on sample points, what these equations rest on: that the given
flow solves H₁'s canonical equations, starts at the elements, and has the canonical Lagrange
brackets [a, b] = Σᵢ (∂ηᵢ/∂a ∂ϖᵢ/∂b − ∂ηᵢ/∂b ∂ϖᵢ/∂a) at every sampled time (computed by
heyoka's symbolic differentiation); the Poisson brackets are then canonical too, (P = (Lᵀ)⁻¹).
"""

from __future__ import annotations

from collections.abc import Sequence

import heyoka as hy
import numpy as np

from ..core.errors import SceneError

Expr = hy.expression

#: Sample points and times of the checks: seeded, so a scene is judged the same way every time.
_SAMPLES = 6
_TOLERANCE = 1e-10


def element_equations(
    H2: Expr,
    eta: Sequence[Expr],
    varpi: Sequence[Expr],
    flow_eta: Sequence[Expr],
    flow_varpi: Sequence[Expr],
    chi: Sequence[Expr],
    lam: Sequence[Expr],
) -> list[tuple[Expr, Expr]]:
    """``(variable, right-hand side)`` pairs of (G′.) for the elements ``chi``, ``lam``.

    ``H2`` is written in η, ϖ (and t); it is composed with the flow and differentiated in the
    elements by heyoka.
    """
    H2_elements = compose(H2, eta, varpi, flow_eta, flow_varpi)
    return hy.hamiltonian(H2_elements, list(chi), list(lam))


def compose(
    expr: Expr,
    eta: Sequence[Expr],
    varpi: Sequence[Expr],
    flow_eta: Sequence[Expr],
    flow_varpi: Sequence[Expr],
) -> Expr:
    """``expr(η, ϖ, t)`` with η, ϖ replaced by the flow φ(χ, λ, t), ψ(χ, λ, t)."""
    table = {str(v): f for v, f in zip(eta, flow_eta, strict=True)}
    table |= {str(v): f for v, f in zip(varpi, flow_varpi, strict=True)}
    return hy.subs(expr, table)


def lagrange_brackets(
    flow_eta: Sequence[Expr], flow_varpi: Sequence[Expr], chi: Sequence[Expr], lam: Sequence[Expr]
) -> list[list[Expr]]:
    """[a, b] = Σᵢ (∂ηᵢ/∂a ∂ϖᵢ/∂b − ∂ηᵢ/∂b ∂ϖᵢ/∂a) over the elements (χ, λ), symbolically.

    Canonical elements have [χᵢ, λₖ] = δᵢₖ and the others zero; the Poisson brackets (z, z′) of
    (C′.) are then canonical too (P = (Lᵀ)⁻¹; Hamilton's theorem, Second Essay §14–15).
    """
    z = [*chi, *lam]
    d_eta = [[hy.diff(f, v) for v in z] for f in flow_eta]
    d_varpi = [[hy.diff(f, v) for v in z] for f in flow_varpi]
    m = len(z)
    return [
        [
            hy.sum([de[a] * dv[b] - de[b] * dv[a] for de, dv in zip(d_eta, d_varpi, strict=True)])
            for b in range(m)
        ]
        for a in range(m)
    ]


def check_flow(
    H1: Expr,
    eta: Sequence[Expr],
    varpi: Sequence[Expr],
    flow_eta: Sequence[Expr],
    flow_varpi: Sequence[Expr],
    chi: Sequence[Expr],
    lam: Sequence[Expr],
    pars: np.ndarray,
    field: str,
) -> None:
    """Raise :class:`SceneError` (on ``field``) unless the flow is H₁'s, from the elements.

    Three identities, at seeded random elements and times in [−3, 3], to 1e-10 relative in
    double: (1) ∂φ/∂t = ∂H₁/∂ϖ and ∂ψ/∂t = −∂H₁/∂η at (φ, ψ); (2) φ = χ, ψ = λ at t = 0;
    (3) the Lagrange brackets of (χ, λ) are canonical and so free of t.
    """
    n = len(eta)
    z = [*chi, *lam]
    # heyoka differentiates in variables, not in time: t becomes the variable τ here.
    tau = hy.make_vars("tau_check")
    flow = [hy.subs(f, {hy.time: tau}) for f in (*flow_eta, *flow_varpi)]
    rates = [hy.diff(f, tau) for f in flow]
    canonical = [rhs for _, rhs in hy.hamiltonian(H1, list(eta), list(varpi))]
    along = [hy.subs(compose(e, eta, varpi, flow[:n], flow[n:]), {hy.time: tau}) for e in canonical]
    brackets = lagrange_brackets(flow[:n], flow[n:], chi, lam)
    exprs = [*rates, *along, *flow, *(e for row in brackets for e in row)]
    cf = hy.cfunc(exprs, [*z, tau])
    rng = np.random.default_rng(1835)
    J = np.block([[np.zeros((n, n)), np.eye(n)], [-np.eye(n), np.zeros((n, n))]])
    for k in range(_SAMPLES):
        point = rng.uniform(-1.5, 1.5, size=2 * n)
        t = 0.0 if k == 0 else float(rng.uniform(-3, 3))
        values = cf(np.append(point, t), pars=pars[: cf.nparams])
        m = 2 * n
        rate, along_v = values[:m], values[m : 2 * m]
        at = values[2 * m : 3 * m]
        L = values[3 * m :].reshape(m, m)
        scale = 1 + np.max(np.abs(values))
        if np.max(np.abs(rate - along_v)) > _TOLERANCE * scale:
            raise SceneError(
                field,
                f"is not the motion of H1: d(flow)/dt differs from H1's canonical equations by "
                f"{np.max(np.abs(rate - along_v)):.2e} at t = {t:.3g}",
            )
        if k == 0 and np.max(np.abs(at - point)) > _TOLERANCE * scale:
            raise SceneError(
                field,
                "must start at the elements: eta_i = chi_i and varpi_i = lambda_i at t = 0",
            )
        if np.max(np.abs(L - J)) > _TOLERANCE * scale**2:
            raise SceneError(
                field,
                f"gives elements whose brackets are not canonical at t = {t:.3g} (largest "
                f"deviation {np.max(np.abs(L - J)):.2e}): the flow must carry initial data",
            )
