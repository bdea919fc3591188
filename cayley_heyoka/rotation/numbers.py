"""The numbers of a rigid-body scene's model, and the structure they fill.

:func:`numbers` is the one place a rigid-body model's numbers are computed — the initial rates
and attitude (λ, μ, ν of the first chart, the quaternion, or γ = Rᵀu), the moments and their
differences, the chart's base, the forces' parameters, the angular momentum the invariable-plane
events watch, the azimuth's and Ψ's constants — so that
:func:`cayley_heyoka.rotation.model.build_model` and a scene of an already built structure
(:mod:`cayley_heyoka.core.structures`) take the same values. :func:`structure` names what the
build compiles: the scene with its numbers masked, except the numbers that are compiled in
(the direction a reduced body's forces see, in the ``poisson`` formulation).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from ..core.errors import SceneError
from ..core.model import Numbers
from ..core.precision import Precision, exact_fraction, fraction_text
from ..core.scene import Scene
from ..core.structures import MASK as _MASK
from ..core.structures import Table, structure_text
from . import attitude as att
from . import azimuth, invariable_angle, poisson
from . import equations as eq
from .charts import RodriguesAtlas, kappa_limit
from .scene import RigidBody

#: Keys of ``[forces.KEY]`` tables whose values are parameters of the model (a reduced body's
#: direction is compiled in: not listed for ``poisson``).
_FORCE_NUMBERS = {
    "heavy_top": ("weight", "center_of_mass", "up"),
    "gravity_gradient": ("gm", "distance", "direction"),
}
_REDUCED_FORCE_NUMBERS = {"heavy_top": ("weight", "center_of_mass"), "gravity_gradient": ("gm",)}
#: A formulation's attitude numbers (:attr:`.formulations.Formulation.numbers`): its initial
#: state after the rates, and its parameters' values.
Attitude = tuple[list[Any], dict[str, Any]]


def structure(scene: Scene) -> str:
    """The scene's model structure: its dictionary with every number the model holds as a
    parameter or an initial value masked, and without its output times (not compiled).

    Examples
    --------
    >>> import cayley_heyoka as ch
    >>> times = {"times": [0, 1]}
    >>> a = {"body": {"inertia": [1, 2, 3]}, "initial": {"rates": [1, 0, 0]}, "output": times}
    >>> b = {"body": {"inertia": [2, 2, 3]}, "initial": {"rates": [0, 1, 0]}, "output": times}
    >>> structure(ch.Scene.from_dict(a)) == structure(ch.Scene.from_dict(b))
    True
    """
    data = {k: v for k, v in scene.source.items()}
    body: RigidBody = scene.model
    data["body"] = {**data.get("body", {}), "inertia": _MASK}
    data["initial"] = dict.fromkeys(data.get("initial", {}), _MASK)
    if "max_chart_angle" in data.get("attitude", {}):
        data["attitude"] = {**data["attitude"], "max_chart_angle": _MASK}
    masked = _REDUCED_FORCE_NUMBERS if body.form.reduced else _FORCE_NUMBERS
    forces = dict(data.get("forces", {}))
    for key, fields in masked.items():
        if key in forces:
            forces[key] = {k: (_MASK if k in fields else v) for k, v in forces[key].items()}
    data["forces"] = forces
    return structure_text(scene, data)


def numbers(scene: Scene) -> Numbers:
    """The initial state and every parameter value of ``scene``'s model.

    Raises
    ------
    SceneError
        A number the model cannot take: invariable-plane events of a body at rest, Ψ where it is
        undefined, an attitude the precision cannot represent, Ψ with a torque.
    """
    body: RigidBody = scene.model
    prec = scene.integrator.precision
    values: dict[str, Any] = {name: body.inertia[i] for i, name in enumerate("ABC")}
    exact_inertia = tuple(exact_fraction(v) for v in body.inertia)
    differences = eq.euler_differences(*exact_inertia)
    values |= {
        name: fraction_text(d, prec)
        for name, d in zip(("B-C", "C-A", "A-B"), differences, strict=True)
    }
    q0 = body.initial_quaternion(prec)
    rates0 = list(prec.array(body.rates))
    initial = list(rates0)
    plane = "invariable_plane" in scene.output.events
    if plane and all(exact_fraction(w) == 0 for w in body.rates):
        raise SceneError(
            "output.events",
            "invariable_plane is undefined where the angular momentum L is 0, and "
            "initial.rates are all zero: remove the event or give the body a rate",
        )
    momentum = None
    if body.torque_free and plane:
        L0 = [m * w for m, w in zip(prec.array(body.inertia), rates0, strict=True)]
        momentum = att.matvec(att.quaternion_to_matrix(list(q0)), L0)
    for force in body.forces:
        values |= force.values(prec)
    form = body.form
    if form.numbers is not None:
        state, more = form.numbers(body, prec, q0, momentum)
        initial += state
        values |= more
    if azimuth.wanted(scene.output.options, form):
        u = poisson.direction(body.forces, prec)
        values |= azimuth.values(prec, u, q0, initial[3:6], rates0)
        initial.append(prec.number(0))
    if invariable_angle.wanted(scene.output.options):
        if not body.torque_free:
            raise SceneError(
                "output.invariable_angle",
                "Ψ is the angle about the invariable line, which only a torque-free body has: "
                "remove [forces] or the option",
            )
        rates = tuple(exact_fraction(w) for w in body.rates)
        values |= invariable_angle.values(prec, exact_inertia, rates)
        initial.append(prec.number(0))
    return Numbers(initial, values)


def rodrigues_numbers(body: RigidBody, prec: Precision, q0: np.ndarray, momentum: Any) -> Attitude:
    """The first chart's λ, μ, ν, its base and limit (:attr:`.formulations.RODRIGUES`)."""
    kmax = kappa_limit(body.max_chart_angle, prec)
    values: dict[str, Any] = {"chart.kappa_max": kmax}
    # Start in the identity chart when the initial attitude fits in it, so that a short run
    # integrates Cayley's own parameters; otherwise from a chart based at the attitude.
    fits = q0[0] * q0[0] * prec.number(kmax) > 1
    one, zero = prec.number(1), prec.number(0)
    base = np.array([one, zero, zero, zero]) if fits else q0
    initial = att.quaternion_to_rodrigues(list(q0)) if fits else [zero] * 3
    values |= RodriguesAtlas.values_of(list(base), momentum)
    return list(initial), values


