"""The scene schema: parse a TOML file or a dictionary, validate it, explain what is wrong.

A scene is a nested dictionary (the TOML document). Its model family is recognised by the
family's table (``[body]`` for rigid-body rotation); the generic tables are

``[integrator]``
    ``precision`` ("double", "quad" or ``{bits = N}``), ``tolerance`` ("auto" or a positive
    number), ``compact_mode`` ("auto", true, false), ``high_accuracy`` (bool).
``[output]``
    ``times`` (``{start, stop, count}`` or a list of increasing numbers), ``events`` (names of
    events to record), ``monitors`` (names of monitored quantities; default: all available).
``[events.NAME]``
    A user event: ``expression`` (text over the model's variables and ``t``) and
    ``direction`` ("any", "up", "down").

The full schema, with the family tables, is documented in ``docs/scenes.md``.

Numbers are kept as they were written: TOML floats are read as their decimal text (never
rounded to double on the way in), so a quadruple-precision run sees ``0.1`` exactly as typed.
"""

from __future__ import annotations

import difflib
import math
import tomllib
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np

from .errors import SceneError
from .precision import Number, Precision, exact_fraction

_DIRECTIONS = {"any": 0, "up": 1, "down": -1}


# ---------------------------------------------------------------------- helpers for families
def check_keys(table: Mapping[str, Any], allowed: Iterable[str], where: str) -> None:
    """Refuse unknown keys, suggesting the nearest valid one."""
    if not isinstance(table, Mapping):
        raise SceneError(where, f"must be a table, got {type(table).__name__}")
    allowed = list(allowed)
    for key in table:
        if key not in allowed:
            near = difflib.get_close_matches(key, allowed, n=1, cutoff=0.5)
            hint = f"; did you mean {near[0]!r}?" if near else f"; valid keys: {', '.join(allowed)}"
            raise SceneError(_join(where, key), f"unknown key{hint}")


def number(value: Any, where: str, *, positive: bool = False, nonneg: bool = False) -> Number:
    """Validate a finite scene number (and its sign); return it unchanged."""
    if isinstance(value, bool) or not isinstance(value, int | float | str):
        raise SceneError(where, f"must be a number, got {value!r}")
    try:
        f = exact_fraction(value)
    except (ValueError, ZeroDivisionError, OverflowError):
        raise SceneError(where, f"must be a finite number, got {value!r}") from None
    if positive and f <= 0:
        raise SceneError(where, f"must be > 0, got {value}")
    if nonneg and f < 0:
        raise SceneError(where, f"must be >= 0, got {value}")
    return value


def vector(value: Any, where: str, length: int) -> tuple[Number, ...]:
    """Validate a list of ``length`` finite numbers."""
    if not isinstance(value, list | tuple) or len(value) != length:
        raise SceneError(where, f"must be a list of {length} numbers, got {value!r}")
    return tuple(number(v, f"{where}[{i}]") for i, v in enumerate(value))


def unit_vector(value: Any, where: str) -> tuple[Number, ...]:
    """A 3-vector of unit length (to 1e-12), so that no direction is silently rescaled."""
    v = vector(value, where, 3)
    norm2 = float(sum(exact_fraction(c) ** 2 for c in v))
    if abs(math.sqrt(norm2) - 1.0) > 1e-12:
        raise SceneError(where, f"must be a unit vector, has norm {math.sqrt(norm2):.17g}")
    return v


def _join(where: str, key: str) -> str:
    return f"{where}.{key}" if where else key


# ---------------------------------------------------------------------- generic tables
@dataclass(frozen=True)
class IntegratorOptions:
    """How to integrate: precision, tolerance ("auto" = the precision's epsilon), code model."""

    precision: Precision = field(default_factory=Precision)
    tolerance: Number | None = None
    compact_mode: bool | None = None
    high_accuracy: bool = False
    max_step: Number | None = None

    @classmethod
    def parse(cls, table: Mapping[str, Any]) -> IntegratorOptions:
        check_keys(
            table,
            ["precision", "tolerance", "compact_mode", "high_accuracy", "max_step"],
            "integrator",
        )
        precision = Precision.from_spec(table.get("precision", "double"))
        tol = table.get("tolerance", "auto")
        tolerance = None if tol == "auto" else number(tol, "integrator.tolerance", positive=True)
        compact = table.get("compact_mode", "auto")
        if compact not in ("auto", True, False):
            raise SceneError(
                "integrator.compact_mode", f"must be 'auto', true or false: {compact!r}"
            )
        high = table.get("high_accuracy", False)
        if not isinstance(high, bool):
            raise SceneError("integrator.high_accuracy", f"must be true or false, got {high!r}")
        step = table.get("max_step", "none")
        max_step = None if step == "none" else number(step, "integrator.max_step", positive=True)
        return cls(precision, tolerance, None if compact == "auto" else compact, high, max_step)


