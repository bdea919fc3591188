"""Build the heyoka system of an orbit scene, in the formulation the scene asks for.

* ``cayley``: Cayley's (r, ṙ, ρ, h, Θ, Σ, Φ) (:mod:`.equations`), with a terminal event that
  stops the run when sin Φ falls to ``orbit.equatorial_limit`` (cosec Φ makes Θ and Σ lose
  accuracy like ε/sin Φ there: see docs/orbits.md).
* ``quaternion``: (r, ṙ, ρ, h) and the orbit frame as a unit quaternion: regular everywhere.
* ``cartesian``: ẍ = −μx/r³ + ∇Ω, the independent check and a formulation of its own.
* ``encke``: the deviation from an osculating Kepler orbit, rectified at every apocentre by a
  terminal event (:mod:`.encke`); the same force model as ``cartesian``, with its rounding
  carried by a state ~10⁻⁴ of the orbit.

Ω is built once, on Cartesian placeholders, for the monitors; its gradient is built at the
formulation's position, with |x|² as the formulation has it (:func:`.disturbing.force`). Only
the terms the scene names are compiled; the reference plane enters the Cayley equations only
when it moves.
"""

from __future__ import annotations

import threading
from collections.abc import Mapping
from typing import Any

import heyoka as hy
import mpmath

from ..core import vectors
from ..core.errors import SceneError
from ..core.expressions import parse_expression
from ..core.model import EventSpec, Model, ParTable, TerminalSpec
from ..core.precision import exact_fraction, scene_mpf
from ..core.scene import Scene
from . import equations as eq
from .disturbing import (
    Context,
    Gradient,
    UserPotential,
    force,
    perturbation_key,
    term_functions,
)
from .encke import STATE as ENCKE
from .encke import Encke
from .family import FAMILY
from .numbers import (
    GUARD_DIGITS,
    initial_cartesian,
    initial_field,
    initial_state,
    plane_angles,
    plane_angles_at,
    sin_phi,
    start_time,
    start_variant,
    variant_numbers,
)
from .revolutions import Revolutions
from .scene import Orbit, PlaneMotion
from .tilt import (
    LEVEL,
    TILTED,
    EquatorialHandover,
    reference_normal,
    sin2_on_reference,
)

__all__ = ["build_model", "initial_cartesian", "initial_state", "plane_angles_at", "validate"]

CARTESIAN = ("x", "y", "z", "vx", "vy", "vz")
CAYLEY = ("r", "rdot", "rho", "h", "Theta", "Sigma", "Phi")
QUATERNION = ("qw", "qx", "qy", "qz")
#: The events the family offers (its record, :data:`.family.FAMILY`, declares them).
EVENTS = FAMILY.events


def build_model(scene: Scene) -> Model:
    """Turn a validated orbit scene into a :class:`~cayley_heyoka.core.model.Model`, its
    numbers from :func:`~cayley_heyoka.orbit.numbers.numbers`.

    A ``cayley`` scene that can approach the reference plane has two variants (:mod:`.tilt`):
    the run starts with the one its start's sin Φ calls for, and builds the other when a
    terminal event hands over to it. A variant's handlers and equations read no number of
    the scene they were built for (the run's state and parameters go on), so the variants
    of a structure's first scene serve every scene of it.
    """
    first = start_variant(scene)
    if first is None:
        return _build(scene, None)
    built: dict[str, Model] = {}
    lock = threading.Lock()

    def variant(name: str) -> Model:
        with lock:
            if name not in built:
                built[name] = _build(scene, name, variant)
            return built[name]

    return variant(first)


