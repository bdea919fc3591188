"""The Hamiltonian tables of a scene: ``[hamiltonian]`` and ``[initial]``.

``[hamiltonian]``
    ``model = "projectile"`` with ``g``, ``mu``, ``nu`` (Hamilton's example, §5 of the notes:
    H = ½|ϖ|² + g η₃ + ½{μ²(η₁² + η₂²) + ν² η₃²}), or ``H = "..."``: any Hamiltonian as text
    over ``eta1 … etaN``, ``varpi1 … varpiN`` and ``t``, or a split ``H1``, ``H2`` with the
    motion of H₁ in ``[hamiltonian.flow]``. ``formulation = "elements"`` integrates Hamilton's
    varying elements of the split instead of η, ϖ.
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


FORMULATIONS = ("canonical", "elements")


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
        varying elements χ, λ of the split, :mod:`.elements`).
    eta, varpi
        Coordinates and momenta at the start time.
    """

    model: str
    constants: Mapping[str, Number]
    text: str | None
    split: tuple[str, str] | None
    flow: Mapping[str, str] | None
    formulation: str
    eta: tuple[Number, ...]
    varpi: tuple[Number, ...]

    @classmethod
    def parse(cls, tables: Mapping[str, Any]) -> Hamiltonian:
        table = tables.get("hamiltonian", {})
        keys = ["model", "H", "H1", "H2", "flow", "formulation", "g", "mu", "nu"]
        check_keys(table, keys, "hamiltonian")
        given = [k for k in ("model", "H", "H1") if k in table]
        if len(given) != 1:
            raise SceneError(
                "hamiltonian",
                "give one of model = 'projectile', H = '<expression>' or H1 and H2 (a split "
                f"with its flow); got {given or 'none'}",
            )
        formulation = table.get("formulation", "canonical")
        if formulation not in FORMULATIONS:
            raise SceneError(
                "hamiltonian.formulation", f"must be one of {FORMULATIONS}, got {formulation!r}"
            )
        eta, varpi = _initial(tables, 3 if "model" in table else None)
        if "model" in table:
            model = table["model"]
            if model not in MODELS:
                raise SceneError("hamiltonian.model", f"must be one of {MODELS}, got {model!r}")
            for key in ("H2", "flow"):
                if key in table:
                    raise SceneError(f"hamiltonian.{key}", "is built in for the projectile")
            constants = {}
            for key in ("g", "mu", "nu"):
                if key not in table:
                    raise SceneError(f"hamiltonian.{key}", "is required by the projectile")
                constants[key] = number(table[key], f"hamiltonian.{key}")
            return cls(model, constants, None, None, None, formulation, eta, varpi)
        extra = [k for k in ("g", "mu", "nu") if k in table]
        if extra:
            raise SceneError(f"hamiltonian.{extra[0]}", "belongs to model = 'projectile'")
        if "H" in table:
            for key in ("H2", "flow"):
                if key in table:
                    raise SceneError(f"hamiltonian.{key}", "goes with H1, not with H")
            if formulation == "elements":
                raise SceneError(
                    "hamiltonian.formulation",
                    "'elements' needs the split H1, H2 and the flow of H1 ([hamiltonian.flow])",
                )
            return cls("expression", {}, _text(table, "H"), None, None, formulation, eta, varpi)
        split = (_text(table, "H1"), _text(table, "H2"))
        flow = None
        if "flow" in table:
            flow = _flow(table["flow"], len(eta))
        elif formulation == "elements":
            raise SceneError(
                "hamiltonian.flow", "is required by formulation = 'elements': H1's motion"
            )
        return cls("expression", {}, None, split, flow, formulation, eta, varpi)

    @property
    def degrees(self) -> int:
        """Number of coordinates N."""
        return len(self.eta)

    @property
    def time_dependent(self) -> bool:
        texts = [self.text] if self.text is not None else list(self.split or ())
        return any(uses_time(t) for t in texts)


def _text(table: Mapping[str, Any], key: str) -> str:
    if key not in table:
        raise SceneError(f"hamiltonian.{key}", "is required")
    text = table[key]
    if not isinstance(text, str) or not text.strip():
        raise SceneError(f"hamiltonian.{key}", f"must be an expression string, got {text!r}")
    return text


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
    text = table[key]
    if not isinstance(text, str) or not text.strip():
        raise SceneError(f"hamiltonian.flow.{key}", f"must be an expression string, got {text!r}")
    return text


def _length(value: Any, where: str) -> int:
    if not isinstance(value, list | tuple) or not 1 <= len(value) <= _MAX_DEGREES:
        raise SceneError(where, f"must be a list of 1 to {_MAX_DEGREES} numbers, got {value!r}")
    return len(value)
