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

from collections.abc import Mapping, Sequence
from fractions import Fraction
from typing import TypeAlias

import heyoka as hy

from ..core.expressions import FUNCTIONS, rebuild
from ..core.model import ParTable
from ..core.symbolic import Algebra, Unsupported

Expr: TypeAlias = hy.expression


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


def shared_canonical_equations(
    H: Expr,
    texts: Sequence[tuple[str, str]],
    symbols: Mapping[str, Expr],
    pars: ParTable,
    eta: Sequence[Expr],
    varpi: Sequence[Expr],
) -> tuple[list[tuple[Expr, Expr]], int | None]:
    """(A.) for ``H``, the sum of ``texts`` (``(text, field)`` pairs that
    :func:`~cayley_heyoka.core.expressions.parse_expression` parsed into ``pars`` over
    ``symbols``), differentiated in exact normal form (:mod:`cayley_heyoka.core.symbolic`).

    Every subexpression the partial derivatives share — a pair's difference of positions, its
    (r²)^(−3/2) with the pair's coefficient — is one heyoka expression, computed once per
    step: for a Newtonian N-body H the system is no larger than ``heyoka.model.nbody``'s. The
    equations are :func:`canonical_equations`' up to round-off, and those are the fallback
    where the algebra refuses an operation (an exact power too large to fold, a division by an
    exact zero).

    Returns
    -------
    system, decomposition
        The ``(variable, right-hand side)`` pairs, and the length of heyoka's decomposition of
        them as the algebra counts it (:attr:`~cayley_heyoka.core.model.Model.decomposition`;
        None for the fallback).
    """
    algebra = Algebra(pars.constant, FUNCTIONS)
    try:
        total = algebra.linear(
            (Fraction(1), rebuild(text, symbols, pars, field, algebra)) for text, field in texts
        )
        coordinates = [algebra.leaf(v) for v in eta]
        momenta = [algebra.leaf(v) for v in varpi]
        rates = [algebra.diff(total, p) for p in momenta]
        rates += [algebra.neg(algebra.diff(total, q)) for q in coordinates]
        rhs = [algebra.emit(r) for r in rates]
    except Unsupported:
        return canonical_equations(H, eta, varpi), None
    system = list(zip((*eta, *varpi), rhs, strict=True))
    return system, 2 * len(system) + algebra.operations