def _build(scene: Scene, variant: str | None, variants: Any = None) -> Model:
    orbit: Orbit = scene.model
    prec = scene.integrator.precision
    given = variant_numbers(scene, variant)
    values = given.values
    pars = ParTable(prec)
    mu = pars.add("mu", values["mu"], "orbit.mu")
    plane = _plane_expressions(orbit.plane, pars, values)
    X = list(hy.make_vars(*CARTESIAN[:3]))
    ctx = Context(mu, pars, prec.dps + GUARD_DIGITS, values)
    omegas = term_functions(orbit.perturbations, X, ctx)
    for term, omega in zip(orbit.perturbations, omegas, strict=True):
        if not isinstance(term, UserPotential):  # a text records itself as it is parsed
            pars.source(f"perturbations.{perturbation_key(term)}", omega)

    b = Builder(orbit, pars, plane, mu, omegas, X, prec, ctx, values)
    orbit.form.build(b, variant)

    monitors, conserved = _monitors(orbit, b, ctx)
    wanted = scene.output.monitors
    if wanted is not None:
        for name in wanted:
            if name not in monitors:
                raise SceneError(
                    "output.monitors",
                    f"{name!r} is not available here; available: {list(monitors)}",
                )
        monitors = {k: v for k, v in monitors.items() if k in wanted}
        conserved = tuple(k for k in conserved if k in wanted)
    events = _events(scene, orbit, b, pars)
    initial = list(given.initial_state)
    model = Model(
        "orbit", b.system, initial, pars, b.outputs, monitors, conserved, events, b.terminal
    )
    _provenance(model, orbit)
    if variant is not None:
        # Tilted, the state does not carry Θ, Σ on the reference plane: NaN is their value.
        model.unbounded = ("Theta", "Sigma")
        model.variant, model.variants = variant, variants
    return model


def _provenance(model: Model, orbit: Orbit) -> None:
    """The scene fields of the state and of the parameters (:meth:`Model.initial_field`,
    :attr:`ParTable.fields`)."""
    if orbit.initial[0] == "cartesian":
        start = "orbit.position, orbit.velocity"
        own = {a: f"orbit.position[{i}]" for i, a in enumerate(CARTESIAN[:3])}
        own |= {a: f"orbit.velocity[{i}]" for i, a in enumerate(CARTESIAN[3:])}
    else:
        start, own = "orbit.elements", {}
    if orbit.form.cartesian:
        model.initial_fields = {v: own.get(v, start) for v in model.state_names}
    else:
        model.initial_fields = dict.fromkeys(model.state_names, start)
    derived = {
        "third_body.": "perturbations.third_body",
        "zonal.": "perturbations.zonal, orbit.mu",
        "orbit.equatorial_limit": "orbit.equatorial_limit",
        "reference_plane.": None,
    }
    pars = model.pars
    for i, name in enumerate(pars.names):
        if pars.fields[i] is None:
            field = next((f or name for k, f in derived.items() if name.startswith(k)), start)
            pars.fields[i] = field


def validate(scene: Scene) -> None:
    """Geometric constraints that need the start time: raise :class:`SceneError` if violated."""
    orbit: Orbit = scene.model
    # In the run's precision and guard digits: an eccentricity of 1 − 10⁻³² is an ellipse to a
    # quad run, and 1 to 30 digits.
    with mpmath.workdps(scene.integrator.precision.dps + GUARD_DIGITS):
        t = start_time(scene)
        x, v = initial_cartesian(orbit, t)
        H = vectors.cross(x, v)
        h = mpmath.sqrt(vectors.dot(H, H))
        where = initial_field(orbit)
        if h == 0:
            raise SceneError(
                where, "gives rectilinear motion (x × v = 0): the orbit plane is undefined"
            )
        r = mpmath.sqrt(vectors.dot(x, x))
        mu = scene_mpf(orbit.mu)
        energy = vectors.dot(v, v) / 2 - mu / r
        e = mpmath.sqrt(max(mpmath.mpf(0), 1 + 2 * energy * h * h / (mu * mu)))
        q = h * h / (mu * (1 + e))
        if not orbit.form.hyperbolic and e >= 1:
            raise SceneError(
                "orbit.formulation",
                f"{orbit.formulation!r} follows an osculating ellipse, but the orbit starts with "
                f"e = {mpmath.nstr(e, 6)} ≥ 1 (parabolic or hyperbolic); use 'cartesian'",
            )
        third = orbit.third_body
        if third is not None and third.degree is not None:
            apo = mpmath.inf if e >= 1 else q * (1 + e) / (1 - e)
            if apo >= third.pericentre:
                raise SceneError(
                    "perturbations.third_body.degree",
                    f"the Legendre expansion assumes the body inside the perturber's orbit, but "
                    f"the orbit's apocentre {mpmath.nstr(apo, 6)} is not below the perturber's "
                    f"pericentre {mpmath.nstr(third.pericentre, 6)}; drop 'degree' for the exact Ω",
                )
        plane = orbit.plane
        turning = plane is not None and (
            exact_fraction(plane.theta_rate) != 0 or exact_fraction(plane.phi_rate) != 0
        )
        # Without a disturbing function or a turning reference plane Θ, Σ, Φ are constant and
        # no cosec Φ is compiled: any inclination will do. With a limit the run starts on the
        # tilted frame below it (:mod:`.tilt`); without one, the equations need sin Φ ≠ 0.
        if orbit.form.angles and (orbit.perturbations or turning):
            if exact_fraction(orbit.equatorial_limit) == 0 and sin_phi(orbit, t) == 0:
                raise SceneError(
                    "orbit.formulation",
                    f"{orbit.formulation!r} with orbit.equatorial_limit = 0 needs sin Φ ≠ 0, but "
                    "the orbit "
                    "starts in the reference plane (Θ and Σ are undefined there: cosec Φ in "
                    "their equations); give a limit > 0 (the run then starts on a tilted frame) "
                    "or use formulation = 'quaternion' or 'cartesian'",
                )


