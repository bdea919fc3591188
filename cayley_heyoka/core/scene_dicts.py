"""A scene's dictionary (the TOML document's shape): copied into plain types
(:func:`plain_copy`, what a scene keeps of its source) and edited at scene paths such as
``initial.rates[0]`` (:func:`edited` for :meth:`.Scene.derive`, :func:`set_at` for a sweep's
members)."""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping, Sequence
from fractions import Fraction
from typing import Any

import numpy as np

from .errors import SceneError
from .precision import as_number

__all__ = ["Path", "edited", "parse_path", "plain_copy", "set_at", "show_path"]


#: One segment of a scene path: a key, then any indices (``rates[0]``), each index at most
#: 18 digits (a scene's lists are short; int() of a long digit string would be refused by
#: Python itself, or be slow).
_SEGMENT = re.compile(r"([A-Za-z0-9_-]+)((?:\[\d{1,18}\])*)")

#: The longest scene path taken (a path names a field; a refusal quotes it).
MAX_PATH_CHARS = 256

Path = tuple[str | int, ...]


def parse_path(name: str, where: str) -> Path:
    """The keys and indices of a dotted scene path with optional indices.

    Raises
    ------
    SceneError
        ``where``: ``name`` is not such a path.

    Examples
    --------
    >>> parse_path("initial.rates[0]", "sweep.parameters")
    ('initial', 'rates', 0)
    """
    if not isinstance(name, str):
        raise SceneError(where, f"must be a scene path as text, got {type(name).__name__}")
    if len(name) > MAX_PATH_CHARS:
        raise SceneError(where, f"is a path of {len(name)} characters, over {MAX_PATH_CHARS}")
    path: list[str | int] = []
    for segment in name.split("."):
        m = _SEGMENT.fullmatch(segment)
        if m is None:
            raise SceneError(
                where, 'must be a dotted scene path with optional indices, like "initial.rates[0]"'
            )
        path.append(m[1])
        path += [int(i) for i in re.findall(r"\[(\d+)\]", m[2])]
    return tuple(path)


def show_path(path: Sequence[str | int]) -> str:
    """A parsed path written back (``initial.rates[0]``)."""
    text = ""
    for key in path:
        text += f"[{key}]" if isinstance(key, int) else (f".{key}" if text else key)
    return text


def set_at(data: dict[str, Any], path: Path, value: Any) -> None:
    """Set ``value`` at ``path`` in ``data``, copying each table and list on the way (``data``
    itself is the caller's copy; what it shares with others is left as it was), a table
    the path names and ``data`` lacks added.

    Raises
    ------
    SceneError
        The path runs through a number or text, or indexes a list beyond its end.
    """
    node: Any = data
    for depth, key in enumerate(path[:-1]):
        child = node[key] if isinstance(key, int) else node.get(key, {})
        if not isinstance(child, Mapping | list | tuple):
            where = show_path(path[: depth + 1])
            raise SceneError(where, f"must be a table to set {show_path(path)}, got {child!r}")
        child = list(child) if isinstance(child, list | tuple) else dict(child)
        node[key] = child
        index = path[depth + 1]
        if isinstance(index, int):
            if not isinstance(child, list):
                raise SceneError(show_path(path[: depth + 1]), "is not a list: it takes no index")
            if index >= len(child):
                where = show_path(path[: depth + 2])
                raise SceneError(where, f"is out of range: the list has {len(child)} entries")
        elif isinstance(child, list):
            where = show_path(path[: depth + 1])
            raise SceneError(where, f"is a list: name an entry, like {where}[0]")
        node = child
    node[path[-1]] = value


def edited(
    data: dict[str, Any], changes: Mapping[str, Any], drop: Iterable[str] = ()
) -> dict[str, Any]:
    """``data`` (a scene's dictionary, changed and returned; the tables and lists on the way
    to a change copied, the rest shared) with the paths of ``drop`` removed where present and
    those of ``changes`` set (:meth:`.Scene.derive`); a path is dotted keys with optional
    indices (:func:`parse_path`).

    Raises
    ------
    SceneError
        ``changes`` not a table or ``drop`` not a list of paths; a path that is not one
        (named, or as ``changes`` / ``drop`` when it is not short text), runs through a
        number, text or a list, or indexes beyond a list's end; a list entry dropped.

    Examples
    --------
    >>> edited({"integrator": {"tolerance": "1e-12"}, "events": {}}, {"integrator.max_steps": 9},
    ...        drop=["events"])
    {'integrator': {'tolerance': '1e-12', 'max_steps': 9}}
    >>> edited({"initial": {"rates": [1, 2, 3]}}, {"initial.rates[1]": "0.5"})
    {'initial': {'rates': [1, '0.5', 3]}}
    """
    if not isinstance(changes, Mapping):
        raise SceneError("changes", f"must be a table of paths and values, got {changes!r:.60}")
    if isinstance(drop, str | bytes) or not isinstance(drop, Iterable):
        raise SceneError("drop", f"must be a list of paths, got {drop!r:.60}")
    for name in drop:
        *tables, key = parse_path(name, _where(name, "drop"))
        if isinstance(key, int):
            raise SceneError(show_path((*tables, key)), "drop removes a key, not a list entry")
        node: Any = data
        for table in tables:
            node = node.get(table) if isinstance(node, dict) else None
        if isinstance(node, dict):
            node.pop(key, None)
    for name, value in changes.items():
        set_at(data, parse_path(name, _where(name, "changes")), value)
    return data


def _where(name: Any, parameter: str) -> str:
    """How a refusal of the path ``name`` given in ``parameter`` names it: the path itself
    when it is short text, else the parameter."""
    if isinstance(name, str) and 0 < len(name) <= MAX_PATH_CHARS:
        return name
    return parameter


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
