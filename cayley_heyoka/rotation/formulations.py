"""The rotation family's formulations: one small object each, declaring what it integrates and
what it supports.

``attitude.formulation`` names one of :data:`FORMULATIONS`; the scene keeps the name
(:attr:`.scene.RigidBody.formulation`) and :attr:`.scene.RigidBody.form` is its
:class:`Formulation`. Every part of the family that differs between formulations — the scene's
checks, the model's attitude and its numbers, the invariable-plane events' numbers of a table,
the consistency check's twin — reads the declaration here rather than comparing names, as
poliastro's propagators declare the orbits they take. The module is light (no heyoka): the
model's and the numbers' parts are named, and imported at their first call
(:func:`~cayley_heyoka.core.families.later`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from ..core.errors import SceneError
from ..core.families import later, named

_MODEL = "cayley_heyoka.rotation.model"
_NUMBERS = "cayley_heyoka.rotation.numbers"


@dataclass(frozen=True, eq=False)
class Formulation:
    """How a rigid-body scene integrates the attitude.

    Attributes
    ----------
    name
        The value of ``attitude.formulation``.
    state
        The attitude's state variables, after the rates p, q, r (empty: the rates alone).
    chart
        The state is a chart of Rodrigues parameters, re-based by a terminal event
        (:mod:`.charts`): ``attitude.max_chart_angle`` is its.
    reduced
        The state is the attitude up to a rotation about the one space direction the forces
        see (the Euler–Poisson reduction, :mod:`.poisson`): that direction is compiled in, and
        ``output.azimuth`` completes the attitude (:mod:`.azimuth`).
    unforced, forced
        Why a torque-free (a forced) body is refused: the scene's error; None where it is taken.
    twin
        The formulation :func:`.closed_form_check.check_twin` runs beside it (None: the check
        needs an attitude).
    element_check
        Whether Cayley's 1846 element check (:mod:`.element_check`) applies: it needs the
        whole attitude integrated.
    attitude
        ``(body, precision, pars, rates, inertia, values) -> _Attitude``: the attitude's part of
        the model (:mod:`.model`); None for the rates alone.
    numbers
        ``(body, precision, q0, momentum) -> (initial, values)``: the attitude's initial state
        and parameters (:func:`.numbers.numbers`; ``momentum``: L in space, for the
        invariable-plane events of a torque-free body, or None); None for the rates alone.
    plane_numbers
        ``(held, momentum) -> values``: the parameters the invariable-plane events of a
        torque-free body hold for L in space ``momentum`` (``held(name)``: a parameter the
        table keeps), for :func:`.numbers.table`; None where the events hold none.
    """

    name: str
    state: tuple[str, ...] = ()
    chart: bool = False
    reduced: bool = False
    unforced: str | None = None
    forced: str | None = None
    twin: str | None = None
    element_check: bool = False
    attitude: Callable[..., Any] | None = None
    numbers: Callable[..., Any] | None = None
    plane_numbers: Callable[..., Any] | None = None

    def check_forces(self, forced: bool) -> None:
        """Raise :class:`SceneError` unless the formulation takes a body with (without) forces."""
        why = self.forced if forced else self.unforced
        if why is not None:
            raise SceneError("attitude.formulation", why)

    def __reduce__(self) -> tuple[Any, tuple[str]]:
        # By name: the named parts are closures, and one object per formulation is the rule.
        return formulation, (self.name,)


RODRIGUES = Formulation(
    "rodrigues",
    state=("lambda", "mu", "nu"),
    chart=True,
    twin="quaternion",
    element_check=True,
    attitude=later(_MODEL, "rodrigues_attitude"),
    numbers=later(_NUMBERS, "rodrigues_numbers"),
    plane_numbers=later(_NUMBERS, "chart_plane_numbers"),
)
QUATERNION = Formulation(
    "quaternion",
    state=("qw", "qx", "qy", "qz"),
    twin="rodrigues",
    element_check=True,
    attitude=later(_MODEL, "quaternion_attitude"),
    numbers=later(_NUMBERS, "quaternion_numbers"),
    plane_numbers=later(_NUMBERS, "space_plane_numbers"),
)
NONE = Formulation(
    "none",
    forced="'none' cannot carry a force function: the torque depends on the attitude",
)
POISSON = Formulation(
    "poisson",
    state=("gamma1", "gamma2", "gamma3"),
    reduced=True,
    unforced="'poisson' reduces a body whose forces see one fixed direction; this one has no "
    "force (use 'none' for the rates alone)",
    twin="quaternion",
    attitude=later(_MODEL, "poisson_attitude"),
    numbers=later(_NUMBERS, "poisson_numbers"),
)

#: Every formulation, by name (in the order the scene's error lists them).
BY_NAME = {f.name: f for f in (RODRIGUES, QUATERNION, NONE, POISSON)}
FORMULATIONS = tuple(BY_NAME)


def formulation(name: Any) -> Formulation:
    """The formulation ``attitude.formulation = name`` names.

    Raises
    ------
    SceneError
        ``attitude.formulation``: ``name`` is none of :data:`FORMULATIONS`.
    """
    return named(BY_NAME, "attitude.formulation", name)
