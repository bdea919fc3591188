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
from typing import Any

import heyoka as hy
import mpmath

from ..core import vectors
from ..core.errors import SceneError
from ..core.expressions import parse_expression
from ..core.model import EventSpec, Model, ParTable, TerminalSpec
from ..core.precision import exact_fraction, scene_mpf
from ..core.scene import Scene
from ..mechanics import frames
from ..mechanics import kepler as el
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
from .encke import Encke, Unbound
from .family import FAMILY
from .revolutions import Revolutions
from .scene import Orbit, PlaneMotion
from .tilt import (
    FRAME,
    LEVEL,
    TILTED,
    EquatorialHandover,
    angles_in,
    reference_normal,
    sin2_on_reference,
)

CARTESIAN = ("x", "y", "z", "vx", "vy", "vz")
CAYLEY = ("r", "rdot", "rho", "h", "Theta", "Sigma", "Phi")
QUATERNION = ("qw", "qx", "qy", "qz")
#: The events the family offers (its record, :data:`.family.FAMILY`, declares them).
EVENTS = FAMILY.events
_GUARD_DIGITS = 15


def build_model(scene: Scene) -> Model:
    """Turn a validated orbit scene into a :class:`~cayley_heyoka.core.model.Model`.

    A ``cayley`` scene that can approach the reference plane has two variants (:mod:`.tilt`):
    the run starts with the one its start's sin Φ calls for, and builds the other when a
    terminal event hands over to it.
    """
    orbit: Orbit = scene.model
    if not _hands_over(orbit):
        return _build(scene, None)
    t0 = _start_time(scene)
    with mpmath.workdps(scene.integrator.precision.dps + _GUARD_DIGITS):
        low = _sin_phi(orbit, scene_mpf(t0)) <= scene_mpf(orbit.equatorial_limit)
    built: dict[str, Model] = {}
    lock = threading.Lock()

    def variant(name: str) -> Model:
        with lock:
            if name not in built:
                built[name] = _build(scene, name, variant)
            return built[name]

    return variant(TILTED if low else LEVEL)


def _hands_over(orbit: Orbit) -> bool:
    """Whether a ``cayley`` orbit can reach the reference plane: Φ can change (a perturbation,
    a turning plane) and ``equatorial_limit`` is not 0."""
    if orbit.formulation != "cayley" or exact_fraction(orbit.equatorial_limit) == 0:
        return False
    plane = orbit.plane
    turning = plane is not None and (
        exact_fraction(plane.theta_rate) != 0 or exact_fraction(plane.phi_rate) != 0
    )
    return bool(orbit.perturbations) or turning


def _build(scene: Scene, variant: str | None, variants: Any = None) -> Model:
    orbit: Orbit = scene.model
    prec = scene.integrator.precision
    pars = ParTable(prec)
    mu = pars.add("mu", orbit.mu, "orbit.mu")
    plane = _plane_expressions(orbit.plane, pars)
    X = list(hy.make_vars(*CARTESIAN[:3]))
    ctx = Context(mu, pars, prec.dps + _GUARD_DIGITS)
    omegas = term_functions(orbit.perturbations, X, ctx)
    for term, omega in zip(orbit.perturbations, omegas, strict=True):
        if not isinstance(term, UserPotential):  # a text records itself as it is parsed
            pars.source(f"perturbations.{perturbation_key(term)}", omega)
    t0 = _start_time(scene)

    b = _Builder(orbit, pars, plane, mu, omegas, X, prec, ctx)
    if orbit.formulation == "encke":
        # Its initial state is the deviation from the initial osculating ellipse, which the
        # formulation's own rectification computes.
        with mpmath.workdps(prec.dps + _GUARD_DIGITS):
            try:
                b.encke(*initial_cartesian(orbit, scene_mpf(t0)))
            except Unbound as exc:
                raise SceneError(
                    _initial_field(orbit),
                    f"{exc} at the start in {prec.name}: its eccentricity rounds to 1 in the "
                    "run's precision (a nearly radial orbit), and formulation = 'encke' follows "
                    "an osculating ellipse; use formulation = 'cartesian', or a higher precision",
                ) from None
    elif orbit.formulation == "cayley":
        b.cayley(initial_state(orbit, t0, prec.dps + _GUARD_DIGITS, variant), variant)
    else:
        start = initial_state(orbit, t0, prec.dps + _GUARD_DIGITS)
        getattr(b, orbit.formulation)(start)

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
    initial = [prec.number(v) for v in b.initial]
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
    if orbit.formulation == "cartesian":
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


def _initial_field(orbit: Orbit) -> str:
    """The scene field holding the orbit's initial state."""
    return "orbit.elements" if orbit.initial[0] == "elements" else "orbit.velocity"


