"""The Hamiltonian tables of a scene: ``[hamiltonian]`` and ``[initial]``.

``[hamiltonian]``
    ``model = "projectile"`` with ``g``, ``mu``, ``nu`` (Hamilton's example, §5 of the notes:
    H = ½|ϖ|² + g η₃ + ½{μ²(η₁² + η₂²) + ν² η₃²}), or ``H = "..."``: any Hamiltonian as text
    over ``eta1 … etaN``, ``varpi1 … varpiN`` and ``t``.
``[initial]``
    ``eta`` and ``varpi``: the coordinates and momenta at the start time (N each; N = 3 for
    the projectile).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from ..errors import SceneError
from ..expressions import uses_time
from ..precision import Number
from ..scene import check_keys, number, vector

MODELS = ("projectile",)
_MAX_DEGREES = 60


@dataclass(frozen=True)
class Hamiltonian:
    """A canonical system.

    Attributes
    ----------
    model
        ``"projectile"`` or ``"expression"`` (a user Hamiltonian in :attr:`text`).
    constants
        ``{"g", "mu", "nu"}`` of the projectile; empty for an expression.
    text
        The user Hamiltonian, or None.
    eta, varpi
        Coordinates and momenta at the start time.
    """

    model: str
    constants: Mapping[str, Number]
    text: str | None
    eta: tuple[Number, ...]
    varpi: tuple[Number, ...]

    @classmethod
    def parse(cls, tables: Mapping[str, Any]) -> Hamiltonian:
        table = tables.get("hamiltonian", {})
        check_keys(table, ["model", "H", "g", "mu", "nu"], "hamiltonian")
        if ("model" in table) == ("H" in table):
            raise SceneError(
                "hamiltonian", "give either model = 'projectile' or H = '<expression>', not both"
            )
        initial = tables.get("initial")
        if initial is None:
            raise SceneError("initial", "is required: eta and varpi at the start time")
        check_keys(initial, ["eta", "varpi"], "initial")
        for key in ("eta", "varpi"):
            if key not in initial:
                raise SceneError(f"initial.{key}", "is required")
        if "H" in table:
            extra = [k for k in ("g", "mu", "nu") if k in table]
            if extra:
                raise SceneError(f"hamiltonian.{extra[0]}", "belongs to model = 'projectile'")
            text = table["H"]
            if not isinstance(text, str) or not text.strip():
                raise SceneError("hamiltonian.H", f"must be an expression string, got {text!r}")
            n = _length(initial["eta"], "initial.eta")
            eta = vector(initial["eta"], "initial.eta", n)
            varpi = vector(initial["varpi"], "initial.varpi", n)
            return cls("expression", {}, text, eta, varpi)
        model = table["model"]
        if model not in MODELS:
            raise SceneError("hamiltonian.model", f"must be one of {MODELS}, got {model!r}")
        constants = {}
        for key in ("g", "mu", "nu"):
            if key not in table:
                raise SceneError(f"hamiltonian.{key}", "is required by the projectile")
            constants[key] = number(table[key], f"hamiltonian.{key}")
        eta = vector(initial["eta"], "initial.eta", 3)
        varpi = vector(initial["varpi"], "initial.varpi", 3)
        return cls(model, constants, None, eta, varpi)

    @property
    def degrees(self) -> int:
        """Number of coordinates N."""
        return len(self.eta)

    @property
    def time_dependent(self) -> bool:
        return self.text is not None and uses_time(self.text)


def _length(value: Any, where: str) -> int:
    if not isinstance(value, list | tuple) or not 1 <= len(value) <= _MAX_DEGREES:
        raise SceneError(where, f"must be a list of 1 to {_MAX_DEGREES} numbers, got {value!r}")
    return len(value)
