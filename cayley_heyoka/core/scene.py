"""The scene schema: parse a TOML file or a dictionary, validate it, explain what is wrong.

A scene is a nested dictionary (the TOML document). Its model family is recognised by the
family's table (``[body]`` for rigid-body rotation); the generic tables are

``[integrator]``
    ``precision`` ("double", "quad" or ``{bits = N}``), ``tolerance`` ("auto" or a number in
    [epsilon, 1) of the precision), ``compact_mode`` ("auto", true, false),
    ``high_accuracy`` (bool), ``max_step`` ("none" or a positive number), ``max_steps`` (the
    step budget, :data:`DEFAULT_MAX_STEPS`).
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

import collections
import contextlib
import contextvars
import difflib
import functools
import math
import pickle
import tomllib
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np

from .errors import OptionError, SceneError
from .names import SCENE_TABLES, check_scene, name_problem
from .precision import (
    NUMBER_KINDS,
    Number,
    Precision,
    as_number,
    exact_fraction,
    shown,
    unit_length,
)
from .scene_dicts import edited, plain_copy

_DIRECTIONS = {"any": 0, "up": 1, "down": -1}

#: The step budget of a run (``integrator.max_steps``): ten times the longest run of our own
#: validation (10⁸ steps, validation/bench_conservation.py), minutes in double. A run that
#: spends it stops cleanly with its results; the budget exists so that nothing runs forever.
DEFAULT_MAX_STEPS = 10**9
#: The largest step budget: heyoka counts steps in 64 bits (10³⁰ was a TypeError from its
#: binding), and 10¹⁸ steps are centuries of computing anyway.
MAX_MAX_STEPS = 10**18
#: The smallest tolerance accepted, as a fraction of the precision's epsilon.
TOLERANCE_FLOOR = Fraction(1, 10**6)
#: Output times at most (10⁷ rows of a 20-number model are 1.6 GB in double); the engine also
#: bounds the recorded rows' estimated memory (:data:`.recording.MAX_RECORD_BYTES`).
MAX_OUTPUT_TIMES = 10**7
#: Largest scene file read (a list of 10⁷ output times as text is ~200 MB; nothing else is big).
MAX_SCENE_BYTES = 256 * 2**20
#: Deepest nesting of tables and lists (the schema needs 4; tomllib recurses once per level).
MAX_SCENE_DEPTH = 16


# ---------------------------------------------------------------------- helpers for families
#: Where :func:`recording_keys` gathers the keys each table allows (None: not recording).
_KEYS: contextvars.ContextVar[list[tuple[str, tuple[str, ...]]] | None] = contextvars.ContextVar(
    "cayley_heyoka_keys", default=None
)


def check_keys(table: Mapping[str, Any], allowed: Iterable[str], where: str) -> None:
    """Refuse unknown keys, suggesting the nearest valid one."""
    allowed = list(allowed)
    if (calls := _KEYS.get()) is not None:
        calls.append((where, tuple(allowed)))
    if not isinstance(table, Mapping):
        raise SceneError(where, f"must be a table, got {type(table).__name__}")
    for key in table:
        if key not in allowed:
            near = difflib.get_close_matches(key, allowed, n=1, cutoff=0.5)
            hint = f"; did you mean {near[0]!r}?" if near else f"; valid keys: {', '.join(allowed)}"
            raise SceneError(_join(where, key), f"unknown key{hint}")


@contextlib.contextmanager
def recording_keys() -> Iterator[list[tuple[str, tuple[str, ...]]]]:
    """The keys each table allows, as the parsers check them: every :func:`check_keys` call
    made within the context, in order, as ``(where, allowed)`` (the top level is ``""``).
    Every parser of scene and study files refuses unknown keys through :func:`check_keys`, so
    this is the schema as the code enforces it (the hostile suite's coverage test lists it).

    Examples
    --------
    >>> with recording_keys() as calls:
    ...     _ = Scene.from_dict({"body": {"inertia": [1, 2, 3]},
    ...                          "initial": {"rates": [0, 0, 1]},
    ...                          "output": {"times": [0, 1]}})
    >>> dict(calls)["body"]
    ('inertia',)
    """
    calls: list[tuple[str, tuple[str, ...]]] = []
    token = _KEYS.set(calls)
    try:
        yield calls
    finally:
        _KEYS.reset(token)


def number(value: Any, where: str, *, positive: bool = False, nonneg: bool = False) -> Number:
    """Validate a finite scene number (and its sign) given as any kind of number
    :func:`~cayley_heyoka.core.precision.as_number` takes; return it as an int, a float or
    decimal text with the same exact value.

    While :meth:`Scene.from_dict` parses a scene, each number is also noted with ``where``:
    the scene then checks it in the run's precision, naming that field.
    """
    try:
        value = as_number(value)
    except TypeError:
        raise SceneError(where, f"must be a number ({NUMBER_KINDS}), got {shown(value)}") from None
    except ValueError as exc:
        raise SceneError(where, f"must be a finite number: {exc}") from None
    try:
        f = exact_fraction(value)
    except (ValueError, OverflowError) as exc:  # text outside the grammar, inf or nan
        raise SceneError(where, f"must be a finite number: {exc}") from None
    if positive and f <= 0:
        raise SceneError(where, f"must be > 0, got {shown(value)}")
    if nonneg and f < 0:
        raise SceneError(where, f"must be >= 0, got {shown(value)}")
    noted = _NOTED.get()
    if noted is not None:
        noted.append((where, value))
    return value


def expression_text(value: Any, where: str) -> str:
    """Validate the text of an expression a scene writes (a force function, an event, a
    monitor, a Hamiltonian); return it unchanged. Its grammar and names are checked when the
    model is built (:func:`cayley_heyoka.core.expressions.parse_expression`)."""
    if not isinstance(value, str) or not value.strip():
        raise SceneError(where, f"must be a non-empty expression string, got {value!r}")
    return value


#: The numbers :func:`number` validated while :meth:`Scene.from_dict` parses, with their fields.
_NOTED: contextvars.ContextVar[list[tuple[str, Number]] | None] = contextvars.ContextVar(
    "scene_numbers", default=None
)


@contextlib.contextmanager
def checked_numbers(precision: Precision | None = None) -> Iterator[list[tuple[str, Number]]]:
    """Note every number :func:`number` validates in the block, with its field; at the end of
    the block hold each in ``precision`` (:meth:`~.precision.Precision.hold`: refused naming
    its field). Without ``precision`` the caller holds the noted list itself (the scene's
    precision is known only once its ``[integrator]`` table is read)."""
    noted: list[tuple[str, Number]] = []
    token = _NOTED.set(noted)
    try:
        yield noted
    finally:
        _NOTED.reset(token)
    if precision is not None:
        for where, value in noted:
            precision.hold(value, where)


def vector(value: Any, where: str, length: int) -> tuple[Number, ...]:
    """Validate a list of ``length`` finite numbers."""
    if not isinstance(value, list | tuple) or len(value) != length:
        raise SceneError(where, f"must be a list of {length} numbers, got {value!r}")
    return tuple(number(v, f"{where}[{i}]") for i, v in enumerate(value))


def unit_vector(value: Any, where: str) -> tuple[Number, ...]:
    """A 3-vector of unit length to 1e-12 (a guard against typos, not a rescaling: the model
    normalises it in the run's precision, :func:`cayley_heyoka.core.precision.normalised`)."""
    v = vector(value, where, 3)
    unit, norm = unit_length(v, Fraction(1, 10**12))
    if not unit:
        raise SceneError(where, f"must be a unit vector, has norm {norm}")
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
    max_steps: int = DEFAULT_MAX_STEPS

    @classmethod
    def parse(cls, table: Mapping[str, Any]) -> IntegratorOptions:
        check_keys(
            table,
            ["precision", "tolerance", "compact_mode", "high_accuracy", "max_step", "max_steps"],
            "integrator",
        )
        precision = Precision.from_spec(table.get("precision", "double"))
        tol = table.get("tolerance", "auto")
        tolerance = None if tol == "auto" else number(tol, "integrator.tolerance", positive=True)
        # heyoka's order grows like -log(tol)/2. A tolerance somewhat below epsilon can pay
        # where the state is small next to its scale (Encke's deviation at 1e-18 in double:
        # 600x less position error, validation/BENCHMARKS.md, "IAS15"), but past
        # TOLERANCE_FLOOR x epsilon only the compilation grows (1e-310 in double compiled for
        # 14 minutes and 3 GB before it was killed). (Relative slack 2^-20: epsilon's
        # shortest decimal text may fall just below it.)
        floor = Fraction(2) ** (1 - precision.bits) * TOLERANCE_FLOOR * (1 - Fraction(1, 2**20))
        if tolerance is not None and exact_fraction(tolerance) >= 1:
            raise SceneError(
                "integrator.tolerance", f"must be < 1 (it is a relative error), got {tolerance}"
            )
        if tolerance is not None and exact_fraction(tolerance) < floor:
            raise SceneError(
                "integrator.tolerance",
                f"must be >= 1e-6 x the epsilon of {precision.name} (2^{1 - precision.bits} = "
                f"{precision.epsilon!r}), got {tolerance}: below that heyoka's order grows "
                "with nothing to gain; raise the precision instead",
            )
        compact = table.get("compact_mode", "auto")
        if compact != "auto" and not isinstance(compact, bool):
            raise SceneError(
                "integrator.compact_mode", f"must be 'auto', true or false: {compact!r}"
            )
        high = table.get("high_accuracy", False)
        if not isinstance(high, bool):
            raise SceneError("integrator.high_accuracy", f"must be true or false, got {high!r}")
        step = table.get("max_step", "none")
        max_step = None if step == "none" else number(step, "integrator.max_step", positive=True)
        budget = table.get("max_steps", DEFAULT_MAX_STEPS)
        if (
            isinstance(budget, bool)
            or not isinstance(budget, int)
            or not 1 <= budget <= MAX_MAX_STEPS
        ):
            raise SceneError(
                "integrator.max_steps",
                f"must be an integer in 1 … 10^18 (a step budget), got {budget!r}",
            )
        compact_mode = None if compact == "auto" else compact
        return cls(precision, tolerance, compact_mode, high, max_step, budget)


@dataclass(frozen=True)
class OutputOptions:
    """When to record, and what."""

    times: tuple[Number, ...] | None = None
    grid: tuple[Number, Number, int] | None = None
    events: tuple[str, ...] = ()
    monitors: tuple[str, ...] | None = None
    options: Mapping[str, Any] = field(default_factory=dict)
    units: Mapping[str, str] = field(default_factory=dict)

    @classmethod
    def parse(cls, table: Mapping[str, Any], family_keys: Iterable[str] = ()) -> OutputOptions:
        """``family_keys``: output keys a model family adds (kept in :attr:`options`)."""
        family_keys = tuple(family_keys)
        check_keys(table, ["times", "events", "monitors", "units", *family_keys], "output")
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
        for where, names in (("output.events", events), ("output.monitors", monitors or [])):
            if twice := sorted(n for n, k in collections.Counter(names).items() if k > 1):
                raise SceneError(where, f"names {', '.join(map(repr, twice))} more than once")
        options = {k: table[k] for k in family_keys if k in table}
        return cls(
            times,
            grid,
            tuple(events),
            None if monitors is None else tuple(monitors),
            options,
            _parse_units(table.get("units", {})),
        )

    @property
    def count(self) -> int:
        """The number of output times."""
        return len(self.times) if self.times is not None else self._grid()[2]

    def span(self) -> tuple[Number, Number]:
        """The first and last output times, as written."""
        if self.times is not None:
            return self.times[0], self.times[-1]
        start, stop, count = self._grid()
        return start, stop if count > 1 else start

    def _grid(self) -> tuple[Number, Number, int]:
        """The grid, when the times are not a list (:meth:`parse` sets exactly one of them)."""
        assert self.grid is not None, "output options with neither times nor a grid"
        return self.grid

    def time_grid(self, precision: Precision) -> np.ndarray:
        """The output times in the target precision (a grid is built there, not in double).

        Raises
        ------
        SceneError
            If two times are equal once rounded to ``precision`` (increasing as written is
            not enough: 0.1 and 0.10000000000000000001 are one double), a time or the span
            from the first to the last is beyond the precision's range.
        """
        return _time_grid(self.times, self.grid, precision)


@functools.lru_cache(maxsize=16)
def _time_grid(
    times: tuple[Number, ...] | None, spec: tuple[Number, Number, int] | None, precision: Precision
) -> np.ndarray:
    """:meth:`OutputOptions.time_grid`, computed once for the members of a sweep, which share
    their base scene's output times (a quad grid of 1000 times costs ~3 ms)."""
    if times is not None:
        grid = precision.array(times)
    else:
        assert spec is not None, "output options with neither times nor a grid"
        grid = _spaced(*spec, precision)
    wild = np.flatnonzero(~np.isfinite(grid))
    if len(wild):
        raise SceneError(
            "output.times",
            f"time [{wild[0]}] is {grid[wild[0]]} in {precision.name}: the grid overflows",
        )
    with np.errstate(over="ignore"):
        span = grid[-1] - grid[0]
    if not np.isfinite(span):
        # Quad and MPFR cannot get here (see above); heyoka measures a run by its span.
        raise SceneError(
            "output.times",
            f"spans {float(grid[0])!r} to {float(grid[-1])!r}, a length beyond "
            f"{precision.name}'s range (about 1.8e308): the integrator cannot measure it; "
            "shorten the span or choose quad",
        )
    if len(grid) > 1:
        same = np.flatnonzero(~(grid[1:] > grid[:-1]))
        if len(same):
            i = int(same[0])
            raise SceneError(
                "output.times",
                f"must be strictly increasing in {precision.name}: times [{i}] and "
                f"[{i + 1}] are both {grid[i]} once rounded; space them further or raise "
                "the precision",
            )
    grid.flags.writeable = False  # shared by the scenes that have these times
    return grid


def _spaced(start: Number, stop: Number, count: int, precision: Precision) -> np.ndarray:
    """``{start, stop, count}`` in ``precision``: ``a + (b - a) k / (count - 1)``."""
    if count == 1:
        return precision.array([start])
    a, b = precision.number(start), precision.number(stop)
    if precision.kind == "double":
        return _double_grid(a, b, count)
    # Quad and MPFR cannot overflow here: (b - a) k is below 2e4007 (scene numbers are within
    # 1e±4000, counts within 1e7), far inside both ranges.
    n = precision.number(count - 1)
    return np.array([a + (b - a) * precision.number(k) / n for k in range(count)])


def _double_grid(a: float, b: float, count: int) -> np.ndarray:
    """``a + (b - a) k / (count - 1)`` in double, for k = 0 … count - 1, element by element
    (numpy does it in microseconds where a loop took ~3 µs a time).

    Where ``(b - a) k`` would overflow (``[-1e308, 1e308]``, or ``[0, 1e305]`` with 10⁵
    times) the same operations are done on ``a`` and ``b`` scaled by a power of two and the
    result scaled back: scaling by 2ᵐ is exact for normal numbers, so each time is the one the
    formula gives in a double without an exponent limit (the first is ``a`` itself: a tiny
    ``a`` scaled down would lose bits). Only a time that itself exceeds double's range
    overflows, and is refused by the caller.
    """
    n = float(count - 1)
    k = np.arange(count, dtype=np.float64)
    if math.isfinite(b - a) and abs(b - a) * n < _DOUBLE_MAX / 4:
        return a + (b - a) * k / n
    shift = (count - 1).bit_length() + 3
    sa, sb = math.ldexp(a, -shift), math.ldexp(b, -shift)
    with np.errstate(over="ignore"):
        grid = np.ldexp(sa + (sb - sa) * k / n, shift)
    grid[0] = a
    return grid


_DOUBLE_MAX = float(np.finfo(float).max)


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
        if count > MAX_OUTPUT_TIMES:
            raise SceneError(
                f"{where}.count",
                f"must be at most {MAX_OUTPUT_TIMES:.0e} output times, got {count}",
            )
        if count > 1 and exact_fraction(stop) <= exact_fraction(start):
            raise SceneError(where, f"stop ({stop}) must be greater than start ({start})")
        return None, (start, stop, count)
    if isinstance(spec, list | tuple):
        if not spec:
            raise SceneError(where, "must not be empty")
        if len(spec) > MAX_OUTPUT_TIMES:
            raise SceneError(where, f"must be at most {MAX_OUTPUT_TIMES:.0e} output times")
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
        text = expression_text(table["expression"], f"{where}.expression")
        direction = table.get("direction", "any")
        if not isinstance(direction, str) or direction not in _DIRECTIONS:
            raise SceneError(f"{where}.direction", f"must be 'any', 'up' or 'down': {direction!r}")
        return cls(name, text, _DIRECTIONS[direction])


#: At most this many user monitors per scene (each is one more compiled output).
MAX_MONITORS = 100


@dataclass(frozen=True)
class UserMonitor:
    """A monitored quantity written as an expression of the model's outputs
    (:mod:`.user_monitors` adds it to the model)."""

    name: str
    expression: str
    conserved: bool = True


def parse_monitors(table: Any) -> dict[str, UserMonitor]:
    """The scene's ``[monitors]`` table: ``NAME = {expression = "…", conserved = true}``."""
    if not isinstance(table, Mapping):
        raise SceneError("monitors", "must be a table of [monitors.NAME] tables")
    if len(table) > MAX_MONITORS:
        raise SceneError("monitors", f"at most {MAX_MONITORS} monitors, got {len(table)}")
    out = {}
    for name, spec in table.items():
        where = f"monitors.{name}"
        if problem := name_problem(name):
            raise SceneError(where, problem)
        if not isinstance(spec, Mapping):
            raise SceneError(where, f'must be a table {{expression = "…"}}, got {spec!r}')
        check_keys(spec, ["expression", "conserved"], where)
        if "expression" not in spec:
            raise SceneError(f"{where}.expression", "is required")
        text = expression_text(spec["expression"], f"{where}.expression")
        conserved = spec.get("conserved", True)
        if not isinstance(conserved, bool):
            raise SceneError(f"{where}.conserved", f"must be true or false, got {conserved!r}")
        out[name] = UserMonitor(name, text, conserved)
    return out


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
    monitors: Mapping[str, UserMonitor] = field(default_factory=dict)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Scene:
        """Validate a scene given as nested dictionaries (the TOML document's shape).

        The one input path of every verb: each number, of any kind
        :func:`~cayley_heyoka.core.precision.as_number` takes (text, int, float, numpy,
        Fraction, Decimal, real128, real, mpf), is checked as a scene number and then held in
        the run's precision (:meth:`~cayley_heyoka.core.precision.Precision.hold`), and the
        output times are computed there (:attr:`time_grid`), before anything else uses them.

        Raises
        ------
        SceneError
            Naming the field at fault (``output.times.stop``, ``initial.rates[0]``) and the
            rule, docs/scenes.md ("Numbers", "Limits").
        """
        from .families import FAMILIES, family_of

        if not isinstance(data, Mapping):
            raise SceneError("scene", f"must be a table, got {type(data).__name__}")
        family = family_of(data)
        spec = FAMILIES[family]
        check_keys(data, [*SCENE_TABLES, *spec.tables], "")
        title = data.get("title", "")
        if not isinstance(title, str):
            raise SceneError("title", f"must be a string, got {title!r}")
        with checked_numbers() as noted:
            integrator = IntegratorOptions.parse(data.get("integrator", {}))
            output = OutputOptions.parse(data.get("output", {}), spec.output_keys)
            events_table = data.get("events", {})
            if not isinstance(events_table, Mapping):
                raise SceneError("events", "must be a table of [events.NAME] tables")
            events = {n: UserEvent.parse(n, t) for n, t in events_table.items()}
            monitors = parse_monitors(data.get("monitors", {}))
            check_scene(monitors, events, spec.name, spec.events)
            model = spec.parse({k: data[k] for k in spec.tables if k in data})
        # Every number as written, in the run's precision, before any other use of it.
        precision = integrator.precision
        for where, value in noted:
            precision.hold(value, where)
        scene = cls(family, model, integrator, output, events, title, plain_copy(data), monitors)
        scene.time_grid  # noqa: B018 -- computed (and refused) here, kept for every user
        if spec.validate is not None:
            spec.validate(scene)
        return scene

    @functools.cached_property
    def time_grid(self) -> np.ndarray:
        """The output times in the run's precision (read-only), checked
        (:meth:`OutputOptions.time_grid`) when the scene is loaded; the engine, the progress
        bars, references and checks all take this one."""
        return self.output.time_grid(self.integrator.precision)

    def __getstate__(self) -> dict[str, Any]:
        # The checked grid is recomputed where the scene is unpickled (a sweep's worker), not
        # shipped with it: 10⁷ output times are 80 MB in double.
        state = dict(self.__dict__)
        state.pop("time_grid", None)
        state.pop("_source_bytes", None)
        return state

    def __repr__(self) -> str:
        """One line: the family, the title, the precision and tolerance, the output times."""
        options = self.integrator
        tolerance = "auto" if options.tolerance is None else options.tolerance
        title = self.title or "untitled"
        return (
            f"<Scene {self.family} {title!r}: {options.precision.name}, tolerance {tolerance}, "
            f"{self.output.count} output times>"
        )

    @classmethod
    def from_toml(cls, text: str) -> Scene:
        """Parse TOML text (floats kept as their decimal text)."""
        return cls.from_dict(parse_toml(text))

    def to_dict(self) -> dict[str, Any]:
        """The plain dictionary this scene was built from (a new copy each call)."""
        return pickle.loads(self._source_bytes)

    def derive(
        self,
        changes: Mapping[str, Any] | None = None,
        drop: Iterable[str] = (),
        options: Mapping[str, str] | None = None,
    ) -> Scene:
        """This scene with fields set or removed, validated as a scene written so would be.

        The one way the package makes a scene from another — a planner's pilot, a check's
        twin, an option that sets a field: the changes go through :meth:`from_dict`, the one
        input path, and a derived scene of the same structure shares its compiled code and
        built model (:mod:`.structures`).

        Parameters
        ----------
        changes
            ``{path: value}``, a path being dotted table names ending in the key set, e.g.
            ``{"integrator.max_steps": 1000}``; the value replaces what stands there (a
            table replaces the whole table).
        drop
            Paths removed, where present (``"events"``, ``"output.events"``).
        options
            ``{path: option}``: the option that set a path (``"--tolerance"``), which names a
            refusal of that field or of one inside it.

        Raises
        ------
        SceneError
            A field the derived scene refuses (:class:`~.errors.OptionError`, naming the
            option, where ``options`` names it).

        Examples
        --------
        >>> import cayley_heyoka as ch
        >>> scene = ch.load_scene("examples/free_body.toml")
        >>> scene.derive({"integrator.max_steps": 10}).integrator.max_steps
        10
        """
        try:
            return Scene.from_dict(edited(self.to_dict(), changes or {}, drop))
        except SceneError as exc:
            for path, option in (options or {}).items():
                if exc.field == path or exc.field.startswith(path + "."):
                    raise OptionError(option, exc.constraint) from None
            raise

    @functools.cached_property
    def _source_bytes(self) -> bytes:
        # Every result carries its scene: unpickling the plain source is ~3× faster than
        # copying it node by node.
        return pickle.dumps(self.source, protocol=pickle.HIGHEST_PROTOCOL)


def require_scene(scene: Any, name: str = "scene") -> Scene:
    """``scene`` if it is a :class:`Scene`; the public functions that take one (``run``,
    ``check_scene``, ``generate_reference``, ``propagate_ensemble``, ``plan``) call this
    first.

    A dictionary is not taken in its place: :meth:`Scene.from_dict` is the one way a scene
    is checked (every number in its precision, its time grid), once, and the checked scene is
    what results keep.

    Raises
    ------
    TypeError
        Naming ``name`` and how to build a scene.
    """
    if isinstance(scene, Scene):
        return scene
    how = (
        "Scene.from_dict(d)"
        if isinstance(scene, Mapping)
        else "Scene.from_dict, Scene.from_toml or load_scene(path)"
    )
    raise TypeError(f"{name} must be a Scene (build it with {how}), got {type(scene).__name__}")


#: The longest unit text ``output.units`` takes (units are labels, not documents).
MAX_UNIT_CHARS = 64


def _parse_units(table: Any) -> dict[str, str]:
    """``output.units``: the unit of ``time`` and of any output or monitor, as text that the
    result files and labelled views carry (CF ``units``); the names are checked against the
    model when it is built (:func:`check_units`)."""
    if not isinstance(table, Mapping):
        raise SceneError("output.units", f'must be a table of name = "unit", got {table!r}')
    for name, unit in table.items():
        where = f"output.units.{name}"
        if not isinstance(unit, str) or not unit.strip():
            raise SceneError(where, f'must be non-empty text (a unit such as "s"), got {unit!r}')
        if len(unit) > MAX_UNIT_CHARS or not unit.isprintable():
            raise SceneError(
                where, f"must be printable text of at most {MAX_UNIT_CHARS} characters"
            )
    return dict(table)


def check_units(scene: Scene, names: Iterable[str]) -> None:
    """Refuse an ``output.units`` entry that names neither ``time`` nor one of ``names`` (the
    model's outputs and monitors)."""
    known = ["time", *names]
    for name in scene.output.units:
        if name not in known:
            raise SceneError(
                f"output.units.{name}",
                f"is not an output or monitor of this scene (known: {', '.join(known)})",
            )


def load_scene(path: str | Path) -> Scene:
    """Read and validate a scene file.

    Raises
    ------
    SceneError
        With field ``scene`` if the file cannot be read (missing, a directory, unreadable,
        larger than :data:`MAX_SCENE_BYTES`, not UTF-8) or is not TOML; else the field at fault.
    """
    return Scene.from_dict(read_toml(path))


def read_toml(path: str | Path, what: str = "scene") -> dict[str, Any]:
    """The TOML document of a file, floats kept as their decimal text.

    Every way the file can fail to be a TOML document raises :class:`SceneError` with field
    ``what``: missing, a directory, unreadable, too large, not UTF-8, not TOML, too deep.
    """
    path = Path(path)
    try:
        if path.is_dir():
            raise SceneError(what, f"{str(path)!r} is a directory, not a TOML file")
        if path.exists() and not path.is_file():
            # Reading a FIFO waits for a writer, /dev/zero never ends: neither is a scene.
            raise SceneError(
                what, f"{str(path)!r} is not a regular file (a pipe, socket or device)"
            )
        size = path.stat().st_size
        if size > MAX_SCENE_BYTES:
            raise SceneError(what, f"{str(path)!r} has {size} bytes, more than {MAX_SCENE_BYTES}")
        raw = path.read_bytes()
    except FileNotFoundError:
        raise SceneError(what, f"no such file: {str(path)!r}") from None
    except OSError as exc:
        raise SceneError(what, f"cannot read {str(path)!r}: {exc.strerror}") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise SceneError(
            what, f"must be UTF-8 text (TOML); byte {exc.start} is {raw[exc.start]:#04x}"
        ) from None
    return parse_toml(text, what)


def parse_toml(text: str, what: str = "scene") -> dict[str, Any]:
    """TOML text as a document (floats as their decimal text), nested at most
    :data:`MAX_SCENE_DEPTH` deep; anything else raises :class:`SceneError` with field ``what``."""
    try:
        data = tomllib.loads(text, parse_float=str)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(what, f"not valid TOML: {exc}") from None
    except RecursionError:
        raise SceneError(what, f"nested deeper than {MAX_SCENE_DEPTH} tables or lists") from None
    stack: list[tuple[Any, int]] = [(data, 0)]
    while stack:
        node, depth = stack.pop()
        if depth > MAX_SCENE_DEPTH:
            raise SceneError(what, f"nested deeper than {MAX_SCENE_DEPTH} tables or lists")
        children = node.values() if isinstance(node, Mapping) else node
        stack += [(c, depth + 1) for c in children if isinstance(c, Mapping | list)]
    return data