@dataclass(frozen=True)
class OutputOptions:
    """When to record, and what."""

    times: tuple[Number, ...] | None = None
    grid: tuple[Number, Number, int] | None = None
    events: tuple[str, ...] = ()
    monitors: tuple[str, ...] | None = None
    options: Mapping[str, Any] = field(default_factory=dict)

    @classmethod
    def parse(cls, table: Mapping[str, Any], family_keys: Iterable[str] = ()) -> OutputOptions:
        """``family_keys``: output keys a model family adds (kept in :attr:`options`)."""
        family_keys = tuple(family_keys)
        check_keys(table, ["times", "events", "monitors", *family_keys], "output")
        if "times" not in table:
            raise SceneError("output.times", "is required ({start, stop, count} or a list)")
        times, grid = _parse_times(table["times"])
        events = table.get("events", [])
        if not isinstance(events, list) or not all(isinstance(e, str) for e in events):
            raise SceneError("output.events", f"must be a list of event names, got {events!r}")
        monitors = table.get("monitors")
        if monitors is not None and (
            not isinstance(monitors, list) or not all(isinstance(m, str) for m in monitors)
        ):
            raise SceneError("output.monitors", f"must be a list of names, got {monitors!r}")
        options = {k: table[k] for k in family_keys if k in table}
        return cls(
            times, grid, tuple(events), None if monitors is None else tuple(monitors), options
        )

    def time_grid(self, precision: Precision) -> np.ndarray:
        """The output times in the target precision (a grid is built there, not in double)."""
        if self.times is not None:
            return precision.array(self.times)
        start, stop, count = self.grid
        a, b = precision.number(start), precision.number(stop)
        if count == 1:
            return precision.array([start])
        n = count - 1
        return np.array(
            [a + (b - a) * precision.number(k) / precision.number(n) for k in range(count)]
        )


def _parse_times(spec: Any) -> tuple[tuple[Number, ...] | None, tuple | None]:
    where = "output.times"
    if isinstance(spec, Mapping):
        check_keys(spec, ["start", "stop", "count"], where)
        missing = [k for k in ("start", "stop", "count") if k not in spec]
        if missing:
            raise SceneError(where, f"a grid needs start, stop and count; missing {missing}")
        start = number(spec["start"], f"{where}.start")
        stop = number(spec["stop"], f"{where}.stop")
        count = spec["count"]
        if isinstance(count, str) and count.isdigit():
            count = int(count)
        if isinstance(count, bool) or not isinstance(count, int) or count < 1:
            raise SceneError(f"{where}.count", f"must be an integer >= 1, got {count!r}")
        if count > 1 and exact_fraction(stop) <= exact_fraction(start):
            raise SceneError(where, f"stop ({stop}) must be greater than start ({start})")
        return None, (start, stop, count)
    if isinstance(spec, list | tuple):
        if not spec:
            raise SceneError(where, "must not be empty")
        values = tuple(number(v, f"{where}[{i}]") for i, v in enumerate(spec))
        fr = [exact_fraction(v) for v in values]
        for i in range(1, len(fr)):
            if fr[i] <= fr[i - 1]:
                raise SceneError(
                    where,
                    f"must be strictly increasing; [{i - 1}] = {values[i - 1]} >= "
                    f"[{i}] = {values[i]}",
                )
        return values, None
    raise SceneError(where, f"must be {{start, stop, count}} or a list, got {spec!r}")


@dataclass(frozen=True)
class UserEvent:
    """An event on any expression of the model's variables."""

    name: str
    expression: str
    direction: int = 0

    @classmethod
    def parse(cls, name: str, table: Mapping[str, Any]) -> UserEvent:
        where = f"events.{name}"
        check_keys(table, ["expression", "direction"], where)
        if "expression" not in table:
            raise SceneError(f"{where}.expression", "is required")
        direction = table.get("direction", "any")
        if direction not in _DIRECTIONS:
            raise SceneError(f"{where}.direction", f"must be 'any', 'up' or 'down': {direction!r}")
        return cls(name, table["expression"], _DIRECTIONS[direction])


# ---------------------------------------------------------------------- the scene
@dataclass(frozen=True)
class Scene:
    """A validated scene.

    Build one with :meth:`from_dict`, :meth:`from_toml` or :func:`load_scene`; the plain
    dictionary it came from is kept in :attr:`source` (and written into result files).
    """

    family: str
    model: Any
    integrator: IntegratorOptions
    output: OutputOptions
    events: Mapping[str, UserEvent]
    title: str
    source: Mapping[str, Any]

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Scene:
        """Validate a scene given as nested dictionaries (the TOML document's shape)."""
        from .families import FAMILIES, family_of

        if not isinstance(data, Mapping):
            raise SceneError("scene", f"must be a table, got {type(data).__name__}")
        family = family_of(data)
        spec = FAMILIES[family]
        generic = ["title", "integrator", "output", "events"]
        check_keys(data, [*generic, *spec.tables], "")
        title = data.get("title", "")
        if not isinstance(title, str):
            raise SceneError("title", f"must be a string, got {title!r}")
        integrator = IntegratorOptions.parse(data.get("integrator", {}))
        output = OutputOptions.parse(data.get("output", {}), spec.output_keys)
        events_table = data.get("events", {})
        if not isinstance(events_table, Mapping):
            raise SceneError("events", "must be a table of [events.NAME] tables")
        events = {n: UserEvent.parse(n, t) for n, t in events_table.items()}
        model = spec.parse({k: data[k] for k in spec.tables if k in data})
        scene = cls(family, model, integrator, output, events, title, _plain(data))
        if spec.check is not None:
            spec.check(scene)
        return scene

    @classmethod
    def from_toml(cls, text: str) -> Scene:
        """Parse TOML text (floats kept as their decimal text)."""
        try:
            data = tomllib.loads(text, parse_float=str)
        except tomllib.TOMLDecodeError as exc:
            raise SceneError("scene", f"not valid TOML: {exc}") from None
        return cls.from_dict(data)

    def to_dict(self) -> dict[str, Any]:
        """The plain dictionary this scene was built from."""
        return _plain(self.source)


def load_scene(path: str | Path) -> Scene:
    """Read and validate a scene file."""
    return Scene.from_toml(Path(path).read_text())


def _plain(data: Any) -> Any:
    """Deep copy into JSON-friendly types (Fractions and numpy scalars become text)."""
    if isinstance(data, Mapping):
        return {str(k): _plain(v) for k, v in data.items()}
    if isinstance(data, list | tuple):
        return [_plain(v) for v in data]
    if isinstance(data, Fraction | np.generic):
        return str(data)
    return data
