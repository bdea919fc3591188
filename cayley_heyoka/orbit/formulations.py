"""The orbit family's formulations: one small object each, declaring what it integrates and
what it supports.

``orbit.formulation`` names one of :data:`FORMULATIONS`; the scene keeps the name
(:attr:`.scene.Orbit.formulation`) and :attr:`.scene.Orbit.form` is its :class:`Formulation`.
The scene's checks, the validation, the model, its numbers and the twin check read the
declaration here rather than comparing names, as poliastro's propagators declare the orbits
they take (an ellipse only, or any conic). The module is light (no heyoka): the model's part
is named, and imported at its first call (:func:`~cayley_heyoka.core.families.later`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from ..core.families import later, named

_MODEL = "cayley_heyoka.orbit.model"


@dataclass(frozen=True, eq=False)
class Formulation:
    """How an orbit scene is integrated.

    Attributes
    ----------
    name
        The value of ``orbit.formulation``.
    state
        The state's variables, in order.
    build
        ``(builder, variant)``: the formulation's system, outputs and terminal events on a
        :class:`.model.Builder` (``variant``: of :mod:`.tilt`, None without variants).
    cartesian
        The state is the position and velocity in the fixed frame (each variable starts at
        its own component of ``orbit.position``, ``orbit.velocity``).
    deviation
        The state is the deviation from an osculating ellipse (:mod:`.encke`): its start
        comes with that ellipse, from the model's numbers.
    hyperbolic
        Takes an orbit that starts with e ≥ 1 (parabolic or hyperbolic); False: it follows an
        osculating ellipse.
    gauge
        The state has Cayley's gauge Σ (``orbit.sigma0``: where the departure point sits).
    revolutions
        The state has ρ, whose whole revolutions are kept out of it (:mod:`.revolutions`).
    angles
        The orbit plane is Cayley's angles Θ, Σ, Φ in the state, singular on the reference plane
        (cosec Φ): the run hands over to a tilted frame below ``orbit.equatorial_limit``
        (:mod:`.tilt`), and with a limit of 0 cannot start on the plane.
    twin
        The default twin of :func:`.cartesian_check.check_twin`: a formulation, or
        ``"precision"`` (the same scene at the next precision).
    """

    name: str
    state: tuple[str, ...]
    build: Callable[..., Any]
    cartesian: bool = False
    deviation: bool = False
    hyperbolic: bool = True
    gauge: bool = False
    revolutions: bool = False
    angles: bool = False
    twin: str = "cartesian"

    def __reduce__(self) -> tuple[Any, tuple[str]]:
        # By name: the model's part is a closure, and one object per formulation is the rule.
        return formulation, (self.name,)


CAYLEY = Formulation(
    "cayley",
    ("r", "rdot", "rho", "h", "Theta", "Sigma", "Phi"),
    later(_MODEL, "Builder.cayley"),
    gauge=True,
    revolutions=True,
    angles=True,
)
QUATERNION = Formulation(
    "quaternion",
    ("r", "rdot", "rho", "h", "qw", "qx", "qy", "qz"),
    later(_MODEL, "Builder.quaternion"),
    gauge=True,
    revolutions=True,
)
CARTESIAN = Formulation(
    "cartesian",
    ("x", "y", "z", "vx", "vy", "vz"),
    later(_MODEL, "Builder.cartesian"),
    cartesian=True,
    twin="precision",
)
ENCKE = Formulation(
    "encke",
    ("dx", "dy", "dz", "dvx", "dvy", "dvz", "psi"),
    later(_MODEL, "Builder.encke"),
    deviation=True,
    hyperbolic=False,
)

#: Every formulation, by name (in the order the scene's error lists them).
BY_NAME = {f.name: f for f in (CAYLEY, QUATERNION, CARTESIAN, ENCKE)}
FORMULATIONS = tuple(BY_NAME)


def formulation(name: Any) -> Formulation:
    """The formulation ``orbit.formulation = name`` names.

    Raises
    ------
    SceneError
        ``orbit.formulation``: ``name`` is none of :data:`FORMULATIONS`.
    """
    return named(BY_NAME, "orbit.formulation", name)
