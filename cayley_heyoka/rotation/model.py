"""Build the heyoka system of a rigid-body scene, with only the terms the scene needs.

* Rates only (``formulation = "none"``): Euler's three equations.
* Rodrigues: Euler's equations, Cayley's kinematics for the chart parameters (λ, μ, ν), the
  torque by Cayley's formula from ``∂V/∂λ, ∂V/∂μ, ∂V/∂ν`` (taken by heyoka), and the chart
  re-basing event (:mod:`.charts`).
* Quaternion: Euler's equations, ``q̇ = ½ q ⊗ (0, ω)``, the torque by the matrix gradient of V.

No torque term is compiled for a torque-free scene, and no attitude for a rates-only one. The
scene's formulation object (:mod:`.formulations`) names the attitude's part
(:func:`rodrigues_attitude`, :func:`quaternion_attitude`, :func:`poisson_attitude`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import heyoka as hy

from ..core.errors import SceneError
from ..core.expressions import parse_expression
from ..core.model import EventSpec, Model, ParTable, TerminalSpec
from ..core.scene import Scene
from . import attitude as att
from . import azimuth, invariable_angle, poisson
from . import equations as eq
from .charts import RodriguesAtlas
from .forces import ForceContext, HeavyTop, Potential, force_key
from .numbers import numbers
from .scene import RigidBody

AXES = ("x1", "y1", "z1")
RODRIGUES = ("lambda", "mu", "nu")
MONITORS = (
    "energy",
    "momentum_squared",
    "momentum_space",
    "momentum_vertical",
    "orthogonality",
    "direction_norm",
)


def build_model(scene: Scene) -> Model:
    """Turn a validated rigid-body scene into a :class:`~cayley_heyoka.core.model.Model`, its
    numbers from :func:`~cayley_heyoka.rotation.numbers.numbers`."""
    body: RigidBody = scene.model
    prec = scene.integrator.precision
    given = numbers(scene)
    values = given.values
    pars = ParTable(prec)
    inertia = [pars.add(name, values[name], f"body.inertia[{i}]") for i, name in enumerate("ABC")]
    rates = list(hy.make_vars("p", "q", "r"))
    outputs: dict[str, Any] = dict(zip("pqr", rates, strict=True))
    build = body.form.attitude
    attitude: _Attitude | None = (
        None if build is None else build(body, prec, pars, rates, inertia, values)
    )

    torque = attitude.torque if attitude else None
    differences = [pars.add(name, values[name], "body.inertia") for name in ("B-C", "C-A", "A-B")]
    system = list(zip(rates, eq.euler_rates(differences, rates, inertia, torque), strict=True))
    terminal = []
    if attitude:
        system += list(zip(attitude.variables, attitude.rhs, strict=True))
        outputs.update(attitude.outputs)
        terminal = list(attitude.terminal)
    if azimuth.wanted(scene.output.options, body.form):
        gamma = attitude.variables
        az = azimuth.Azimuth(pars, prec, attitude.u, values, len(system), 3)
        s = hy.make_vars("azimuth_reduced")
        system.append((s, az.rhs(gamma, rates)))
        outputs.update(az.attitude(s, gamma))
        terminal += az.terminal(s, gamma)
    if invariable_angle.wanted(scene.output.options):
        psi = invariable_angle.InvariableAngle(pars, prec, values, len(system))
        u = hy.make_vars("psi_reduced")
        system.append((u, psi.rhs(rates[2], inertia[2])))
        outputs["psi"] = psi.psi(u)
        terminal.append(psi.terminal(u))

    monitors, conserved = _monitors(body, inertia, rates, attitude, pars)
    wanted = scene.output.monitors
    if wanted is not None:
        for name in wanted:
            if name not in monitors:
                why = "needs an attitude" if name in MONITORS else f"is unknown; known: {MONITORS}"
                raise SceneError("output.monitors", f"{name!r} {why} (available: {list(monitors)})")
        monitors = {k: v for k, v in monitors.items() if k in wanted}
        conserved = tuple(k for k in conserved if k in wanted)

    events = _events(scene, body, inertia, rates, attitude, outputs, pars)
    initial = list(given.initial_state)
    model = Model("rotation", system, initial, pars, outputs, monitors, conserved, events, terminal)
    # tan(θ/2) n is infinite at a half-turn in both formulations: the attitude is fine there.
    model.unbounded = RODRIGUES if "lambda" in outputs else ()
    _provenance(model, body, attitude)
    return model


def _provenance(model: Model, body: RigidBody, attitude: _Attitude | None) -> None:
    """The scene fields of the state and of the parameters derived from several numbers
    (:meth:`Model.initial_field`, :attr:`ParTable.fields`)."""
    start = f"initial.{body.attitude[0]}" if body.attitude is not None else "initial"
    fields = {name: f"initial.rates[{i}]" for i, name in enumerate("pqr")}
    if attitude is not None:
        # γ = Rᵀu: the attitude and the forces' direction.
        where = f"{start}, forces" if attitude.direction is not None else start
        fields |= {str(v): where for v in attitude.variables}
    model.initial_fields = fields
    motion = f"body.inertia, initial.rates, {start}"
    derived = {
        "chart.kappa_max": "attitude.max_chart_angle",
        "chart.": start,
        "momentum_space": motion,
        "psi.": "body.inertia, initial.rates",
        "azimuth.": f"{motion}, forces",
    }
    pars = model.pars
    for i, name in enumerate(pars.names):
        if pars.fields[i] is None:
            pars.fields[i] = next((f for k, f in derived.items() if name.startswith(k)), None)


class _Attitude:
    """The attitude part of the system: variables, right-hand sides, torque, outputs."""

    def __init__(self) -> None:
        self.variables: list[Any] = []
        self.rhs: list[Any] = []
        self.torque: list[Any] | None = None
        self.potential: Any = None
        self.R: list[list[Any]] = []
        # The integrated frame, when it can drift off the rotations (R(q) with |q| ≠ 1): the
        # orthogonality monitor measures it. Otherwise R itself.
        self.frame: list[list[Any]] | None = None
        self.outputs: dict[str, Any] = {}
        self.terminal: list[TerminalSpec] = []
        # Builds the invariable-plane event functions of a torque-free body (allocating their
        # parameters only when the scene asks for the events).
        self.plane_events: Callable[[], list[Any]] | None = None
        # The Euler–Poisson reduction's γ: no attitude matrix, only the forces' direction.
        self.direction: list[Any] | None = None
        self.u: Any = None  # the poisson formulation's space direction


def rodrigues_attitude(body, prec, pars, rates, inertia, values) -> _Attitude:
    """Cayley's kinematics of a re-based chart (:mod:`.charts`), the torque by Cayley's
    formula (:attr:`.formulations.RODRIGUES`)."""
    a = _Attitude()
    rho = list(hy.make_vars("lambda", "mu", "nu"))
    atlas = RodriguesAtlas(pars, slice(3, 6), values)
    kmax = pars.add("chart.kappa_max", values["chart.kappa_max"])

    qb = atlas.base_pars
    # The base is normalised at each fold, to within a rounding: R(qb) is |qb|² times its
    # rotation, and |qb|² − 1 scaled the forces fold after fold (the heavy top's energy kept
    # a shared part, windows shared 0.33 at 10⁷ steps). Dividing makes the base's norm a gauge.
    R_base, _ = att.quaternion_rotation(qb)
    R = att.matmul(R_base, att.rodrigues_to_matrix(rho))
    q_total = att.quaternion_multiply(qb, [1, *rho])  # norm √κ: the chart's w is 1/√κ
    rho_total = [q_total[i] / q_total[0] for i in (1, 2, 3)]
    norm = hy.sqrt(att.kappa(rho))

    a.variables, a.R = rho, R
    a.rhs = eq.rodrigues_kinematics(rho, rates)
    if body.forces:
        a.potential = force_function(body, R, rho_total, inertia, pars, values)
        a.torque = eq.cayley_torque(a.potential, rho)
    a.outputs = dict(zip(("lambda", "mu", "nu"), rho_total, strict=True))
    a.outputs.update(zip(("qw", "qx", "qy", "qz"), [c / norm for c in q_total], strict=True))
    a.terminal = [TerminalSpec(att.kappa(rho) - kmax, 1, atlas.rebase, "rebasings")]
    if body.torque_free:

        def plane_events():
            kR = att.rodrigues_kappa_matrix(rho)
            gb = atlas.momentum_in_chart_base()
            return [sum(kR[i][j] * gb[i] for i in range(3)) for j in range(3)]

        a.plane_events = plane_events
    return a


def quaternion_attitude(body, prec, pars, rates, inertia, values) -> _Attitude:
    """``q̇ = ½ q ⊗ (0, ω)``, the torque by the matrix gradient of V
    (:attr:`.formulations.QUATERNION`)."""
    a = _Attitude()
    quat = list(hy.make_vars("qw", "qx", "qy", "qz"))
    # The norm of q is a gauge (q and cq are one attitude; the kinematics is linear in q), but
    # truncation drifts it steadily in a steady rotation, and R(q) would carry that drift into
    # L in space and the forces: everything physical reads the normalised attitude.
    frame = att.quaternion_to_matrix(quat)
    R, norm2 = att.quaternion_rotation(quat)
    a.variables, a.R, a.frame = quat, R, frame
    a.rhs = eq.quaternion_kinematics(quat, rates)
    if body.forces:
        names = [[hy.expression(f"R{i + 1}{j + 1}__") for j in range(3)] for i in range(3)]
        V = force_function(body, names, rodrigues_of_matrix(names), inertia, pars, values)
        pars.bind({str(names[i][j]): R[i][j] for i in range(3) for j in range(3)})
        a.torque = eq.matrix_torque(V, names, R, scaled=(frame, norm2))
        a.potential = hy.subs(V, {str(names[i][j]): R[i][j] for i in range(3) for j in range(3)})
    a.outputs = dict(
        zip(("lambda", "mu", "nu"), [quat[i] / quat[0] for i in (1, 2, 3)], strict=True)
    )
    norm = hy.sqrt(norm2)
    a.outputs.update(zip(("qw", "qx", "qy", "qz"), [c / norm for c in quat], strict=True))
    if body.torque_free:

        def plane_events():
            # Scaling by |q|² > 0 moves no root: the events need no division.
            g = [pars.add(f"momentum_space[{i}]", values[f"momentum_space[{i}]"]) for i in range(3)]
            return [sum(frame[i][j] * g[i] for i in range(3)) for j in range(3)]

        a.plane_events = plane_events
    return a


def poisson_attitude(body, prec, pars, rates, inertia, values) -> _Attitude:
    """The rates and γ = Rᵀu (:mod:`.poisson`): no attitude beyond the forces' direction
    (:attr:`.formulations.POISSON`)."""
    a = _Attitude()
    u = poisson.direction(body.forces, prec)
    gamma = list(hy.make_vars(*poisson.GAMMA))
    a.variables = gamma
    a.rhs = poisson.kinematics(gamma, rates)
    zero = hy.expression(prec.number(0))
    frame = poisson.frame(u, gamma, prec)
    a.potential = force_function(body, frame, [zero] * 3, inertia, pars, values)
    a.torque = poisson.torque(a.potential, gamma)
    a.outputs = dict(zip(poisson.GAMMA, gamma, strict=True))
    a.direction, a.u = gamma, u
    return a


def force_function(body: RigidBody, R, rho_total, inertia, pars: ParTable, values) -> hy.expression:
    """The scene's force function V (the sum of its forces) on the attitude matrix ``R`` and
    the Cayley–Rodrigues parameters ``rho_total`` of the whole attitude, its parameters holding
    ``values``."""
    ctx = ForceContext(R, rho_total, inertia, pars, values)
    terms = []
    for force in body.forces:
        term = force.potential(ctx)
        if not isinstance(force, Potential):  # a text records itself as it is parsed
            pars.source(f"forces.{force_key(force)}", term)
        terms.append(term)
    return terms[0] if len(terms) == 1 else hy.sum(terms)


def rodrigues_of_matrix(R) -> list:
    """Cayley–Rodrigues parameters of a rotation matrix (of expressions), away from θ = π."""
    upsilon = 1 + R[0][0] + R[1][1] + R[2][2]
    return [
        (R[2][1] - R[1][2]) / upsilon,
        (R[0][2] - R[2][0]) / upsilon,
        (R[1][0] - R[0][1]) / upsilon,
    ]


def _monitors(body: RigidBody, inertia, rates, attitude: _Attitude | None, pars: ParTable):
    L = eq.body_momentum(inertia, rates)
    T = eq.kinetic_energy(inertia, rates)
    time_dependent = any(f.time_dependent for f in body.forces)
    monitors: dict[str, Any] = {}
    monitors["energy"] = (
        T - attitude.potential if attitude and attitude.potential is not None else T
    )
    monitors["momentum_squared"] = L[0] * L[0] + L[1] * L[1] + L[2] * L[2]
    conserved = [] if time_dependent else ["energy"]
    if body.torque_free:
        conserved.append("momentum_squared")
    if attitude and attitude.direction is not None:
        gamma = attitude.direction
        monitors["momentum_vertical"] = hy.sum([gamma[i] * L[i] for i in range(3)])
        monitors["direction_norm"] = hy.sum([g * g for g in gamma])
        conserved += ["momentum_vertical", "direction_norm"]
    elif attitude:
        R = attitude.R
        monitors["momentum_space"] = att.matvec(R, L)
        if body.torque_free:
            conserved.append("momentum_space")
        tops = [f for f in body.forces if isinstance(f, HeavyTop)]
        if tops and len(tops) == len(body.forces):
            up = [hy.par[pars.index(f"heavy_top.up[{i}]")] for i in range(3)]
            g = monitors["momentum_space"]
            monitors["momentum_vertical"] = sum(up[i] * g[i] for i in range(3))
            conserved.append("momentum_vertical")
        frame = attitude.frame or R
        RtR = att.matmul(att.transpose(frame), frame)
        defect = [RtR[i][j] - (1 if i == j else 0) for i in range(3) for j in range(3)]
        monitors["orthogonality"] = hy.sqrt(hy.sum([d * d for d in defect]))
    return monitors, tuple(conserved)


def _events(scene: Scene, body, inertia, rates, attitude, outputs, pars) -> list[EventSpec]:
    events: list[EventSpec] = []
    for name in scene.output.events:
        if name == "invariable_plane":
            # (A body at rest has no invariable plane: refused by numbers().)
            if attitude is not None and attitude.plane_events is not None:
                exprs = attitude.plane_events()
            else:
                # With a torque, or without attitude, the plane is the one perpendicular to the
                # instantaneous L: body axis j lies in it exactly when (Ap, Bq, Cr)_j = 0.
                exprs = list(rates)
            events += [EventSpec(name, AXES[j], exprs[j]) for j in range(3)]
        elif name in scene.events:
            ev = scene.events[name]
            symbols = dict(outputs)
            symbols.update(zip("ABC", inertia, strict=True))
            expr = parse_expression(ev.expression, symbols, pars, f"events.{name}.expression")
            events.append(EventSpec(name, name, expr, ev.direction))
        else:
            known = ["invariable_plane", *scene.events]
            raise SceneError("output.events", f"unknown event {name!r}; known: {known}")
    for name in scene.events:
        if name not in scene.output.events:
            raise SceneError(f"events.{name}", "is defined but not listed in output.events")
    return events