def validate(scene: Scene) -> None:
    """Geometric constraints that need the start time: raise :class:`SceneError` if violated."""
    orbit: Orbit = scene.model
    # In the run's precision and guard digits: an eccentricity of 1 − 10⁻³² is an ellipse to a
    # quad run, and 1 to 30 digits.
    with mpmath.workdps(scene.integrator.precision.dps + _GUARD_DIGITS):
        t = _start_time(scene)
        x, v = initial_cartesian(orbit, t)
        H = vectors.cross(x, v)
        h = mpmath.sqrt(vectors.dot(H, H))
        where = _initial_field(orbit)
        if h == 0:
            raise SceneError(
                where, "gives rectilinear motion (x × v = 0): the orbit plane is undefined"
            )
        r = mpmath.sqrt(vectors.dot(x, x))
        mu = scene_mpf(orbit.mu)
        energy = vectors.dot(v, v) / 2 - mu / r
        e = mpmath.sqrt(max(mpmath.mpf(0), 1 + 2 * energy * h * h / (mu * mu)))
        q = h * h / (mu * (1 + e))
        if orbit.formulation == "encke" and e >= 1:
            raise SceneError(
                "orbit.formulation",
                f"'encke' follows an osculating ellipse, but the orbit starts with e = "
                f"{mpmath.nstr(e, 6)} ≥ 1 (parabolic or hyperbolic); use 'cartesian'",
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
        if orbit.formulation == "cayley" and (orbit.perturbations or turning):
            if exact_fraction(orbit.equatorial_limit) == 0 and _sin_phi(orbit, t) == 0:
                raise SceneError(
                    "orbit.formulation",
                    "'cayley' with orbit.equatorial_limit = 0 needs sin Φ ≠ 0, but the orbit "
                    "starts in the reference plane (Θ and Σ are undefined there: cosec Φ in "
                    "their equations); give a limit > 0 (the run then starts on a tilted frame) "
                    "or use formulation = 'quaternion' or 'cartesian'",
                )


def _sin_phi(orbit: Orbit, t: Any) -> Any:
    """sin Φ of the osculating orbit on the reference plane at time t (mpmath)."""
    x, v = initial_cartesian(orbit, t)
    H = vectors.cross(x, v)
    h = mpmath.sqrt(vectors.dot(H, H))
    M01 = _plane_matrix_at(orbit.plane, t)
    n = vectors.matvec(vectors.transpose(M01), [c / h for c in H])
    return mpmath.sqrt(n[0] ** 2 + n[1] ** 2)


def initial_cartesian(orbit: Orbit, t: Any) -> tuple[list, list]:
    """Position and velocity at the start time, in mpmath at the current precision."""
    if orbit.initial[0] == "cartesian":
        _, x, v = orbit.initial
        return [scene_mpf(c) for c in x], [scene_mpf(c) for c in v]
    values = {k: scene_mpf(v) for k, v in orbit.initial[1].items()}
    return el.elements_to_cartesian(
        el.Elements(**values), scene_mpf(orbit.mu), frame=plane_angles_at(orbit.plane, t)
    )


def initial_state(orbit: Orbit, t: Any, dps: int, variant: str | None = None) -> list[str]:
    """The formulation's initial state as decimal text with ``dps`` digits (not ``encke``,
    whose state depends on the parameters its model allocates: see :meth:`_Builder.encke`);
    Cayley's angles on the working frame of ``variant`` (:mod:`.tilt`) if given."""
    if orbit.formulation == "encke":
        raise ValueError("the encke state is the deviation from its ellipse: build the model")
    with mpmath.workdps(dps):
        t = scene_mpf(t)
        x, v = initial_cartesian(orbit, t)
        if orbit.formulation == "cartesian":
            values = [*x, *v]
        else:
            frame = plane_angles_at(orbit.plane, t)
            s = el.cartesian_to_cayley(x, v, sigma=scene_mpf(orbit.sigma0), frame=frame)
            values = [s.r, s.rdot, s.rho, s.h]
            if orbit.formulation == "cayley":
                angles = (s.Theta, s.Sigma, s.Phi)
                if variant == TILTED:
                    angles = angles_in(TILTED, *angles)
                values += list(angles)
            else:
                values += _plane_quaternion(frame, (s.Theta, s.Sigma, s.Phi))
        return [mpmath.nstr(c, dps, strip_zeros=False) for c in values]


# ---------------------------------------------------------------------- the formulations
class _Builder:
    """Collects the system, the position and velocity expressions and the outputs."""

    def __init__(self, orbit, pars, plane, mu, omegas, X, precision, ctx) -> None:
        self.orbit, self.pars, self.plane, self.mu = orbit, pars, plane, mu
        self.precision, self.ctx = precision, ctx
        self.omegas, self.X = omegas, X
        self.Omega = None if not omegas else omegas[0] if len(omegas) == 1 else hy.sum(omegas)
        self.perturbed = bool(omegas)
        self.system: list[tuple[Any, Any]] = []
        self.initial: list[str] = []
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
        return self.pars.add(name, self.orbit.equatorial_limit)

    def force(self, x: list[Any], r2: Any, radius: Any = None) -> Gradient | None:
        """∇Ω at the position x, |x|² = r2, or at r x̂ for ``x`` = x̂ and ``radius`` = r
        (:func:`.disturbing.force`); None without a disturbing function."""
        if not self.perturbed:
            return None
        return force(self.orbit.perturbations, self.omegas, self.X, x, r2, self.ctx, radius)

    def at_position(self, expr: Any) -> Any:
        """An expression of the Cartesian placeholders, composed with the position."""
        return hy.subs(expr, {str(x): p for x, p in zip(self.X, self.position, strict=True)})

    def cartesian(self, start: list[str]) -> None:
        x = self.X
        v = list(hy.make_vars(*CARTESIAN[3:]))
        rhs = eq.cartesian_rates(x, v, self.mu, self.force(x, vectors.dot(x, x)))
        self.system = list(zip([*x, *v], rhs, strict=True))
        self.initial = start
        self.position, self.velocity = x, v
        self.momentum = vectors.cross(x, v)
        self.outputs = dict(zip(CARTESIAN, [*x, *v], strict=True))
        self.node_function = vectors.dot(self._plane_normal(), x)
        self.apsis_function = vectors.dot(x, v)
        self.radius = hy.sqrt(vectors.dot(x, x))

    def encke(self, x: list, v: list) -> None:
        """δ = x − y from the osculating ellipse y, and ψ = E/2, half its eccentric anomaly
        (:mod:`.encke`)."""
        d = list(hy.make_vars(*ENCKE[:3]))
        dv = list(hy.make_vars(*ENCKE[3:6]))
        psi = hy.make_vars(ENCKE[6])
        en = Encke(self.pars, self.precision, self.mu, self.orbit.mu)
        self.initial = en.start(x, v)
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

    def cayley(self, start: list[str], variant: str | None = None) -> None:
        """Cayley's equations; with ``variant`` (:mod:`.tilt`), on that working frame, with
        the terminal event that hands the run over to the other."""
        r, rdot, rho, h, Theta, Sigma, Phi = hy.make_vars(*CAYLEY)
        turns = self._revolutions(start, rho)
        u = turns.angle(rho) - Sigma
        if variant is None:
            axes, _ = eq.cayley_axes(Theta, Phi, u, self.plane)
            partials = self._partials(r, axes)
            rhs = eq.in_plane_rates(r, rdot, h, self.mu, partials[0], partials[1])
            rhs += eq.plane_rates(u, h, Phi, partials[2], self.plane, Theta)
            self.system = list(zip([r, rdot, rho, h, Theta, Sigma, Phi], rhs, strict=True))
            self.initial = start
            self._kinematics(r, rdot, h, axes)
            values = [r, rdot, turns.rho(rho), h, Theta, Sigma, Phi]
            self.outputs.update(zip(CAYLEY, values, strict=True))
            self.node_function = hy.sin(u)
            return
        # Allocated alike in both variants: they share one parameter table.
        eps = self.equatorial_limit()
        cos, sin = FRAME[variant]
        c, s = self.pars.add("orbit.frame_cos", cos), self.pars.add("orbit.frame_sin", sin)
        self.pars.add("orbit.theta_before", "0")
        self.pars.add("orbit.sigma_before", "0")
        tilted = variant == TILTED
        general, _ = eq.cayley_axes(Theta, Phi, u, self.plane, (c, s))
        axes = general if tilted else eq.cayley_axes(Theta, Phi, u, self.plane)[0]
        partials = self._partials(r, axes)
        rhs = eq.in_plane_rates(r, rdot, h, self.mu, partials[0], partials[1])
        rhs += eq.plane_rates(u, h, Phi, partials[2], self.plane, Theta, (c, s) if tilted else None)
        self.system = list(zip([r, rdot, rho, h, Theta, Sigma, Phi], rhs, strict=True))
        self.initial = start
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

    def quaternion(self, start: list[str]) -> None:
        r, rdot, rho, h = hy.make_vars(*CAYLEY[:4])
        q = list(hy.make_vars(*QUATERNION))
        turns = self._revolutions(start, rho)
        angle = turns.angle(rho)
        axes = eq.quaternion_axes(q, angle)
        partials = self._partials(r, axes)
        rhs = eq.in_plane_rates(r, rdot, h, self.mu, partials[0], partials[1])
        rhs += eq.quaternion_rates(q, angle, h, partials[2])
        self.system = list(zip([r, rdot, rho, h, *q], rhs, strict=True))
        self.initial = start
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

    def _revolutions(self, start: list[str], rho: Any) -> Revolutions:
        """Whole turns of ρ kept out of the state (:mod:`.revolutions`); ρ₀ = start[2] is
        replaced by its reduced value."""
        turns = Revolutions(self.pars, self.precision, start[2], 2)
        start[2] = turns.initial_rho
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


# ---------------------------------------------------------------------- reference plane
def _plane_angles(motion: PlaneMotion, t: Any, value: Any) -> tuple[tuple, tuple]:
    """(θ′, σ′, φ′) and their rates at time ``t`` (None for a rate that is exactly zero).

    ``value(name, number)`` builds each number: heyoka (``value`` allocates a parameter, ``t``
    is ``hy.time``) and mpmath alike.
    """

    def rate(name: str, v: Any) -> Any:
        # A rate that is exactly zero is left out (None), so a plane at rest compiles no
        # time terms.
        return None if exact_fraction(v) == 0 else value(name, v)

    f = frames.functions_for(t)
    th0, th1 = value("theta0", motion.theta0), rate("theta_rate", motion.theta_rate)
    ph0, ph1 = value("phi0", motion.phi0), rate("phi_rate", motion.phi_rate)
    sg0 = value("sigma0", motion.sigma0)
    theta = th0 if th1 is None else th0 + th1 * t
    phi = ph0 if ph1 is None else ph0 + ph1 * t
    if not motion.departure_point:
        sg1 = rate("sigma_rate", motion.sigma_rate)
        sigma = sg0 if sg1 is None else sg0 + sg1 * t
    elif th1 is None:
        sg1, sigma = None, sg0
    elif ph1 is None:
        sg1 = th1 * f.cos(ph0)
        sigma = sg0 + sg1 * t
    else:
        # σ′ = σ′₀ + θ̇′(sin φ′ − sin φ′₀)/φ̇′, written without the cancelling difference.
        half = ph1 * t / 2
        sigma = sg0 + 2 * th1 * f.cos(ph0 + half) * f.sin(half) / ph1
        sg1 = th1 * f.cos(phi)
    return (theta, sigma, phi), (th1, sg1, ph1)


def _plane_expressions(motion: PlaneMotion | None, pars: ParTable) -> eq.ReferencePlane | None:
    if motion is None:
        return None

    def value(name: str, v: Any) -> Any:
        return pars.add(f"reference_plane.{name}", v)

    (theta, sigma, phi), (th1, sg1, ph1) = _plane_angles(motion, hy.time, value)
    return eq.ReferencePlane(theta, sigma, phi, th1, sg1, ph1, motion.departure_point)


def plane_angles_at(motion: PlaneMotion | None, t: Any) -> tuple:
    """(θ′, σ′, φ′) at time t in mpmath (zeros for the fixed frame)."""
    if motion is None:
        return (mpmath.mpf(0),) * 3
    return _plane_angles(motion, scene_mpf(t), lambda _, v: scene_mpf(v))[0]


def _plane_matrix_at(motion: PlaneMotion | None, t: Any) -> frames.Matrix:
    return frames.plane_matrix(*plane_angles_at(motion, t))


def _plane_quaternion(frame: tuple, angles: tuple) -> list:
    """q of M₀₂ = M(θ′, σ′, φ′) M(Θ, Σ, Φ) as a product of axis quaternions
    (docs/orbits.md, "The quaternion formulation")."""

    def axis(k: int, a: Any) -> list:
        q = [mpmath.cos(a / 2), mpmath.mpf(0), mpmath.mpf(0), mpmath.mpf(0)]
        q[k] = mpmath.sin(a / 2)
        return q

    q = [mpmath.mpf(1), mpmath.mpf(0), mpmath.mpf(0), mpmath.mpf(0)]
    for theta, sigma, phi in (frame, angles):
        for factor in (axis(3, theta), axis(1, phi), axis(3, -sigma)):
            q = _hamilton(q, factor)
    return q


def _hamilton(a: list, b: list) -> list:
    return [
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    ]


def _start_time(scene: Scene) -> Any:
    grid = scene.output
    return grid.times[0] if grid.times is not None else grid.grid[0]


# ---------------------------------------------------------------------- monitors and events
def _monitors(orbit: Orbit, b: _Builder, ctx: Context) -> tuple[dict, tuple]:
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


def _events(scene: Scene, orbit: Orbit, b: _Builder, pars: ParTable) -> list[EventSpec]:
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


def _equatorial_function(b: _Builder) -> Any:
    """(sin²Φ − ε²)|L|², zero where sin Φ = ε; no square root, no division."""
    eps = b.equatorial_limit()
    L = b.momentum
    c = vectors.dot(b._plane_normal(), L)
    return vectors.dot(L, L) * (1 - eps * eps) - c * c
