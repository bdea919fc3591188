"""Hamilton's canonical equations and the principal function, as heyoka expressions.

Symbols (Hamilton 1835, *Second Essay on a General Method in Dynamics*, (A.), (19.)–(23.);
docs/hamilton.md): ηᵢ the coordinates, ϖᵢ
their conjugate momenta, H(η, ϖ, t) the Hamiltonian (T − U, with U Lagrange's force function),
e and p the values of η and ϖ at the start time. The canonical equations (A.) are

    dηᵢ/dt = ∂H/∂ϖᵢ,        dϖᵢ/dt = −∂H/∂ηᵢ,

and the principal function S = ∫ (T + U) dt = ∫ (Σᵢ ϖᵢ η̇ᵢ − H) dt (19.)–(23.) is carried as one
more state variable, so that ∂S/∂η = ϖ, ∂S/∂e = −p and ∂S/∂t = −H can be checked on the run.
"""

from __future__ import annotations

from collections.abc import Sequence

import heyoka as hy

Expr = hy.expression


def canonical_equations(
    H: Expr, eta: Sequence[Expr], varpi: Sequence[Expr]
) -> list[tuple[Expr, Expr]]:
    """``(variable, right-hand side)`` pairs of (A.), by heyoka's symbolic differentiation.

    Parameters
    ----------
    H
        The Hamiltonian: an expression of ``eta``, ``varpi``, parameters and time.
    eta, varpi
        The coordinates and momenta (heyoka variables), in conjugate pairs.
    """
    return hy.hamiltonian(H, list(eta), list(varpi))


def principal_rate(H: Expr, system: Sequence[tuple[Expr, Expr]], varpi: Sequence[Expr]) -> Expr:
    """dS/dt = Σᵢ ϖᵢ η̇ᵢ − H (= T + U when T is quadratic in the momenta).

    ``system`` is the output of :func:`canonical_equations`, whose first half holds η̇.
    """
    rates = [rhs for _, rhs in system[: len(varpi)]]
    return hy.sum([p * r for p, r in zip(varpi, rates, strict=True)]) - H