def quaternion_numbers(body: RigidBody, prec: Precision, q0: np.ndarray, momentum: Any) -> Attitude:
    """The unit quaternion, and L in space for the invariable-plane events
    (:attr:`.formulations.QUATERNION`)."""
    values = {} if momentum is None else space_plane_numbers(None, momentum)
    return list(q0), values


def poisson_numbers(body: RigidBody, prec: Precision, q0: np.ndarray, momentum: Any) -> Attitude:
    """γ = Rᵀu at the start (:attr:`.formulations.POISSON`; u is compiled in)."""
    u = poisson.direction(body.forces, prec)
    return list(poisson.initial_direction(q0, u, prec)), {}


def chart_plane_numbers(held: Callable[[str], Any], momentum: Any) -> dict[str, Any]:
    """The chart's parameters of the invariable-plane events: L in space and in the base
    ``held`` keeps (:attr:`.formulations.RODRIGUES`)."""
    base = [held(f"chart.base[{i}]") for i in range(4)]
    chart = RodriguesAtlas.values_of(base, momentum)
    return {k: v for k, v in chart.items() if not k.startswith("chart.base")}


def space_plane_numbers(held: Any, momentum: Any) -> dict[str, Any]:
    """L in space, which the quaternion's invariable-plane events hold
    (:attr:`.formulations.QUATERNION`)."""
    return {f"momentum_space[{i}]": momentum[i] for i in range(3)}


#: The scene fields :func:`table` computes from, and the first state index or moment each sets.
_RATES = {("initial", "rates", i): i for i in range(3)}
_MOMENTS = {("body", "inertia", i): i for i in range(3)}


