"""The Hamiltonian family's formulations: one small object each, declaring what it integrates
and what it needs.

``hamiltonian.formulation`` names one of :data:`FORMULATIONS`; the scene keeps the name
(:attr:`.scene.Hamiltonian.formulation`) and :attr:`.scene.Hamiltonian.form` is its
:class:`Formulation`. The scene's checks, the models (:mod:`.model`,
:mod:`.predominant_mass.model`), their numbers and the closed form read the declaration here
rather than comparing names.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ..core.families import named


@dataclass(frozen=True, eq=False)
class Formulation:
    """How a Hamiltonian scene is integrated.

    Attributes
    ----------
    name
        The value of ``hamiltonian.formulation``.
    coordinates, momenta
        The stems of the state's names for an expression or the projectile (``eta1 …``,
        ``varpi1 …``, or ``chi1 …``, ``lambda1 …``): each starts at ``initial.eta[i]``,
        ``initial.varpi[i]``.
    elements
        The state is Hamilton's varying elements rather than the canonical coordinates and
        momenta: of the split H = H₁ + H₂ through H₁'s flow (:mod:`.elements`), or of every
        body's orbit about the predominant mass, held as offsets from their start values
        (:mod:`.predominant_mass`). The equations, their coefficients and the starting state
        follow it.
    needs_flow
        An expression's H must be the split H₁, H₂ with H₁'s flow (``[hamiltonian.flow]``).
    from_zero
        An expression or the projectile starts at t = 0 (its elements are the initial data
        there).
    ellipses
        The bodies about the predominant mass move on bound, eccentric, inclined orbits (the
        element equations are singular on the others).
    compact
        The predominant mass is compiled in compact mode whatever the number of bodies.
    closed_form
        Hamilton's projectile in closed form (:mod:`.projectile_reference`) is compared with
        it: its state is η, ϖ.
    """

    name: str
    coordinates: str
    momenta: str
    elements: bool = False
    needs_flow: bool = False
    from_zero: bool = False
    ellipses: bool = False
    compact: bool = False
    closed_form: bool = False

    def __reduce__(self) -> tuple[Any, tuple[str]]:
        # By name: one object per formulation.
        return formulation, (self.name,)


CANONICAL = Formulation("canonical", "eta", "varpi", closed_form=True)
ELEMENTS = Formulation(
    "elements",
    "chi",
    "lambda",
    elements=True,
    needs_flow=True,
    from_zero=True,
    ellipses=True,
    compact=True,
)

#: Every formulation, by name (in the order the scene's error lists them).
BY_NAME = {f.name: f for f in (CANONICAL, ELEMENTS)}
FORMULATIONS = tuple(BY_NAME)


def formulation(name: Any) -> Formulation:
    """The formulation ``hamiltonian.formulation = name`` names.

    Raises
    ------
    SceneError
        ``hamiltonian.formulation``: ``name`` is none of :data:`FORMULATIONS`.
    """
    return named(BY_NAME, "hamiltonian.formulation", name)
