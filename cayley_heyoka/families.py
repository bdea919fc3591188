"""The registry of model families: which scene tables each owns, how it parses and builds."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from .errors import SceneError


@dataclass(frozen=True)
class Family:
    """A model family: its scene tables, the table that identifies it, parse and build."""

    name: str
    key_table: str
    tables: tuple[str, ...]
    parse: Callable[[Mapping[str, Any]], Any]
    build: Callable[[Any], Any]


def _rotation() -> Family:
    from .rotation.model import build_model
    from .rotation.scene import RigidBody

    return Family(
        "rotation", "body", ("body", "initial", "attitude", "forces"), RigidBody.parse, build_model
    )


FAMILIES: dict[str, Family] = {f.name: f for f in (_rotation(),)}


def family_of(data: Mapping[str, Any]) -> str:
    """The family whose identifying table the scene has."""
    found = [f.name for f in FAMILIES.values() if f.key_table in data]
    if len(found) == 1:
        return found[0]
    expected = ", ".join(f"[{f.key_table}] ({f.name})" for f in FAMILIES.values())
    if not found:
        raise SceneError("scene", f"names no model family; expected one of the tables {expected}")
    raise SceneError("scene", f"names several model families {found}; use one of {expected}")