# ---------------------------------------------------------------------- the formulations
class Builder:
    """Collects the system, the position and velocity expressions and the outputs; each
    formulation's method (:attr:`.formulations.Formulation.build`) fills them."""

    def __init__(self, orbit, pars, plane, mu, omegas, X, precision, ctx, values) -> None:
        self.orbit, self.pars, self.plane, self.mu = orbit, pars, plane, mu
        self.values: Mapping[str, Any] = values  # the model's numbers, by parameter name
        self.precision, self.ctx = precision, ctx
        self.omegas, self.X = omegas, X
        self.Omega = None if not omegas else omegas[0] if len(omegas) == 1 else hy.sum(omegas)
        self.perturbed = bool(omegas)
        self.system: list[tuple[Any, Any]] = []
        self.outputs: dict[str, Any] = {}
        self.terminal: list[TerminalSpec] = []
        self.position: list[Any] = []
        self.velocity: list[Any] = []
        self.momentum: list[Any] = []  # x × v
        self.normal: list[Any] = []  # of the orbit, in frame 0
        self.node_function: Any = None
        self.apsis_function: Any = None
        self.radius: Any = None

    def equatorial_limit(self) -> Any:
        """The parameter holding ε = orbit.equatorial_limit (allocated on first use)."""
        name = "orbit.equatorial_limit"
        if name in self.pars.names:
            return hy.par[self.pars.index(name)]
        return self.pars.add(name, self.values[name])

    def force(self, x: list[Any], r2: Any, radius: Any = None) -> Gradient | None:
        """∇Ω at the position x, |x|² = r2, or at r x̂ for ``x`` = x̂ and ``radius`` = r
        (:func:`.disturbing.force`); None without a disturbing function."""
        if not self.perturbed:
            return None
        return force(self.orbit.perturbations, self.omegas, self.X, x, r2, self.ctx, radius)

    def at_position(self, expr: Any) -> Any:
        """An expression of the Cartesian placeholders, composed with the position."""
        return hy.subs(expr, {str(x): p for x, p in zip(self.X, self.position, strict=True)})

    def cartesian(self, variant: None = None) -> None:
        """ẍ = −μx/r³ + ∇Ω (no variants)."""
        x = self.X
        v = list(hy.make_vars(*CARTESIAN[3:]))
        rhs = eq.cartesian_rates(x, v, self.mu, self.force(x, vectors.dot(x, x)))
        self.system = list(zip([*x, *v], rhs, strict=True))
        self.position, self.velocity = x, v
        self.momentum = vectors.cross(x, v)
        self.outputs = dict(zip(CARTESIAN, [*x, *v], strict=True))
        self.node_function = vectors.dot(self._plane_normal(), x)
        self.apsis_function = vectors.dot(x, v)
        self.radius = hy.sqrt(vectors.dot(x, x))

    def encke(self, variant: None = None) -> None:
        """δ = x − y from the osculating ellipse y, and ψ = E/2, half its eccentric anomaly
        (:mod:`.encke`; the initial ellipse is among the numbers; no variants)."""
        d = list(hy.make_vars(*ENCKE[:3]))
        dv = list(hy.make_vars(*ENCKE[3:6]))
        psi = hy.make_vars(ENCKE[6])
        en = Encke(self.pars, self.precision, self.mu, self.values)
        y, ydot, parts = en.curve(psi)
        self.position = [y[i] + d[i] for i in range(3)]
        self.velocity = [ydot[i] + dv[i] for i in range(3)]
        # ∇Ω at y + δ: its part along the position joins the Kepler part's coefficients.
        g = self.force(self.position, en.distance(y, d, parts))
        acc = en.acceleration(y, d, parts, None if g is None else _total(g.central))
        if g is not None:
            for i in range(3):
                gi = g.component(i)
                if gi is not None:
                    acc[i] = acc[i] + gi
        rates = [*dv, *acc, parts["psi_rate"]]
        self.system = list(zip([*d, *dv, psi], rates, strict=True))
        x_, v_ = self.position, self.velocity
        self.momentum = vectors.cross(x_, v_)
        self.outputs = dict(zip(CARTESIAN, [*x_, *v_], strict=True))
        self.node_function = vectors.dot(self._plane_normal(), x_)
        self.apsis_function = vectors.dot(x_, v_)
        self.radius = hy.sqrt(vectors.dot(x_, x_))
        self.terminal.append(TerminalSpec(en.event(psi), 1, en, "rectifications"))

    def cayley(self, variant: str | None = None) -> None:
        """Cayley's equations; with ``variant`` (:mod:`.tilt`), on that working frame, with
        the terminal event that hands the run over to the other."""
        r, rdot, rho, h, Theta, Sigma, Phi = hy.make_vars(*CAYLEY)
        turns = self._revolutions(rho)
        u = turns.angle(rho) - Sigma
        if variant is None:
            axes, _ = eq.cayley_axes(Theta, Phi, u, self.plane)
            partials = self._partials(r, axes)
            rhs = eq.in_plane_rates(r, rdot, h, self.mu, partials[0], partials[1])
            rhs += eq.plane_rates(u, h, Phi, partials[2], self.plane, Theta)
            self.system = list(zip([r, rdot, rho, h, Theta, Sigma, Phi], rhs, strict=True))
            self._kinematics(r, rdot, h, axes)
            values = [r, rdot, turns.rho(rho), h, Theta, Sigma, Phi]
            self.outputs.update(zip(CAYLEY, values, strict=True))
            self.node_function = hy.sin(u)
            return
        # Allocated alike in both variants: they share one parameter table.
        eps = self.equatorial_limit()
        c, s = (self.pars.add(k, self.values[k]) for k in ("orbit.frame_cos", "orbit.frame_sin"))
        for name in ("orbit.theta_before", "orbit.sigma_before"):
            self.pars.add(name, self.values[name])
        tilted = variant == TILTED
        general, _ = eq.cayley_axes(Theta, Phi, u, self.plane, (c, s))
        axes = general if tilted else eq.cayley_axes(Theta, Phi, u, self.plane)[0]
        partials = self._partials(r, axes)
        rhs = eq.in_plane_rates(r, rdot, h, self.mu, partials[0], partials[1])
        rhs += eq.plane_rates(u, h, Phi, partials[2], self.plane, Theta, (c, s) if tilted else None)
        self.system = list(zip([r, rdot, rho, h, Theta, Sigma, Phi], rhs, strict=True))
        # Outputs, monitors and recorded events: one expression for both variants.
        self._kinematics(r, rdot, h, general)
        n = reference_normal(Theta, Phi, c, s)
        on_reference = hy.atan2(hy.sqrt(n[0] * n[0] + n[1] * n[1]), n[2])
        undefined = c / c  # 1 on the reference plane, NaN tilted (Θ, Σ are not carried)
        values = [r, rdot, turns.rho(rho), h, Theta * undefined, Sigma * undefined]
        values.append(c * Phi + s * on_reference)
        self.outputs.update(zip(CAYLEY, values, strict=True))
        if tilted:
            self.node_function = vectors.dot(self._plane_normal(), general.radial)
            back = sin2_on_reference(Theta, Phi, c, s) - 4 * eps * eps
            turn = EquatorialHandover(LEVEL, self.pars, self.precision)
            self.terminal.append(TerminalSpec(back, 1, turn, "equatorial_handovers"))
        else:
            self.node_function = hy.sin(u)
            # At ε/2, not ε: the tilted variant then starts clear of the equatorial event's
            # zero, which a root search starting on it could miss with the next one.
            turn = EquatorialHandover(TILTED, self.pars, self.precision)
            down = 2 * hy.sin(Phi) - eps
            self.terminal.append(TerminalSpec(down, -1, turn, "equatorial_handovers"))

    def quaternion(self, variant: None = None) -> None:
        """(r, ṙ, ρ, h) and the orbit frame as a unit quaternion (no variants)."""
        r, rdot, rho, h = hy.make_vars(*CAYLEY[:4])
        q = list(hy.make_vars(*QUATERNION))
        turns = self._revolutions(rho)
        angle = turns.angle(rho)
        axes = eq.quaternion_axes(q, angle)
        partials = self._partials(r, axes)
        rhs = eq.in_plane_rates(r, rdot, h, self.mu, partials[0], partials[1])
        rhs += eq.quaternion_rates(q, angle, h, partials[2])
        self.system = list(zip([r, rdot, rho, h, *q], rhs, strict=True))
        self._kinematics(r, rdot, h, axes)
        # Θ, Σ, Φ read off M₁₂ = M₀₁ᵀ ℛ(q) (docs/orbits.md, "The quaternion formulation"), for
        # output only.
        M02 = eq.quaternion_matrix(q)
        M12 = (
            M02
            if self.plane is None
            else vectors.matmul(vectors.transpose(self.plane.matrix()), M02)
        )
        Theta = hy.atan2(M12[0][2], -M12[1][2])
        Phi = hy.atan2(hy.sqrt(M12[0][2] ** 2 + M12[1][2] ** 2), M12[2][2])
        Sigma = hy.atan2(-M12[2][0], M12[2][1])
        values = [r, rdot, turns.rho(rho), h, Theta, Sigma, Phi]
        self.outputs.update(zip(CAYLEY, values, strict=True))
        self.outputs.update(zip(QUATERNION, q, strict=True))
        self.node_function = vectors.dot(self._plane_normal(), axes.radial)

    def _revolutions(self, rho: Any) -> Revolutions:
        """Whole turns of ρ kept out of the state (:mod:`.revolutions`; the state's ρ₀ is
        reduced among the numbers)."""
        turns = Revolutions(self.pars, self.precision, self.values, 2)
        self.terminal.append(TerminalSpec(turns.event(rho), 1, turns, "revolutions"))
        return turns

    def _partials(self, r, axes: eq.OrbitAxes) -> tuple:
        self.position = [r * c for c in axes.radial]
        g = self.force(axes.radial, None, radius=r)
        if g is None:
            return None, None, None
        return eq.cayley_partials(g, r, axes)

    def _kinematics(self, r, rdot, h, axes: eq.OrbitAxes) -> None:
        """x = r x̂₃, ẋ = ṙ x̂₃ + (h/r) ŷ₃ (§5), x × v = h n̂."""
        self.position = [r * c for c in axes.radial]
        self.velocity = [
            rdot * a + h / r * b for a, b in zip(axes.radial, axes.transverse, strict=True)
        ]
        self.normal = axes.normal
        self.momentum = [h * c for c in axes.normal]
        self.outputs = dict(zip(CARTESIAN, [*self.position, *self.velocity], strict=True))
        self.apsis_function = rdot
        self.radius = r

    def _plane_normal(self) -> list[Any]:
        if self.plane is None:
            return [hy.expression(0.0), hy.expression(0.0), hy.expression(1.0)]
        M01 = self.plane.matrix()
        return [M01[0][2], M01[1][2], M01[2][2]]


