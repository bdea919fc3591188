"""The numbers of a Hamiltonian scene's model, and the structure they fill.

:func:`numbers` is the one place a Hamiltonian model's numbers are computed — the starting
η, ϖ (and S = 0), the projectile's g, μ²/2 and ν²/2, and for ``model = "predominant_mass"``
the coefficients and starting state of :mod:`.predominant_mass.numbers` — so that
:func:`cayley_heyoka.hamilton.model.build_model` and a scene of an already built structure
(:mod:`cayley_heyoka.core.structures`) take the same values. :func:`structure` names what the
build compiles: the scene with those numbers masked and without its output times. The
literals of the scene's texts (H, H₁, H₂, the flow, events, monitors) are not masked: they are
parameters ``FIELD#k`` the structure owns, equal texts giving equal values, and the flow of a
split is checked on them.
"""

from __future__ import annotations

from fractions import Fraction
from typing import Any

from ..core.errors import SceneError
from ..core.model import Numbers, ParTable
from ..core.precision import exact_fraction, fraction_text
from ..core.scene import Scene
from ..core.structures import MASK as _MASK
from ..core.structures import structure_text
from .outputs import wants_principal_function
from .predominant_mass import numbers as predominant_mass
from .scene import Hamiltonian


def structure(scene: Scene) -> str:
    """The scene's model structure: its dictionary with every number the model holds as a
    parameter or an initial value masked, and without its output times (not compiled; the
    start time a formulation needs is checked or used by :func:`numbers`).

    Examples
    --------
    >>> import cayley_heyoka as ch
    >>> def scene(g, eta):
    ...     return ch.Scene.from_dict({
    ...         "hamiltonian": {"model": "projectile", "g": g, "mu": "0.3", "nu": "0.4"},
    ...         "initial": {"eta": eta, "varpi": ["0", "1", "2"]},
    ...         "output": {"times": [0, 1]}})
    >>> structure(scene("1", ["0", "0", "1"])) == structure(scene("9.8", ["1", "2", "3"]))
    True
    """
    ham: Hamiltonian = scene.model
    data = {k: v for k, v in scene.source.items()}
    table = dict(data.get("hamiltonian", {}))
    if ham.model == "predominant_mass":
        table = predominant_mass.masked(table)
    elif ham.model == "projectile":
        table |= {key: _MASK for key in ("g", "mu", "nu") if key in table}
    data["hamiltonian"] = table
    if "initial" in data:
        # The lengths stay: N is the number of degrees of freedom.
        initial = data["initial"]
        data["initial"] = {
            k: [_MASK] * len(v) if isinstance(v, list | tuple) else _MASK
            for k, v in initial.items()
        }
    return structure_text(scene, data)


def numbers(scene: Scene) -> Numbers:
    """The initial state and every parameter value of ``scene``'s model (the literals of its
    texts excepted: the structure's).

    Raises
    ------
    SceneError
        ``formulation = "elements"`` from a start time other than 0 (``output.times``), a
        number the precision cannot hold, and the predominant mass's refusals
        (:func:`.predominant_mass.numbers.numbers`).
    """
    ham: Hamiltonian = scene.model
    if ham.model == "predominant_mass":
        return predominant_mass.numbers(scene)
    prec = scene.integrator.precision
    values: dict[str, Any] = {}
    if ham.model == "projectile":
        values["projectile.g"] = ham.constants["g"]
        for key in ("mu", "nu"):
            # The square taken exactly and rounded once: no product of parameters is left for
            # heyoka to evaluate at every Taylor order.
            value = Fraction(exact_fraction(ham.constants[key])) ** 2 / 2
            values[f"projectile.{key}_squared_half"] = fraction_text(value, prec)
    if ham.form.from_zero:
        out = scene.output
        start = out.times[0] if out.times is not None else out.grid[0]
        if exact_fraction(start) != 0:
            raise SceneError(
                "output.times",
                f"formulation = {ham.form.name!r} starts at t = 0: its elements are the initial "
                "data there",
            )
    # (χ, λ) start at (η, ϖ): the flow of H₁ is the identity at t = 0.
    initial: list[Any] = [*ham.eta, *ham.varpi]
    if wants_principal_function(scene):
        initial.append(0)
    return Numbers([prec.number(v) for v in initial], values)


def same_numbers(pars: ParTable, given: Numbers) -> None:
    """Raise RuntimeError unless the model's parameters are exactly those ``given`` names,
    with the literals of its texts (``FIELD#k``) beside them: a scene filled with
    :func:`numbers` would otherwise miss a value, or carry one its model does not have."""
    built = {name for name in pars.names if "#" not in name}
    if built != set(given.values):
        missing, extra = sorted(built - set(given.values)), sorted(set(given.values) - built)
        raise RuntimeError(
            f"the Hamiltonian model's parameters are not its numbers': {missing} have no value, "
            f"{extra} are not parameters (a fault of the family)"
        )
