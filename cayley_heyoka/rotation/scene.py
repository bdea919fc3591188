"""The rigid-body tables of a scene: ``[body]``, ``[initial]``, ``[attitude]``, ``[forces.*]``."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import numpy as np

from ..core.errors import SceneError
from ..core.precision import Number, Precision, exact_fraction, unit_length
from ..core.scene import check_keys, number, vector
from . import attitude as att
from .forces import parse_forces
from .formulations import FORMULATIONS as FORMULATIONS
from .formulations import Formulation, formulation

#: Smallest ``attitude.max_chart_angle`` (degrees): each re-basing is a terminal event and a
#: restart of the propagation, so below a few hundred per turn they cost more than the steps;
#: at 1e-300 every step re-based and the run never ended.
MIN_CHART_ANGLE = 1
_UNIT_TOL = Fraction(1, 10**12)


@dataclass(frozen=True)
class RigidBody:
    """A body turning about a fixed point.

    Attributes
    ----------
    inertia
        Principal moments (A, B, C): positive, finite, each at most the sum of the others.
    rates
        Body-frame angular velocity (p, q, r) at the start time.
    attitude
        ``(kind, value)`` with kind ``"rodrigues"``, ``"quaternion"`` or ``"matrix"``, or None
        for the identity.
    formulation
        How the attitude is integrated: ``"quaternion"`` (the default with an attitude or a
        force: the fastest at equal error, validation/users_rotation.py), ``"rodrigues"``
        (Cayley's parameters, re-based through rotation angles near π), or ``"none"`` (rates
        only). λ, μ, ν are outputs whichever is integrated. :attr:`form` declares what it
        integrates and supports (:mod:`.formulations`).
    max_chart_angle
        Rotation angle (degrees) of the Rodrigues chart at which it is re-based.
    forces
        Force functions, each a :mod:`.forces` object.
    """

    inertia: tuple[Number, Number, Number]
    rates: tuple[Number, Number, Number]
    attitude: tuple[str, Any] | None
    formulation: str
    max_chart_angle: Number
    forces: tuple

    @classmethod
    def parse(cls, tables: Mapping[str, Any]) -> RigidBody:
        body = tables.get("body", {})
        check_keys(body, ["inertia"], "body")
        if "inertia" not in body:
            raise SceneError("body.inertia", "is required: the principal moments [A, B, C]")
        inertia = vector(body["inertia"], "body.inertia", 3)
        _check_inertia(inertia)

        initial = tables.get("initial", {})
        check_keys(initial, ["rates", "rodrigues", "quaternion", "matrix"], "initial")
        if "rates" not in initial:
            raise SceneError("initial.rates", "is required: the body rates [p, q, r]")
        rates = vector(initial["rates"], "initial.rates", 3)
        given = [k for k in ("rodrigues", "quaternion", "matrix") if k in initial]
        if len(given) > 1:
            raise SceneError("initial", f"give one attitude, not several: {given}")
        attitude = _parse_attitude(given[0], initial[given[0]]) if given else None

        forces = parse_forces(tables.get("forces", {}))
        opts = tables.get("attitude", {})
        check_keys(opts, ["formulation", "max_chart_angle"], "attitude")
        # The quaternion: the chart's pole at θ = π shortens its Taylor steps (2–3× the
        # quaternion's steps, and more time at equal error: validation/users_rotation.py).
        default = "quaternion" if (attitude is not None or forces) else "none"
        form = formulation(opts.get("formulation", default))
        form.check_forces(bool(forces))
        angle = number(opts.get("max_chart_angle", 160), "attitude.max_chart_angle")
        if not MIN_CHART_ANGLE <= exact_fraction(angle) < 180:
            raise SceneError(
                "attitude.max_chart_angle",
                f"must be in [{MIN_CHART_ANGLE}, 180) degrees, got {angle}",
            )
        return cls(inertia, rates, attitude, form.name, angle, forces)

    @property
    def form(self) -> Formulation:
        """What :attr:`formulation` integrates and supports (:mod:`.formulations`)."""
        return formulation(self.formulation)

    @property
    def torque_free(self) -> bool:
        return not self.forces

    def initial_quaternion(self, precision: Precision) -> np.ndarray:
        """The initial attitude as a unit quaternion (w ≥ 0) in the target precision."""
        one = precision.number(1)
        if self.attitude is None:
            return np.array([one, 0 * one, 0 * one, 0 * one])
        kind, value = self.attitude
        if kind == "rodrigues":
            q = np.array(att.rodrigues_to_quaternion(list(precision.array(value))))
            # Beyond ~1e154 in double |ρ|² overflows and the quaternion comes out zero.
            if not abs(np.sum(q * q) - 1) <= 64 * precision.epsilon:
                raise SceneError(
                    "initial.rodrigues",
                    f"cannot be represented in {precision.name}: 1 + |ρ|² overflows; give the "
                    "attitude as a quaternion or a matrix",
                )
            return q
        if kind == "quaternion":
            q = precision.array(value)
            q = q / np.sqrt(np.sum(q * q))
            return -q if q[0] < 0 else q
        R = [list(precision.array(row)) for row in value]
        return np.array(att.matrix_to_quaternion(R))


def with_formulation(scene: Any, value: str, more: bool = False) -> dict[str, Any]:
    """The rigid-body scene's dictionary with the same motion integrated as ``value``
    (``Family.with_formulation``, :meth:`cayley_heyoka.core.families.Family.in_formulation`).

    The whole attitude as a quaternion, as Rodrigues parameters, or by the Euler–Poisson
    reduction with ``output.azimuth = true`` (set when the reduction is the target) is one
    motion; the reduction without the azimuth and the rates alone (``"none"``) are others.
    Away from the reduction ``output.azimuth`` is dropped (the others report the attitude
    themselves); ``attitude.max_chart_angle`` is the Rodrigues chart's and goes with it.

    Parameters
    ----------
    more
        Allow a target that integrates more than the scene (the whole attitude of a reduced
        body): a twin that compares what both have.

    Raises
    ------
    SceneError
        ``attitude.formulation``: ``value`` is unknown, or integrates another motion.
    """
    data = scene.to_dict()
    own: Formulation = scene.model.form
    if value == own.name:
        return data
    target = formulation(value)
    output = dict(data.get("output", {}))
    if not target.state:
        raise SceneError(
            "attitude.formulation",
            f"{target.name!r} integrates the rates alone: it would drop the attitude that "
            f"{own.name!r} integrates",
        )
    if not own.state:
        raise SceneError(
            "attitude.formulation",
            f"the scene integrates the rates alone ({own.name!r}): {value!r} would add an "
            "attitude it does not have",
        )
    if own.reduced and output.get("azimuth") is not True and not more:
        raise SceneError(
            "attitude.formulation",
            f"the scene reduces the attitude to the direction of its forces ({own.name!r} "
            f"without output.azimuth): {value!r} would add the azimuth about it (set "
            "output.azimuth = true to compare the whole attitude)",
        )
    attitude = dict(data.get("attitude", {}))
    attitude["formulation"] = value
    if not target.chart:
        attitude.pop("max_chart_angle", None)
    data["attitude"] = attitude
    if target.reduced:
        output["azimuth"] = True
    else:
        output.pop("azimuth", None)
    data["output"] = output
    return data


def _check_inertia(inertia: tuple[Number, Number, Number]) -> None:
    A, B, C = (exact_fraction(v) for v in inertia)
    text = dict(zip("ABC", inertia, strict=True))  # as written: float() overflows past 1e308
    for name, v in zip("ABC", (A, B, C), strict=True):
        if v <= 0:
            raise SceneError("body.inertia", f"moment {name} must be > 0, got {v}")
    for (n1, a), (n2, b), (n3, c) in (
        (("A", A), ("B", B), ("C", C)),
        (("B", B), ("C", C), ("A", A)),
        (("C", C), ("A", A), ("B", B)),
    ):
        if a + b < c:
            raise SceneError(
                "body.inertia",
                f"violates the triangle inequality {n1} + {n2} >= {n3} "
                f"({text[n1]} + {text[n2]} < {text[n3]}): no rigid body has these moments",
            )


def _parse_attitude(kind: str, value: Any) -> tuple[str, Any]:
    where = f"initial.{kind}"
    if kind == "rodrigues":
        return kind, vector(value, where, 3)
    if kind == "quaternion":
        q = vector(value, where, 4)
        unit, norm = unit_length(q, _UNIT_TOL)
        if not unit:
            raise SceneError(
                where, f"is not a rotation: a unit quaternion is needed, norm is {norm}"
            )
        return kind, q
    if not isinstance(value, list | tuple) or len(value) != 3:
        raise SceneError(where, "must be a 3x3 list of rows")
    rows = tuple(vector(row, f"{where}[{i}]", 3) for i, row in enumerate(value))
    # Rows of a rotation are unit vectors; checked exactly first (float() overflows past 1e308).
    for i, row in enumerate(rows):
        if not unit_length(row, _UNIT_TOL)[0]:
            raise SceneError(where, f"is not a rotation: row {i} is not a unit vector")
    M = np.array([[float(exact_fraction(v)) for v in row] for row in rows])
    defect = float(np.max(np.abs(M.T @ M - np.eye(3))))
    det = float(np.linalg.det(M))
    if defect > _UNIT_TOL or det <= 0:
        raise SceneError(
            where,
            f"is not a rotation: needs RᵀR = I and det R = +1 (max |RᵀR − I| = {defect:.3g}, "
            f"det R = {det:.17g})",
        )
    return kind, rows
