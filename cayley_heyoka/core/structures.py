"""Structure once, numbers many: a scene's model is its structure's, filled with its numbers.

A model is a structure — the expressions of the equations, outputs, monitors and events, the
terminal handlers, the compiled code's keys — plus numbers: the initial state and the values of
the runtime parameters. Scenes that differ only in numbers (the members of a sweep, a pilot of
the planner, a check's twin, the same scene run again) share the structure, so it is built
once: :func:`model_for` asks the scene's family for its structure's name
(``Family.structure``), builds the first scene of a structure in full, and fills that model
with each later scene's numbers (``Family.numbers``, :meth:`~.model.Model.with_numbers`),
building no expression and fingerprinting none. A family without the two hooks, or a scene
whose family names no structure, is built in full every time.

The second scene of every structure is also built in full and compared with its filled model
— the compiled code's key, the initial state and every parameter value, exactly — so that a
family's ``numbers`` that disagrees with its ``build`` is an error on first use, not a silent
difference.

Many scenes of one structure at once (a sweep's members, in double precision) need not be
scenes at all: :func:`table_for` asks the family for the numbers of all of them as arrays
(``Family.table``), computed from the values that differ (a member's swept fields) with
vectorised arithmetic that rounds as ``numbers`` does. Members whose values the table cannot
vouch for — a value double cannot hold, a body near the edge of a constraint — come back as
*suspects*, to be validated and built one by one, so that the table never accepts what a
scene would refuse; its rows are checked against two members built in full.
"""

from __future__ import annotations

import json
import math
import threading
from collections import OrderedDict
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .families import FAMILIES
from .model import Model, Numbers
from .precision import SMALLEST_NORMAL, exact_fraction

#: Structures kept (least recently used dropped first).
HELD = 64


@dataclass
class _Structure:
    model: Model
    #: Whether its numbers were checked against a full build (:func:`model_for`), and the
    #: swept fields whose tables were (:func:`table_for`): once each per structure.
    checked: bool = False
    tables: set[tuple] = field(default_factory=set)


_STRUCTURES: OrderedDict[tuple[str, str], _Structure] = OrderedDict()
_LOCK = threading.Lock()


#: What a family's ``structure`` writes in place of a number the model holds as a parameter.
MASK = "#"


def structure_text(scene: Any, tables: Mapping[str, Any]) -> str:
    """A structure's name as a family's ``structure`` returns it: ``tables`` (the scene's
    dictionary with the numbers the model holds as parameters or initial values replaced by
    :data:`MASK`) without the output times, which are not compiled, and with the precision,
    as canonical JSON."""
    data = dict(tables)
    output = dict(data.get("output", {}))
    output.pop("times", None)
    data["output"] = output
    data["precision"] = scene.integrator.precision.name
    return json.dumps(data, sort_keys=True, default=repr, ensure_ascii=True)


def structure_of(scene: Any) -> str | None:
    """The name of ``scene``'s structure within its family (None: the family names none)."""
    family = FAMILIES[scene.family]
    if family.structure is None or family.numbers is None:
        return None
    return family.structure(scene)


def model_for(scene: Any) -> Model:
    """``scene``'s model: its structure's (built once), with its numbers.

    Parameters
    ----------
    scene
        A validated scene.

    Raises
    ------
    SceneError
        As the family's ``build`` (a number its model cannot take is refused by ``numbers``).
    RuntimeError
        The family's ``numbers`` disagrees with its ``build`` (a fault of the family).
    """
    family = FAMILIES[scene.family]
    key = structure_of(scene)
    if key is None:
        return family.build(scene)
    slot = (scene.family, key)
    with _LOCK:
        held = _STRUCTURES.get(slot)
        if held is not None:
            _STRUCTURES.move_to_end(slot)
    if held is None:
        model = family.build(scene)
        model.code_key, model.integrator_parameters()  # once, for every scene of the structure
        with _LOCK:
            _STRUCTURES[slot] = _Structure(model)
            while len(_STRUCTURES) > HELD:
                _STRUCTURES.popitem(last=False)
        return model
    numbers: Numbers = family.numbers(scene)  # type: ignore[misc]
    model = held.model.with_numbers(numbers)
    if not held.checked:
        _check(family.name, key, model, family.build(scene))
        held.checked = True
    return model


def clear() -> None:
    """Forget the structures built."""
    with _LOCK:
        _STRUCTURES.clear()


def _check(family: str, key: str, filled: Model, built: Model) -> None:
    """``filled`` (a structure with a scene's numbers) is ``built`` (that scene in full)."""
    problems = []
    if filled.code_key != built.code_key:
        problems.append("its expressions differ")
    if built.pars.names != filled.pars.names:
        problems.append("its parameters differ")
    else:
        for name, a, b in zip(built.pars.names, built.pars.values, filled.pars.values, strict=True):
            if not _same(a, b):
                problems.append(f"parameter {name!r}: {b!r} for {a!r}")
    for name, a, b in zip(
        built.state_names, built.initial_state, filled.initial_state, strict=True
    ):
        if not _same(a, b):
            problems.append(f"initial {name}: {b!r} for {a!r}")
    if problems:
        raise RuntimeError(
            f"the {family} family's numbers disagree with its build for the structure "
            f"{key[:80]!r}…: {'; '.join(problems[:5])} (a fault of the family)"
        )


def _same(a: Any, b: Any) -> bool:
    if type(a) is not type(b):
        return False
    try:
        equal = bool(a == b)
    except (TypeError, ValueError):
        return False
    return equal or (a != a and b != b)  # NaN is NaN