def table(
    scene: Scene,
    model: Any,
    fields: tuple[tuple[str | int, ...], ...],
    x: np.ndarray,
    exact: np.ndarray,
    low: np.ndarray | None = None,
) -> Table | None:
    """The numbers of rigid bodies that are ``scene`` with other rates or moments, as arrays
    (double precision; :func:`cayley_heyoka.core.structures.table_for`).

    ``x`` holds each body's numbers at ``fields`` (``initial.rates[i]``, ``body.inertia[i]``:
    None for any other field, or where Ψ or the azimuth is wanted), ``exact`` whether each is
    the scene's number exactly (``low``, the rest of one that is not, is not needed: such a
    moment is a suspect, and a rate is rounded as the scene rounds it). Every value is computed
    in the operations, and their order, that :func:`numbers` takes: a product or difference of
    two doubles is correctly rounded in numpy as in Python, so the rows are :func:`numbers`'
    bit for bit (``table_for`` checks two).
    A body whose moments are not exact doubles or lie within rounding of the triangle
    inequality, or at rest with invariable-plane events, is a suspect: built alone.

    Examples
    --------
    >>> import numpy as np
    >>> import cayley_heyoka as ch
    >>> from cayley_heyoka.core.structures import model_for
    >>> data = {"body": {"inertia": [1, 2, 2.5]}, "initial": {"rates": [1, 0, 0]},
    ...         "output": {"times": [0, 1]}}
    >>> scene = ch.Scene.from_dict(data)
    >>> rates = np.array([[0.5], [2.0]])
    >>> t = table(scene, model_for(scene), (("initial", "rates", 1),), rates, rates == rates)
    >>> t.initial[:, :3].tolist()
    [[1.0, 0.5, 0.0], [1.0, 2.0, 0.0]]
    """
    body: RigidBody = scene.model
    if any(f not in _RATES and f not in _MOMENTS for f in fields):
        return None
    options = scene.output.options
    if azimuth.wanted(options, body.form) or invariable_angle.wanted(options):
        return None
    prec = scene.integrator.precision
    moments = [float(prec.number(m)) for m in body.inertia]
    swept = any(f in _MOMENTS for f in fields)
    if swept and any(
        exact_fraction(d) != exact_fraction(m) for d, m in zip(moments, body.inertia, strict=True)
    ):
        return None  # a difference with a moment written in decimals is not of doubles
    n = len(x)
    names = model.pars.names
    initial = np.repeat(np.asarray(model.initial_state, dtype=np.float64)[None], n, axis=0)
    pars = np.repeat(np.asarray(model.pars.values, dtype=np.float64)[None], n, axis=0)
    suspect = np.zeros(n, dtype=bool)
    rates = [initial[:, i].copy() for i in range(3)]
    columns = [np.full(n, m) for m in moments]
    for j, f in enumerate(fields):
        if f in _RATES:
            rates[_RATES[f]] = initial[:, _RATES[f]] = x[:, j]
        else:
            columns[_MOMENTS[f]] = x[:, j]
            suspect |= ~exact[:, j]
    values: dict[str, Any] = {}
    with np.errstate(all="ignore"):  # a value double cannot hold is a suspect already
        if swept:
            A, B, C = columns
            # The scene's checks are exact; within a few roundings of their edge, it decides.
            edge = 8 * np.finfo(np.float64).eps * np.maximum(np.maximum(A, B), C)
            suspect |= (A <= 0) | (B <= 0) | (C <= 0)
            suspect |= (A + B - C <= edge) | (B + C - A <= edge) | (C + A - B <= edge)
            values |= {"A": A, "B": B, "C": C, "B-C": B - C, "C-A": C - A, "A-B": A - B}
        if "invariable_plane" in scene.output.events and body.torque_free:
            suspect |= (rates[0] == 0) & (rates[1] == 0) & (rates[2] == 0)
            q0 = body.initial_quaternion(prec)
            L0 = [m * w for m, w in zip(columns, rates, strict=True)]
            momentum = att.matvec(att.quaternion_to_matrix(list(q0)), L0)
            plane = body.form.plane_numbers
            if plane is not None:
                values |= plane(lambda name: pars[0, names.index(name)], momentum)
        for name, column in values.items():
            pars[:, names.index(name)] = column
        suspect |= ~(np.isfinite(initial).all(axis=1) & np.isfinite(pars).all(axis=1))
    return Table(initial, pars, suspect)