def _plane_expressions(
    motion: PlaneMotion | None, pars: ParTable, values: Mapping[str, Any]
) -> eq.ReferencePlane | None:
    if motion is None:
        return None

    def value(name: str, _: Any) -> Any:
        key = f"reference_plane.{name}"
        return pars.add(key, values[key])

    (theta, sigma, phi), (th1, sg1, ph1) = plane_angles(motion, hy.time, value)
    return eq.ReferencePlane(theta, sigma, phi, th1, sg1, ph1, motion.departure_point)


# ---------------------------------------------------------------------- monitors and events
def _monitors(orbit: Orbit, b: Builder, ctx: Context) -> tuple[dict, tuple]:
    """Energy; the Jacobi constant (circular perturber); k̂·(x × v) (zonal field)."""
    v2 = vectors.dot(b.velocity, b.velocity)
    energy = v2 / 2 - b.mu / b.radius
    if b.Omega is not None:
        energy = energy - b.at_position(b.Omega)
    monitors: dict[str, Any] = {"energy": energy}
    conserved: list[str] = [] if orbit.time_dependent else ["energy"]
    monitors["angular_momentum"] = list(b.momentum)
    if not orbit.perturbations:
        conserved.append("angular_momentum")
    third, zonal = orbit.third_body, orbit.zonal
    if third is not None and third.circular:
        # In the frame turning with the perturber, H − n k̂₃·(x × v) is conserved.
        n = hy.par[ctx.pars.index("third_body.n")]
        k3 = third.normal(ctx)
        monitors["jacobi"] = energy - n * vectors.dot(k3, b.momentum)
        others = [p for p in orbit.perturbations if p is not third]
        if not others:
            conserved.append("jacobi")
    if zonal is not None:
        i = zonal.coordinate_axis()
        if i is None:
            k = [hy.par[ctx.pars.index(f"zonal.axis_unit[{j}]")] for j in range(3)]
            monitors["polar_momentum"] = vectors.dot(k, b.momentum)
        else:
            sign = 1 if exact_fraction(zonal.axis[i]) > 0 else -1
            monitors["polar_momentum"] = sign * b.momentum[i]
        if len(orbit.perturbations) == 1:
            conserved.append("polar_momentum")
    return monitors, tuple(conserved)


