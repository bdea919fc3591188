"""The Euler–Poisson reduction: a body whose forces see one space-fixed direction only.

When the force function depends on the attitude only through the body components
``γ = Rᵀu`` of one fixed space direction ``u`` — a heavy top's vertical (Lagrange's,
Kovalevskaya's, Goryachev–Chaplygin's tops), a gravity-gradient's direction, a user ``V`` of
``R31, R32, R33`` alone (u = space z) — the motion closes on the rates and γ (Poisson's
equations):

    γ̇ = γ × ω,        A ṗ = (B − C) q r + N₁, …,        N = (∂V/∂γ) × γ,

six equations instead of the quaternion's seven or the Rodrigues chart's six and its
re-basing events (``[attitude] formulation = "poisson"``). Conserved: the energy ``T − V``,
``|γ|²`` (``direction_norm``, = 1) and the area integral ``L · γ`` (``momentum_vertical``:
``N · γ = 0``). The azimuth about ``u`` is not integrated unless ``output.azimuth = true``
asks for the whole attitude (:mod:`.azimuth`, by quadrature).

The force functions are written on the direction cosines; here they are given the matrix
``u γᵀ`` (``R_ij = u_i γ_j``), whose every use ``Rᵀu`` is ``|u|² γ = γ`` and whose third row is
γ when u = z: each force keeps its one definition.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import heyoka as hy

from ..core.errors import SceneError
from ..core.expressions import names_used
from ..core.precision import Precision, exact_fraction, normalised
from .forces import GravityGradient, HeavyTop, Potential

Expr = Any  # a heyoka expression
GAMMA = ("gamma1", "gamma2", "gamma3")
#: Names a user force function may use in the reduced model (u = space z).
POTENTIAL_NAMES = {"R31", "R32", "R33", "A", "B", "C", "t", "pi"}


def direction(forces: Sequence[Any], precision: Precision) -> tuple[Any, ...]:
    """The one space direction ``u`` every force sees (unit, in the run's precision), or a
    :class:`SceneError` saying why the scene cannot be reduced."""
    if not forces:
        raise SceneError(
            "attitude.formulation",
            "'poisson' reduces a body whose forces see one fixed direction; this one has no "
            "force (use 'none' for the rates alone)",
        )
    seen: list[tuple[str, tuple[Any, ...]]] = []
    for force in forces:
        if isinstance(force, HeavyTop):
            seen.append(("forces.heavy_top.up", force.up))
        elif isinstance(force, GravityGradient):
            seen.append(("forces.gravity_gradient.direction", force.direction))
        elif isinstance(force, Potential):
            other = names_used(force.V, "forces.potential.V") - POTENTIAL_NAMES
            if other:
                raise SceneError(
                    "attitude.formulation",
                    f"'poisson' needs V of R31, R32, R33 alone (the space z axis in body axes); "
                    f"forces.potential.V uses {sorted(other)}",
                )
            seen.append(("forces.potential.V", (0, 0, 1)))
        else:  # a force added later must say how it sees the attitude
            raise SceneError("attitude.formulation", f"'poisson' cannot reduce {force!r}")
    units = [normalised(u, precision) for _, u in seen]
    exact = [tuple(exact_fraction(x) for x in u) for u in units]
    for (where, _), u in zip(seen[1:], exact[1:], strict=True):
        if u != exact[0]:
            raise SceneError(
                "attitude.formulation",
                f"'poisson' needs one fixed direction, but {seen[0][0]} and {where} differ",
            )
    return units[0]


def initial_direction(q0: Sequence[Any], u: Sequence[Any], precision: Precision) -> list[Any]:
    """γ(0) = R(q0)ᵀ u in the run's precision (u as decimal text, read in that precision)."""
    from .attitude import quaternion_to_matrix

    R = quaternion_to_matrix(list(q0))
    uu = [precision.number(x) for x in u]
    return [sum(R[i][j] * uu[i] for i in range(3)) for j in range(3)]


def frame(u: Sequence[Any], gamma: Sequence[Expr], precision: Precision) -> list[list[Expr]]:
    """The matrix ``u γᵀ`` the force functions are evaluated on."""
    return [[_times(precision, u[i], gamma[j]) for j in range(3)] for i in range(3)]


def _times(precision: Precision, ui: Any, gj: Expr) -> Expr:
    f = exact_fraction(ui)
    if f == 0:
        return hy.expression(precision.number(0))
    if f == 1:
        return gj
    return hy.expression(precision.number(ui)) * gj


def kinematics(gamma: Sequence[Expr], rates: Sequence[Expr]) -> list[Expr]:
    """Poisson's equations γ̇ = γ × ω."""
    g1, g2, g3 = gamma
    p, q, r = rates
    return [g2 * r - g3 * q, g3 * p - g1 * r, g1 * q - g2 * p]


def torque(potential: Expr, gamma: Sequence[Expr]) -> list[Expr]:
    """N = (∂V/∂γ) × γ: a virtual rotation δφ of the body moves γ by γ × δφ."""
    gx, gy, gz = (hy.diff(potential, g) for g in gamma)
    g1, g2, g3 = gamma
    return [gy * g3 - gz * g2, gz * g1 - gx * g3, gx * g2 - gy * g1]
