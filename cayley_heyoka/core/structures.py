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
"""

from __future__ import annotations

import json
import threading
from collections import OrderedDict
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from .families import FAMILIES
from .model import Model, Numbers

#: Structures kept (least recently used dropped first).
HELD = 64


@dataclass
class _Structure:
    model: Model
    checked: bool = False


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
