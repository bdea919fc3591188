"""Force functions V for a body turning about a fixed point.

``V`` is Cayley's *force function* (the work function, minus the potential energy), written
as an expression of the direction cosines ``R`` (row = space axis, column = body axis) of the
body's attitude; the torque then follows by Cayley's formula or by the matrix gradient (see
:mod:`.equations`). Constant terms of ``V`` are dropped: they exert no torque.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import heyoka as hy

from ..core.errors import SceneError
from ..core.expressions import parse_expression, uses_time
from ..core.model import ParTable
from ..core.precision import Precision, normalised
from ..core.scene import check_keys, expression_text, number, unit_vector, vector
from .attitude import Matrix

Expr = hy.expression


@dataclass
class ForceContext:
    """What a force function may use: attitude, inertia, time and the parameter table.

    ``rodrigues`` are the Cayley–Rodrigues parameters of the whole attitude (space ← body)
    as expressions of the integrated state, whatever the formulation; ``values`` the scene's
    numbers by parameter name (:func:`cayley_heyoka.rotation.numbers.numbers`, which asks each
    force for its ``values``).
    """

    R: Matrix
    rodrigues: Sequence[Expr]
    inertia: Sequence[Expr]
    pars: ParTable
    values: Mapping[str, Any]

    def add(self, name: str, field: str) -> Expr:
        """The parameter ``name``, holding the scene's number for it."""
        return self.pars.add(name, self.values[name], field)


@dataclass(frozen=True)
class HeavyTop:
    """Uniform gravity on a body whose centre of mass is off the fixed point.

    ``V = −Mg (û · R c)``: ``weight`` = Mg, ``center_of_mass`` = c in body axes, ``up`` = the unit
    vertical û in space axes (gravity is −Mg û), normalised in the run's precision.
    """

    weight: Any
    center_of_mass: tuple
    up: tuple = (0, 0, 1)
    time_dependent = False

    @classmethod
    def parse(cls, table: Mapping[str, Any], where: str) -> HeavyTop:
        check_keys(table, ["weight", "center_of_mass", "up"], where)
        for key in ("weight", "center_of_mass"):
            if key not in table:
                raise SceneError(f"{where}.{key}", "is required")
        return cls(
            number(table["weight"], f"{where}.weight", nonneg=True),
            vector(table["center_of_mass"], f"{where}.center_of_mass", 3),
            unit_vector(table.get("up", [0, 0, 1]), f"{where}.up"),
        )

    def values(self, precision: Precision) -> dict[str, Any]:
        """The force's parameters (the vertical normalised in ``precision``)."""
        up = normalised(self.up, precision)
        return {
            "heavy_top.weight": self.weight,
            **{f"heavy_top.center_of_mass[{j}]": self.center_of_mass[j] for j in range(3)},
            **{f"heavy_top.up[{i}]": up[i] for i in range(3)},
        }

    def potential(self, ctx: ForceContext) -> Expr:
        where = "forces.heavy_top"
        Mg = ctx.add("heavy_top.weight", f"{where}.weight")
        c = [
            ctx.add(f"heavy_top.center_of_mass[{j}]", f"{where}.center_of_mass[{j}]")
            for j in range(3)
        ]
        u = [ctx.add(f"heavy_top.up[{i}]", f"{where}.up[{i}]") for i in range(3)]
        height = sum(u[i] * sum(ctx.R[i][j] * c[j] for j in range(3)) for i in range(3))
        return -Mg * height


@dataclass(frozen=True)
class GravityGradient:
    """The tidal torque of a distant point mass (MacCullagh's approximation).

    ``V = −(3 GM / 2d³) ûᵦ · I ûᵦ`` with ``ûᵦ = Rᵀ û`` the body components of the unit vector û
    (space axes, normalised in the run's precision) from the fixed point to the mass, ``gm`` =
    GM, ``distance`` = d. The torque is ``N = (3 GM/d³) ûᵦ × I ûᵦ``.
    """

    gm: Any
    distance: Any
    direction: tuple
    time_dependent = False

    @classmethod
    def parse(cls, table: Mapping[str, Any], where: str) -> GravityGradient:
        check_keys(table, ["gm", "distance", "direction"], where)
        for key in ("gm", "distance", "direction"):
            if key not in table:
                raise SceneError(f"{where}.{key}", "is required")
        return cls(
            number(table["gm"], f"{where}.gm", nonneg=True),
            number(table["distance"], f"{where}.distance", positive=True),
            unit_vector(table["direction"], f"{where}.direction"),
        )

    def values(self, precision: Precision) -> dict[str, Any]:
        """The force's parameters (the direction normalised in ``precision``)."""
        direction = normalised(self.direction, precision)
        return {
            "gravity_gradient.gm": self.gm,
            "gravity_gradient.distance": self.distance,
            **{f"gravity_gradient.direction[{i}]": u_i for i, u_i in enumerate(direction)},
        }

    def potential(self, ctx: ForceContext) -> Expr:
        where = "forces.gravity_gradient"
        gm = ctx.add("gravity_gradient.gm", f"{where}.gm")
        d = ctx.add("gravity_gradient.distance", f"{where}.distance")
        u = [
            ctx.add(f"gravity_gradient.direction[{i}]", f"{where}.direction[{i}]") for i in range(3)
        ]
        ub = [sum(ctx.R[i][j] * u[i] for i in range(3)) for j in range(3)]
        quad = sum(ctx.inertia[j] * ub[j] * ub[j] for j in range(3))
        return -1.5 * gm / (d * d * d) * quad


@dataclass(frozen=True)
class Potential:
    """A user force function, written as text.

    Names available: ``lambda``, ``mu``, ``nu`` (Cayley–Rodrigues parameters of the attitude),
    ``R11`` … ``R33`` (direction cosines, ``Rij`` = cos(space axis i, body axis j)), ``A``, ``B``,
    ``C`` and ``t``. Prefer the direction cosines: ``V`` written in λ, μ, ν is singular where
    the rotation angle reaches π.
    """

    V: str
    time_dependent: bool = False

    @classmethod
    def parse(cls, table: Mapping[str, Any], where: str) -> Potential:
        check_keys(table, ["V"], where)
        if "V" not in table:
            raise SceneError(f"{where}.V", "is required")
        V = expression_text(table["V"], f"{where}.V")
        return cls(V, uses_time(V))

    def values(self, precision: Precision) -> dict[str, Any]:
        """None besides the literals of its text, which the structure holds."""
        return {}

    def potential(self, ctx: ForceContext) -> Expr:
        symbols = {f"R{i + 1}{j + 1}": ctx.R[i][j] for i in range(3) for j in range(3)}
        symbols.update(zip(("lambda", "mu", "nu"), ctx.rodrigues, strict=True))
        symbols.update(zip("ABC", ctx.inertia, strict=True))
        return parse_expression(self.V, symbols, ctx.pars, "forces.potential.V")


FORCES = {"heavy_top": HeavyTop, "gravity_gradient": GravityGradient, "potential": Potential}


def force_key(force: Any) -> str:
    """The ``[forces.KEY]`` table of a parsed force."""
    return next(key for key, cls in FORCES.items() if isinstance(force, cls))


def parse_forces(table: Mapping[str, Any]) -> tuple:
    """Parse the ``[forces.*]`` tables, in a fixed order so equal scenes compile equally."""
    check_keys(table, list(FORCES), "forces")
    return tuple(FORCES[k].parse(table[k], f"forces.{k}") for k in FORCES if k in table)