def _events(scene: Scene, orbit: Orbit, b: Builder, pars: ParTable) -> list[EventSpec]:
    events: list[EventSpec] = []
    for name in scene.output.events:
        if name == "node":
            labels = {1: "ascending", -1: "descending"}
            events.append(EventSpec(name, "node", b.node_function, labels=labels))
        elif name == "apsis":
            labels = {1: "pericentre", -1: "apocentre"}
            events.append(EventSpec(name, "apsis", b.apsis_function, labels=labels))
        elif name == "equatorial":
            if exact_fraction(orbit.equatorial_limit) == 0:
                raise SceneError(
                    "output.events",
                    "'equatorial' records where sin Φ crosses orbit.equatorial_limit, which is 0 "
                    "here (sin Φ only touches 0); give a limit > 0",
                )
            labels = {-1: "approach", 1: "recede"}
            spec = EventSpec(name, "equatorial", _equatorial_function(b), labels=labels)
            events.append(spec)
        elif name in scene.events:
            ev = scene.events[name]
            expr = parse_expression(ev.expression, b.outputs, pars, f"events.{name}.expression")
            events.append(EventSpec(name, name, expr, ev.direction))
        else:
            known = [*EVENTS, *scene.events]
            raise SceneError("output.events", f"unknown event {name!r}; known: {known}")
    for name in scene.events:
        if name not in scene.output.events:
            raise SceneError(f"events.{name}", "is defined but not listed in output.events")
    return events


def _total(terms: list[Any]) -> Any:
    """The sum of ``terms``, or None for none."""
    if not terms:
        return None
    return terms[0] if len(terms) == 1 else hy.sum(terms)


def _equatorial_function(b: Builder) -> Any:
    """(sin²Φ − ε²)|L|², zero where sin Φ = ε; no square root, no division."""
    eps = b.equatorial_limit()
    L = b.momentum
    c = vectors.dot(b._plane_normal(), L)
    return vectors.dot(L, L) * (1 - eps * eps) - c * c
