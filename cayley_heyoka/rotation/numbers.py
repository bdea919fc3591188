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

from typing import Any

import numpy as np

from ..core.errors import SceneError
from ..core.model import Numbers
from ..core.precision import exact_fraction, fraction_text
from ..core.scene import Scene
from ..core.structures import MASK as _MASK
from ..core.structures import structure_text
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


def structure(scene: Scene) -> str:
    """The scene's model structure: its dictionary with every number the model holds as a
    parameter or an initial value masked, and without its output times (not compiled).

    Examples
    --------
    >>> import cayley_heyoka as ch
    >>> a = ch.Scene.from_dict({"body": {"inertia": [1, 2, 3]}, "initial": {"rates": [1, 0, 0]}})
    >>> b = ch.Scene.from_dict({"body": {"inertia": [2, 2, 3]}, "initial": {"rates": [0, 1, 0]}})
    >>> structure(a) == structure(b)
    True
    """
    data = {k: v for k, v in scene.source.items()}
    body: RigidBody = scene.model
    data["body"] = {**data.get("body", {}), "inertia": _MASK}
    data["initial"] = dict.fromkeys(data.get("initial", {}), _MASK)
    if "max_chart_angle" in data.get("attitude", {}):
        data["attitude"] = {**data["attitude"], "max_chart_angle": _MASK}
    masked = _REDUCED_FORCE_NUMBERS if body.formulation == "poisson" else _FORCE_NUMBERS
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
    if body.formulation == "rodrigues":
        kmax = kappa_limit(body.max_chart_angle, prec)
        values["chart.kappa_max"] = kmax
        # Start in the identity chart when the initial attitude fits in it, so that a short run
        # integrates Cayley's own parameters; otherwise from a chart based at the attitude.
        fits = q0[0] * q0[0] * prec.number(kmax) > 1
        one, zero = prec.number(1), prec.number(0)
        base = np.array([one, zero, zero, zero]) if fits else q0
        initial += att.quaternion_to_rodrigues(list(q0)) if fits else [zero] * 3
        values |= RodriguesAtlas.values_of(list(base), momentum)
    elif body.formulation == "quaternion":
        initial += list(q0)
        if momentum is not None:
            values |= {f"momentum_space[{i}]": momentum[i] for i in range(3)}
    elif body.formulation == "poisson":
        u = poisson.direction(body.forces, prec)
        gamma0 = poisson.initial_direction(q0, u, prec)
        initial += gamma0
    if azimuth.wanted(scene.output.options, body.formulation):
        values |= azimuth.values(prec, u, q0, gamma0, rates0)
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
