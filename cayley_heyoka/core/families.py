"""The registry of model families: which scene tables each owns, how it parses and builds."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from importlib import import_module
from typing import Any

from .errors import SceneError


@dataclass(frozen=True)
class Family:
    """A model family: its scene tables, the table that identifies it, parse, build, the
    checks that need the whole scene (e.g. the start time) and its consistency check
    (``consistency_check(scene, options) -> CheckReport``, ``cayley-heyoka check``)."""

    name: str
    key_table: str
    tables: tuple[str, ...]
    parse: Callable[[Mapping[str, Any]], Any]
    build: Callable[[Any], Any]
    check: Callable[[Any], None] | None = None
    output_keys: tuple[str, ...] = ()
    consistency_check: Callable[[Any, Any], Any] | None = None


def _later(module: str, name: str) -> Callable[[Any, Any], Any]:
    """``module.name``, imported when first called: the checks import the families."""

    def call(scene: Any, options: Any) -> Any:
        return getattr(import_module(module, __package__), name)(scene, options)

    return call


def _rotation() -> Family:
    from ..rotation.model import build_model
    from ..rotation.scene import RigidBody

    return Family(
        "rotation",
        "body",
        ("body", "initial", "attitude", "forces"),
        RigidBody.parse,
        build_model,
        consistency_check=_later("..rotation.closed_form_check", "check_rotation"),
    )


def _orbit() -> Family:
    from ..orbit.model import build_model, check
    from ..orbit.scene import Orbit

    tables = ("orbit", "perturbations", "reference_plane")
    return Family(
        "orbit",
        "orbit",
        tables,
        Orbit.parse,
        build_model,
        check,
        consistency_check=_later("..orbit.cartesian_check", "check_orbit"),
    )


def _hamiltonian() -> Family:
    from ..hamilton.model import build_model
    from ..hamilton.scene import Hamiltonian

    tables = ("hamiltonian", "initial")
    return Family(
        "hamiltonian",
        "hamiltonian",
        tables,
        Hamiltonian.parse,
        build_model,
        output_keys=("principal_function",),
        consistency_check=_later("..hamilton.projectile_check", "check_hamiltonian"),
    )


FAMILIES: dict[str, Family] = {f.name: f for f in (_rotation(), _orbit(), _hamiltonian())}


def family_of(data: Mapping[str, Any]) -> str:
    """The family whose identifying table the scene has."""
    found = [f.name for f in FAMILIES.values() if f.key_table in data]
    if len(found) == 1:
        return found[0]
    expected = ", ".join(f"[{f.key_table}] ({f.name})" for f in FAMILIES.values())
    if not found:
        raise SceneError("scene", f"names no model family; expected one of the tables {expected}")
    raise SceneError("scene", f"names several model families {found}; use one of {expected}")
