"""The Hamiltonian tables of a scene: ``[hamiltonian]`` and ``[initial]``.

``[hamiltonian]``
    ``model = "projectile"`` with ``g``, ``mu``, ``nu`` (Hamilton's example, Second Essay §24–27:
    H = ½|ϖ|² + g η₃ + ½{μ²(η₁² + η₂²) + ν² η₃²}), or ``H = "..."``: any Hamiltonian as text
    over ``eta1 … etaN``, ``varpi1 … varpiN`` and ``t``, or a split ``H1``, ``H2`` with the
    motion of H₁ in ``[hamiltonian.flow]``. ``formulation = "elements"`` integrates Hamilton's
    varying elements of the split instead of η, ϖ.
    ``model = "predominant_mass"`` with ``G``, ``central_mass`` and ``[[hamiltonian.bodies]]``
    (each a ``mass`` and either ``elements`` or ``position`` and ``velocity``): Hamilton's
    system with one predominant mass (Second Essay §31–39; :mod:`.predominant_mass`), integrated in
    canonical heliocentric coordinates or through Hamilton's elements of every body.
``[initial]``
    ``eta`` and ``varpi``: the coordinates and momenta at the start time (N each; N = 3 for
    the projectile). Not used by the predominant mass, whose bodies carry their own state.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import mpmath

from ..core.errors import SceneError
from ..core.expressions import uses_time
from ..core.precision import Number, exact_fraction, exceeds_pi, scene_mpf
from ..core.scene import check_keys, expression_text, number, vector
from ..core.vectors import cross, dot
from ..mechanics.kepler import ELEMENT_KEYS, Elements
from .formulations import FORMULATIONS as FORMULATIONS
from .formulations import Formulation, formulation
from .predominant_mass import system as planets

MODELS = ("projectile", "predominant_mass")
_MAX_DEGREES = 60
#: Bodies about the predominant mass: the element equations grow like N², and at N = 8 they
#: still compile in compact mode in seconds (docs/hamilton.md).
MAX_BODIES = 8
_PLANET_KEYS = ("G", "central_mass", "bodies")
#: Digits of the predominant mass's canonical starting state in :attr:`Hamiltonian.eta`.
STATE_DIGITS = 100


@dataclass(frozen=True)
class Hamiltonian:
    """A canonical system, and how to integrate it.

    Attributes
    ----------
    model
        ``"projectile"`` or ``"expression"`` (a user Hamiltonian in :attr:`text` or
        :attr:`split`).
    constants
        ``{"g", "mu", "nu"}`` of the projectile; empty for an expression.
    text
        The user Hamiltonian H, or None.
    split
        The user split (H₁, H₂), or None.
    flow
        The user's closed-form motion of H₁: ``{"eta1": text, …, "varpi1": text, …}`` over
        ``chi1 … chiN``, ``lambda1 … lambdaN`` and ``t``; or None.
    formulation
        ``"canonical"`` (η, ϖ by the canonical equations of H) or ``"elements"`` (Hamilton's
        varying elements χ, λ of the split, :mod:`.elements`). :attr:`form` declares what it
        integrates and needs (:mod:`.formulations`).
    eta, varpi
        Coordinates and momenta at the start time. For the predominant mass: the canonical
        heliocentric state, ξ of every body and pᵢ = mᵢx′ᵢ, as decimal text with
        :data:`STATE_DIGITS` digits (the model computes its own in the run's precision).
    bodies
        The bodies about the predominant mass (``model = "predominant_mass"``, whose
        :attr:`constants` are ``{"G", "central_mass"}``); empty otherwise.
    """

    model: str
    constants: Mapping[str, Number]
    text: str | None
    split: tuple[str, str] | None
    flow: Mapping[str, str] | None
    formulation: str
    eta: tuple[Number, ...]
    varpi: tuple[Number, ...]
    bodies: tuple[Body, ...] = ()

    @classmethod
    def parse(cls, tables: Mapping[str, Any]) -> Hamiltonian:
        table = tables.get("hamiltonian", {})
        keys = ["model", "H", "H1", "H2", "flow", "formulation", "g", "mu", "nu", *_PLANET_KEYS]
        check_keys(table, keys, "hamiltonian")
        given = [k for k in ("model", "H", "H1") if k in table]
        if len(given) != 1:
            raise SceneError(
                "hamiltonian",
                f"give one of model = {' | '.join(repr(m) for m in MODELS)}, H = '<expression>' "
                f"or H1 and H2 (a split with its flow); got {given or 'none'}",
            )
        form = formulation(table.get("formulation", "canonical"))
        model = table.get("model")
        if model is not None and model not in MODELS:
            raise SceneError("hamiltonian.model", f"must be one of {MODELS}, got {model!r}")
        if model == "predominant_mass":
            return cls._predominant_mass(tables, form)
        extra = [k for k in _PLANET_KEYS if k in table]
        if extra:
            raise SceneError(f"hamiltonian.{extra[0]}", "belongs to model = 'predominant_mass'")
        eta, varpi = _initial(tables, 3 if "model" in table else None)
        if model is not None:
            for key in ("H2", "flow"):
                if key in table:
                    raise SceneError(f"hamiltonian.{key}", "is built in for the projectile")
            constants = {}
            for key in ("g", "mu", "nu"):
                if key not in table:
                    raise SceneError(f"hamiltonian.{key}", "is required by the projectile")
                constants[key] = number(table[key], f"hamiltonian.{key}")
            return cls(model, constants, None, None, None, form.name, eta, varpi)
        extra = [k for k in ("g", "mu", "nu") if k in table]
        if extra:
            raise SceneError(f"hamiltonian.{extra[0]}", "belongs to model = 'projectile'")
        if "H" in table:
            for key in ("H2", "flow"):
                if key in table:
                    raise SceneError(f"hamiltonian.{key}", "goes with H1, not with H")
            if form.needs_flow:
                raise SceneError(
                    "hamiltonian.formulation",
                    f"{form.name!r} needs the split H1, H2 and the flow of H1 ([hamiltonian.flow])",
                )
            return cls("expression", {}, _text(table, "H"), None, None, form.name, eta, varpi)
        split = (_text(table, "H1"), _text(table, "H2"))
        flow = None
        if "flow" in table:
            flow = _flow(table["flow"], len(eta))
        elif form.needs_flow:
            raise SceneError(
                "hamiltonian.flow", f"is required by formulation = {form.name!r}: H1's motion"
            )
        return cls("expression", {}, None, split, flow, form.name, eta, varpi)

    @classmethod
    def _predominant_mass(cls, tables: Mapping[str, Any], form: Formulation) -> Hamiltonian:
        table = tables["hamiltonian"]
        for key in ("H2", "flow", "g", "mu", "nu"):
            if key in table:
                raise SceneError(
                    f"hamiltonian.{key}", "is not used by model = 'predominant_mass' (built in)"
                )
        if "initial" in tables:
            raise SceneError(
                "initial",
                "is not used by model = 'predominant_mass': each [[hamiltonian.bodies]] table "
                "gives its body's mass and state at the start time",
            )
        constants = {}
        for key, meaning in (("G", "the constant of gravitation"), ("central_mass", "M")):
            if key not in table:
                raise SceneError(
                    f"hamiltonian.{key}", f"is required by model = 'predominant_mass' ({meaning})"
                )
            constants[key] = number(table[key], f"hamiltonian.{key}", positive=True)
        bodies = tuple(_bodies(table.get("bodies"), form))
        _check_bodies(bodies, form, constants["G"], constants["central_mass"])
        eta, varpi = _canonical_state(bodies, constants["G"], constants["central_mass"])
        return cls("predominant_mass", constants, None, None, None, form.name, eta, varpi, bodies)

    @property
    def form(self) -> Formulation:
        """What :attr:`formulation` integrates and needs (:mod:`.formulations`)."""
        return formulation(self.formulation)

    @property
    def degrees(self) -> int:
        """Number of coordinates N (3 per body for the predominant mass)."""
        return len(self.eta)

    @property
    def time_dependent(self) -> bool:
        texts = [self.text] if self.text is not None else list(self.split or ())
        return any(uses_time(t) for t in texts)


def _text(table: Mapping[str, Any], key: str) -> str:
    if key not in table:
        raise SceneError(f"hamiltonian.{key}", "is required")
    return expression_text(table[key], f"hamiltonian.{key}")


def _initial(tables: Mapping[str, Any], n: int | None) -> tuple[tuple, tuple]:
    initial = tables.get("initial")
    if initial is None:
        raise SceneError("initial", "is required: eta and varpi at the start time")
    check_keys(initial, ["eta", "varpi"], "initial")
    for key in ("eta", "varpi"):
        if key not in initial:
            raise SceneError(f"initial.{key}", "is required")
    if n is None:
        n = _length(initial["eta"], "initial.eta")
    return vector(initial["eta"], "initial.eta", n), vector(initial["varpi"], "initial.varpi", n)


def _flow(table: Any, n: int) -> dict[str, str]:
    names = [f"eta{i + 1}" for i in range(n)] + [f"varpi{i + 1}" for i in range(n)]
    check_keys(table, names, "hamiltonian.flow")
    missing = [k for k in names if k not in table]
    if missing:
        raise SceneError(
            "hamiltonian.flow", f"must give every coordinate and momentum; missing {missing}"
        )
    return {k: _flow_text(table, k) for k in names}


def _flow_text(table: Mapping[str, Any], key: str) -> str:
    return expression_text(table[key], f"hamiltonian.flow.{key}")


def _length(value: Any, where: str) -> int:
    if not isinstance(value, list | tuple) or not 1 <= len(value) <= _MAX_DEGREES:
        raise SceneError(where, f"must be a list of 1 to {_MAX_DEGREES} numbers, got {value!r}")
    return len(value)


# ---------------------------------------------------------------------- the predominant mass
@dataclass(frozen=True)
class Body:
    """A body about the predominant mass, with its state at the start time.

    Attributes
    ----------
    mass
        m > 0.
    elements
        The classical elements ``a, e, inclination, node, argument_of_pericentre,
        mean_anomaly`` of its relative orbit in Hamilton's meaning (Kepler orbit of ξ with
        parameter G(M + m) and velocity (1 + m/M) x′, §8.3), or None.
    position, velocity
        ξ (relative to the predominant mass) and x′ (relative to the centre of gravity), or
        None when :attr:`elements` are given.
    """

    mass: Number
    elements: Mapping[str, Number] | None = None
    position: tuple[Number, ...] | None = None
    velocity: tuple[Number, ...] | None = None

    def state(self, central_mass: Number, G: Number) -> tuple[list, list]:
        """(ξ, x′) at the start time in mpmath, at the current precision."""
        if self.elements is None:
            return [_mpf(c) for c in self.position], [_mpf(c) for c in self.velocity]
        values = Elements(**{k: _mpf(v) for k, v in self.elements.items()})
        return planets.classical_state(values, _mpf(self.mass), _mpf(central_mass), _mpf(G))


def _mpf(value: Number) -> mpmath.mpf:
    return scene_mpf(value)


def _bodies(value: Any, form: Formulation) -> list[Body]:
    where = "hamiltonian.bodies"
    if value is None:
        raise SceneError(
            where,
            "is required by model = 'predominant_mass': one [[hamiltonian.bodies]] table per "
            "body, with its mass and elements (or position and velocity)",
        )
    if not isinstance(value, list | tuple) or not 1 <= len(value) <= MAX_BODIES:
        raise SceneError(
            where, f"must be an array of 1 to {MAX_BODIES} tables ([[hamiltonian.bodies]])"
        )
    return [_body(b, f"{where}[{i}]", form) for i, b in enumerate(value)]


def _body(table: Any, where: str, form: Formulation) -> Body:
    check_keys(table, ["mass", "elements", "position", "velocity"], where)
    if "mass" not in table:
        raise SceneError(f"{where}.mass", "is required")
    mass = number(table["mass"], f"{where}.mass", positive=True)
    cartesian = [k for k in ("position", "velocity") if k in table]
    if "elements" in table:
        if cartesian:
            raise SceneError(
                where, f"give either elements or position and velocity, not both ({cartesian})"
            )
        return Body(mass, elements=_elements(table["elements"], f"{where}.elements", form))
    if len(cartesian) != 2:
        raise SceneError(where, "needs its state: elements = {a, e, …}, or position and velocity")
    position = vector(table["position"], f"{where}.position", 3)
    velocity = vector(table["velocity"], f"{where}.velocity", 3)
    if all(exact_fraction(c) == 0 for c in position):
        raise SceneError(f"{where}.position", "must not be the origin (the predominant mass)")
    return Body(mass, position=position, velocity=velocity)


def _elements(table: Any, where: str, form: Formulation) -> dict[str, Number]:
    check_keys(table, ELEMENT_KEYS, where)
    missing = [k for k in ELEMENT_KEYS if k not in table]
    if missing:
        raise SceneError(where, f"missing {missing}")
    values = {k: number(table[k], f"{where}.{k}") for k in ELEMENT_KEYS}
    if exact_fraction(values["a"]) <= 0:
        raise SceneError(f"{where}.a", f"must be > 0, got {values['a']}")
    e = exact_fraction(values["e"])
    if not 0 <= e < 1:
        raise SceneError(
            f"{where}.e",
            f"must be in [0, 1), got {values['e']}: Hamilton's bodies are bound to the "
            "predominant mass (give another orbit by position and velocity, with formulation = "
            "'canonical')",
        )
    inclination = exact_fraction(values["inclination"])
    if inclination < 0 or exceeds_pi(values["inclination"]):
        raise SceneError(f"{where}.inclination", f"must be in [0, π], got {values['inclination']}")
    if form.ellipses:
        if e == 0:
            raise SceneError(f"{where}.e", "must be > 0 " + _CIRCULAR)
        if inclination == 0:
            raise SceneError(f"{where}.inclination", "must not be 0 " + _PLANAR)
    return values


_CIRCULAR = (
    "with formulation = 'elements': on a circular orbit the pericentre, hence ϖ and τ, is "
    "undefined and the element equations are singular; use formulation = 'canonical'"
)
_PLANAR = (
    "with formulation = 'elements': in the reference plane (sin i = 0) the node ν is undefined "
    "and the element equations are singular; use formulation = 'canonical', or tilt the axes"
)


def _canonical_state(bodies: tuple[Body, ...], G: Number, M: Number) -> tuple[tuple, tuple]:
    """(ξ of every body, pᵢ = mᵢx′ᵢ of every body) at the start time, as decimal text."""
    with mpmath.workdps(STATE_DIGITS + 10):
        states = [b.state(M, G) for b in bodies]
        eta = [c for x, _ in states for c in x]
        varpi = [_mpf(b.mass) * c for b, (_, v) in zip(bodies, states, strict=True) for c in v]
        text = [mpmath.nstr(c, STATE_DIGITS, strip_zeros=False) for c in (*eta, *varpi)]
    return tuple(text[: len(eta)]), tuple(text[len(eta) :])


def _check_bodies(bodies: tuple[Body, ...], form: Formulation, G: Number, M: Number) -> None:
    """Refuse states the formulation cannot take: coincident bodies (H is singular), and for
    Hamilton's elements unbound, rectilinear, circular or planar relative orbits."""
    with mpmath.workdps(40):
        states = [b.state(M, G) for b in bodies]
        for k, (x, _) in enumerate(states):
            for i in range(k):
                d = [a - b for a, b in zip(x, states[i][0], strict=True)]
                if mpmath.sqrt(dot(d, d)) <= mpmath.mpf(10) ** -30 * mpmath.sqrt(dot(x, x)):
                    raise SceneError(
                        f"hamiltonian.bodies[{k}]",
                        f"starts at the position of hamiltonian.bodies[{i}]: their distance is "
                        "0 and H is singular there",
                    )
        if not form.ellipses:
            return
        for k, (body, (x, xp)) in enumerate(zip(bodies, states, strict=True)):
            if body.elements is not None:
                continue  # checked with the elements: bound, e > 0, sin i > 0
            where = f"hamiltonian.bodies[{k}].velocity"
            m, Mf, Gf = _mpf(body.mass), _mpf(M), _mpf(G)
            mu = (1 + m / Mf) * dot(xp, xp) / 2 - Gf * Mf / mpmath.sqrt(dot(x, x))
            if mu >= 0:
                raise SceneError(
                    where,
                    f"gives an unbound relative orbit (μ = {mpmath.nstr(mu, 6)} ≥ 0): Hamilton's "
                    "elements need an ellipse; use formulation = 'canonical'",
                )
            _check_exact_state(body, where, M, G)


def _check_exact_state(body: Body, where: str, M: Number, G: Number) -> None:
    """Rectilinear, planar and circular relative orbits, decided exactly in rationals."""
    x = [exact_fraction(c) for c in body.position]
    xp = [exact_fraction(c) for c in body.velocity]
    L = cross(x, xp)
    if all(c == 0 for c in L):
        raise SceneError(where, "gives rectilinear motion (ξ × x′ = 0): λ = 0 has no orbit plane")
    if L[0] == 0 and L[1] == 0:
        raise SceneError(
            where, "puts the orbit in the reference plane (i = 0 or π), refused " + _PLANAR
        )
    m, Mf, Gf = (exact_fraction(v) for v in (body.mass, M, G))
    v = [(1 + m / Mf) * c for c in xp]
    # e = 0 exactly: ξ·v = 0 and |v|² = K/r, i.e. |v|⁴ |ξ|² = K².
    if dot(x, v) == 0 and dot(v, v) ** 2 * dot(x, x) == (Gf * (Mf + m)) ** 2:
        raise SceneError(where, "gives a circular relative orbit (e = 0), refused " + _CIRCULAR)
