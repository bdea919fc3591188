"""The orbit tables of a scene: ``[orbit]``, ``[perturbations.*]``, ``[reference_plane]``."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any

from ..core.errors import SceneError
from ..core.precision import Number, exact_fraction, exceeds_pi
from ..core.scene import check_keys, number, vector
from ..mechanics.kepler import ELEMENT_KEYS
from .disturbing import ThirdBody, Zonal, parse_perturbations
from .formulations import FORMULATIONS as FORMULATIONS
from .formulations import Formulation, formulation

#: Default of ``orbit.equatorial_limit``: below this sin Φ the Cayley angles are carried on a
#: tilted working frame (:mod:`.tilt`; docs/orbits.md, "Near-equatorial orbits").
EQUATORIAL_LIMIT = "1e-3"


@dataclass(frozen=True)
class PlaneMotion:
    """The reference plane: θ′ = θ′₀ + θ̇′t, φ′ = φ′₀ + φ̇′t, and σ′.

    σ′ follows from the departure-point condition dσ′ = cos φ′ dθ′ unless ``sigma_rate`` is
    given, in which case σ′ = σ′₀ + σ̇′t and the origin x₁ is not a departure point.
    """

    theta0: Number = 0
    theta_rate: Number = 0
    phi0: Number = 0
    phi_rate: Number = 0
    sigma0: Number = 0
    sigma_rate: Number | None = None

    @classmethod
    def parse(cls, table: Mapping[str, Any]) -> PlaneMotion:
        keys = ["theta0", "theta_rate", "phi0", "phi_rate", "sigma0", "sigma_rate"]
        check_keys(table, keys, "reference_plane")
        values = {k: number(table[k], f"reference_plane.{k}") for k in keys if k in table}
        return cls(**values)

    @property
    def departure_point(self) -> bool:
        return self.sigma_rate is None


@dataclass(frozen=True)
class Orbit:
    """A body about a central mass, disturbed by Ω.

    Attributes
    ----------
    mu
        Gravitational parameter of the central mass (plus the body's), > 0.
    initial
        ``("cartesian", position, velocity)`` in the fixed frame, or ``("elements", values)``
        with the classical elements referred to the reference plane at the start time.
    formulation
        ``"cayley"`` (r, ṙ, ρ, h, Θ, Σ, Φ), ``"quaternion"`` (r, ṙ, ρ, h and the orbit frame as
        a quaternion: regular at every inclination), ``"cartesian"`` or ``"encke"`` (the
        deviation from an osculating ellipse, rectified at every apocentre). :attr:`form`
        declares what it integrates and supports (:mod:`.formulations`).
    sigma0
        Gauge Σ at the start time (where the departure point sits on the orbit).
    equatorial_limit
        ε in [0, ¼]: where sin Φ falls to ε/2 the Cayley formulation hands over to a tilted
        working frame, and back where it rises to 2ε (0: never; :mod:`.tilt`); the
        ``equatorial`` event of any formulation records where sin Φ crosses it.
    perturbations
        Disturbing-function terms (:mod:`.disturbing`).
    plane
        Motion of the reference plane, or None when it is the fixed frame.
    """

    mu: Number
    initial: tuple
    formulation: str
    sigma0: Number
    equatorial_limit: Number
    perturbations: tuple
    plane: PlaneMotion | None
    #: Values derived from the fields, by what they are and the precision they were computed
    #: in (:func:`.numbers.initial_cartesian`: the validation, the start variant and the
    #: initial state each need the start's position and velocity). Not part of the orbit's
    #: value: equality, hashing and ``dataclasses.replace`` ignore it.
    derived: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    @classmethod
    def parse(cls, tables: Mapping[str, Any]) -> Orbit:
        table = tables.get("orbit", {})
        keys = [
            "mu",
            "position",
            "velocity",
            "elements",
            "formulation",
            "sigma0",
            "equatorial_limit",
        ]
        check_keys(table, keys, "orbit")
        if "mu" not in table:
            raise SceneError("orbit.mu", "is required: the central gravitational parameter")
        mu = number(table["mu"], "orbit.mu", positive=True)
        initial = _parse_initial(table)
        form = formulation(table.get("formulation", "cayley"))
        if not form.gauge and "sigma0" in table:
            raise SceneError("orbit.sigma0", f"has no meaning for formulation = {form.name!r}")
        sigma0 = number(table.get("sigma0", 0), "orbit.sigma0")
        limit = number(table.get("equatorial_limit", EQUATORIAL_LIMIT), "orbit.equatorial_limit")
        if 0 < exact_fraction(limit) < Fraction(1, 10**100):
            # The hand-back compares sin²Φ with (2ε)², which must not underflow.
            raise SceneError(
                "orbit.equatorial_limit",
                f"must be 0 (no hand-over) or at least 1e-100 (no precision resolves the orbit "
                f"plane to a smaller sin Φ), got {limit}",
            )
        if not 0 <= exact_fraction(limit) <= Fraction(1, 4):
            # Above ¼ the tilted frame would itself come near its plane (sin Φ_W ≥ √(1 − 4ε²)).
            raise SceneError(
                "orbit.equatorial_limit",
                f"must be in [0, 1/4] (sin Φ where the Cayley angles hand over to a tilted "
                f"frame, and back at twice it), got {limit}",
            )
        perturbations = parse_perturbations(tables.get("perturbations", {}))
        plane = (
            PlaneMotion.parse(tables["reference_plane"]) if "reference_plane" in tables else None
        )
        return cls(mu, initial, form.name, sigma0, limit, perturbations, plane)

    @property
    def form(self) -> Formulation:
        """What :attr:`formulation` integrates and supports (:mod:`.formulations`)."""
        return formulation(self.formulation)

    def term(self, kind: type) -> Any:
        """The perturbation of the given class, or None."""
        return next((p for p in self.perturbations if isinstance(p, kind)), None)

    @property
    def time_dependent(self) -> bool:
        return any(p.time_dependent for p in self.perturbations)

    @property
    def zonal(self) -> Zonal | None:
        return self.term(Zonal)

    @property
    def third_body(self) -> ThirdBody | None:
        return self.term(ThirdBody)


def with_formulation(scene: Any, value: str) -> dict[str, Any]:
    """The orbit scene's dictionary integrated in formulation ``value``
    (``Family.with_formulation``, :meth:`cayley_heyoka.core.families.Family.in_formulation`).

    The motion is the same in every formulation; ``orbit.sigma0``, the gauge of Cayley's
    angles, is dropped for the Cartesian and Encke ones, which have none (the position and
    velocity do not depend on it).

    Raises
    ------
    SceneError
        ``orbit.formulation``: ``value`` is unknown.
    """
    data = scene.to_dict()
    if value == scene.model.formulation:
        return data
    target = formulation(value)
    orbit = dict(data["orbit"])
    orbit["formulation"] = value
    if not target.gauge:
        orbit.pop("sigma0", None)
    data["orbit"] = orbit
    return data


def _parse_initial(table: Mapping[str, Any]) -> tuple:
    cartesian = [k for k in ("position", "velocity") if k in table]
    if "elements" in table:
        if cartesian:
            raise SceneError(
                "orbit", f"give either elements or position and velocity, not both ({cartesian})"
            )
        el = table["elements"]
        check_keys(el, ELEMENT_KEYS, "orbit.elements")
        missing = [k for k in ELEMENT_KEYS if k not in el]
        if missing:
            raise SceneError("orbit.elements", f"missing {missing}")
        values = {k: number(el[k], f"orbit.elements.{k}") for k in ELEMENT_KEYS}
        if exact_fraction(values["a"]) <= 0:
            raise SceneError("orbit.elements.a", f"must be > 0, got {values['a']}")
        e = exact_fraction(values["e"])
        if not 0 <= e < 1:
            raise SceneError(
                "orbit.elements.e",
                f"must be in [0, 1) for an elliptic element set, got {values['e']}; give a "
                "hyperbolic or parabolic orbit by position and velocity",
            )
        inclination = values["inclination"]
        if exact_fraction(inclination) < 0 or exceeds_pi(inclination):
            raise SceneError(
                "orbit.elements.inclination", f"must be in [0, π], got {values['inclination']}"
            )
        return ("elements", values)
    if len(cartesian) != 2:
        raise SceneError(
            "orbit", "needs the initial state: position and velocity, or elements = {a, e, …}"
        )
    position = vector(table["position"], "orbit.position", 3)
    velocity = vector(table["velocity"], "orbit.velocity", 3)
    if all(exact_fraction(c) == 0 for c in position):
        raise SceneError("orbit.position", "must not be the origin (the central mass)")
    return ("cartesian", position, velocity)
