"""A scene's dictionary (the TOML document's shape): copied into plain types
(:func:`plain_copy`, what a scene keeps of its source) and edited by dotted paths
(:func:`edited`, for :meth:`.Scene.derive`)."""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from fractions import Fraction
from typing import Any

import numpy as np

from .errors import SceneError
from .precision import as_number

__all__ = ["edited", "plain_copy"]


def edited(
    data: dict[str, Any], changes: Mapping[str, Any], drop: Iterable[str] = ()
) -> dict[str, Any]:
    """``data`` (a scene's dictionary, changed in place and returned) with the dotted paths of
    ``drop`` removed where present and those of ``changes`` set (:meth:`Scene.derive`).

    Raises
    ------
    SceneError
        A path through something that is not a table.

    Examples
    --------
    >>> edited({"integrator": {"tolerance": "1e-12"}, "events": {}}, {"integrator.max_steps": 9},
    ...        drop=["events"])
    {'integrator': {'tolerance': '1e-12', 'max_steps': 9}}
    """
    for path in drop:
        *tables, key = path.split(".")
        node: Any = data
        for table in tables:
            node = node.get(table) if isinstance(node, dict) else None
        if isinstance(node, dict):
            node.pop(key, None)
    for path, value in changes.items():
        *tables, key = path.split(".")
        node = data
        for depth, table in enumerate(tables):
            node = node.setdefault(table, {})
            if not isinstance(node, dict):
                where = ".".join(tables[: depth + 1])
                raise SceneError(where, f"must be a table to set {path}, got {node!r}")
        node[key] = value
    return data


def plain_copy(data: Any) -> Any:
    """Deep copy into JSON-friendly types: a number of another kind (numpy, Fraction,
    real128, mpmath) becomes the int, float or text with its exact value that the scene was
    built from (:func:`~cayley_heyoka.core.precision.as_number`), so that the copy gives the
    same scene again."""
    kind = type(data)
    if kind is str or kind is float or kind is int or kind is bool or data is None:
        return data  # the common leaves first: a sweep copies every member's scene
    if kind is dict:
        return {str(k): plain_copy(v) for k, v in data.items()}
    if kind is list:
        return [plain_copy(v) for v in data]
    if isinstance(data, Mapping):
        return {str(k): plain_copy(v) for k, v in data.items()}
    if isinstance(data, list | tuple):
        return [plain_copy(v) for v in data]
    if data is None or isinstance(data, bool | str | int | float):
        return data
    try:
        return as_number(data)
    except (TypeError, ValueError):
        return str(data) if isinstance(data, Fraction | np.generic) else data