# ---------------------------------------------------------------------- many at once
@dataclass(frozen=True)
class Table:
    """The numbers of many scenes of one structure (double precision), row by row.

    Attributes
    ----------
    initial
        ``(scenes, len(model.system))``: each scene's initial state.
    pars
        ``(scenes, len(model.pars))``: each scene's whole parameter vector.
    suspect
        ``(scenes,)``: rows the table does not vouch for (their other columns are
        meaningless): validate and build those scenes one by one.
    """

    initial: np.ndarray
    pars: np.ndarray
    suspect: np.ndarray


def doubles(values: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Scenes' numbers (``(scenes, fields)``: ints, floats, decimal text or fractions) as
    doubles, correctly rounded as a scene holds them; with whether each is that double exactly,
    and whether double holds it (finite, and zero or a normal number: :meth:`.Precision.hold`).
    """
    x, _, exact, held = double_doubles(values)
    return x, exact, held


def double_doubles(values: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """As :func:`doubles`, with the rest of each number: ``(x, low, exact, held)``, ``low``
    the double nearest to the number minus ``x`` (0 where ``x`` is the number), so that
    ``x + low`` is the number to about 2⁻¹⁰⁷ of it (:mod:`.ddouble`)."""
    try:
        x = np.array(values, dtype=np.float64, ndmin=2)
    except (OverflowError, ValueError, TypeError):
        x = None
    if x is not None and all(type(v) is float for row in values for v in row):
        exact = np.ones(x.shape, dtype=bool)  # a float is its own double
        low = np.zeros(x.shape)
    else:
        rows = [[_double(v) for v in row] for row in values]
        x = np.array([[d for d, _, _ in row] for row in rows], dtype=np.float64, ndmin=2)
        low = np.array([[r for _, r, _ in row] for row in rows], dtype=np.float64, ndmin=2)
        exact = np.array([[e for _, _, e in row] for row in rows], dtype=bool, ndmin=2)
    held = np.isfinite(x) & ((x == 0) | (np.abs(x) >= SMALLEST_NORMAL)) & ((x != 0) | exact)
    return x, low, exact, held


def _double(value: Any) -> tuple[float, float, bool]:
    try:
        f = exact_fraction(value)
    except (ValueError, OverflowError, TypeError):
        return float("nan"), 0.0, False
    try:
        x = f.numerator / f.denominator  # correctly rounded
    except OverflowError:
        return float("inf"), 0.0, False
    if not math.isfinite(x):
        return x, 0.0, False
    p, q = x.as_integer_ratio()
    rest = f.numerator * q - p * f.denominator  # (f − x) f.denominator q, in integers
    return x, (rest / (f.denominator * q) if rest else 0.0), not rest


def table_for(
    scene: Any,
    model: Model,
    fields: Sequence[tuple[str | int, ...]],
    values: Any,
    scene_of: Callable[[int], Any],
) -> Table | None:
    """The numbers of scenes that are ``scene`` with other ``values`` at ``fields``, as arrays.

    Parameters
    ----------
    scene, model
        One of the scenes (validated) and its model (:func:`model_for`).
    fields
        The scene paths that differ, e.g. ``("initial", "rates", 0)``.
    values
        ``(scenes, fields)``: each scene's numbers at ``fields``.
    scene_of
        The validated scene of row ``k`` (to check the table's rows against full builds):
        ``scene`` itself for its own row, whose ``model`` is then not built again.

    Returns
    -------
    Table or None
        None where the family offers no table for these fields (or not in this precision):
        build the scenes one by one.

    Raises
    ------
    RuntimeError
        The family's table disagrees with its ``numbers`` (a fault of the family): its first
        and last trusted rows against full builds, once per structure and swept fields, as
        :func:`model_for` checks a structure's numbers once.
    """
    family = FAMILIES[scene.family]
    if family.table is None or scene.integrator.precision.kind != "double":
        return None
    key = structure_of(scene)
    if key is None:
        return None
    x, low, exact, held = double_doubles(values)
    table = family.table(scene, model, tuple(fields), x, exact, low)
    if table is None:
        return None
    suspect = table.suspect | ~held.all(axis=1)
    table = Table(table.initial, table.pars, suspect)
    with _LOCK:
        built = _STRUCTURES.get((scene.family, key))
    swept = tuple(fields)
    if built is not None and swept in built.tables:
        return table
    trusted = np.flatnonzero(~suspect)
    for k in dict.fromkeys(trusted[[0, -1]].tolist() if len(trusted) else ()):
        of_k = scene_of(k)
        _check_row(family.name, model if of_k is scene else model_for(of_k), table, k)
    if built is not None and len(trusted):
        built.tables.add(swept)
    return table


def _check_row(family: str, built: Model, table: Table, k: int) -> None:
    """Row ``k`` of ``table`` holds the numbers of ``built`` (its scene built in full), bit for
    bit."""
    initial = np.asarray(built.initial_state, dtype=np.float64)
    pars = np.asarray(built.pars.values, dtype=np.float64)
    problems = [
        f"{what} {names[i]}: {got[i]!r} for {want[i]!r}"
        for what, names, got, want in (
            ("initial", built.state_names, table.initial[k], initial),
            ("parameter", built.pars.names, table.pars[k], pars),
        )
        for i in np.flatnonzero(got.view(np.int64) != want.view(np.int64))
    ]
    if problems:
        raise RuntimeError(
            f"the {family} family's table disagrees with its numbers for row {k}: "
            f"{'; '.join(problems[:5])} (a fault of the family)"
        )
