"""The names results are kept under, in every layout: one registry, one holder per name.

A run's numbers are found by name in several layouts: the result file (netCDF-4 in HDF5,
:meth:`.result.Result.fill`), the reference file (a result file with a ``certificate`` group),
the sweep file (:mod:`cayley_heyoka.workflows.sweep_result`) and the labelled views
(:mod:`.labelled`: ``to_xarray``, ``to_pandas``). Some names belong to the layouts themselves —
the time axis, the dimensions of vectors, the group of events — and the rest are the scene's:
its family's outputs, monitors and events, and the user's ``[monitors.NAME]`` and
``[events.NAME]``. (A check file holds none of the scene's names at its root: ``rows/NN`` and
``series/<name>``, the series named by the checks.)

This module keeps the layouts' own names (:data:`RESULT_FILE`, :data:`SWEEP_FILE`,
:data:`SCENE_TABLES`), the rule that flattens a vector into the columns of a table
(:func:`columns`), the rule a name must follow to be written at all (:func:`name_problem`), and
the checks that give each name one holder: :func:`check_scene` when a scene is validated (the
user's names against the layouts and the family's events) and :func:`check_model` when its
model is built (every output and monitor, the user's among them, and each column of a
vector). A collision is refused with the field at fault and what already holds the name,
before any work.

It imports nothing heavier than the standard library: readers of files (``info``) use it
without heyoka.
"""

from __future__ import annotations

import itertools
import re
import unicodedata
from collections.abc import Iterable
from typing import Any

from .errors import SceneError

#: Tables every scene may have, whatever its family: no family may own one.
SCENE_TABLES = ("title", "integrator", "output", "events", "monitors")

#: The result file's (and a reference file's) own names beside the outputs and monitors, each
#: with what it is. The labelled views use the same: ``time`` is the views' dimension and the
#: pandas table's index.
RESULT_FILE = {
    "time": "the result file's time axis (the dimension time, and the index of to_pandas())",
    "component": "the result file's dimension of the components of 3-vectors",
    "events": "the result file's group of events",
    "certificate": "the certificate group of a reference file",
}
#: ``component_N``: the dimension of an N-vector's components (N ≠ 3), in the file and views.
_COMPONENT_N = re.compile(r"component_[0-9]+")

#: The sweep file's own names (and its xarray view's), which no swept parameter may take.
SWEEP_FILE = (
    "time", "member", "monitor", "variable", "event", "drift", "final_state", "status",
    "message", "steps", "events",
)  # fmt: skip

#: Labels of the components of three-vectors (space axes), as in the files and the views.
COMPONENTS = ("x", "y", "z")

#: The longest name, in bytes of UTF-8: netCDF's ``NC_MAX_NAME`` (a netCDF reader refuses a
#: file whose variable has a longer name).
MAX_NAME_BYTES = 256


def component_dim(size: int) -> str:
    """The dimension of a ``size``-vector's components: ``component`` for three (labels
    :data:`COMPONENTS`), ``component_N`` otherwise."""
    return "component" if size == len(COMPONENTS) else f"component_{size}"


def columns(name: str, shape: tuple[int, ...] = ()) -> list[str]:
    """The columns of a flat table (``to_pandas()``) that hold ``name``, whose value at one
    time has ``shape``: ``[name]`` for a number; ``NAME_x``, ``NAME_y``, ``NAME_z`` for a
    3-vector; ``NAME_0`` … for another length; ``NAME_x_0`` … for a matrix (each axis of
    three labelled by :data:`COMPONENTS`, the others by index)."""
    if not shape:
        return [name]
    axes = [COMPONENTS if n == len(COMPONENTS) else [str(i) for i in range(n)] for n in shape]
    return ["_".join((name, *labels)) for labels in itertools.product(*axes)]


def name_problem(name: Any) -> str | None:
    """Why ``name`` cannot name a result in every layout (None when it can).

    A name is an identifier (letters, digits and ``_``, not starting with a digit), as
    Python, netCDF and the expression grammar read it; not starting with ``_`` (netCDF and
    xarray keep those); in Unicode's NFKC form (Python reads ``ｐ`` as ``p``, so
    ``ds.ｐ`` would be another variable than ``ds["ｐ"]``); at most :data:`MAX_NAME_BYTES`
    bytes. So no ``/`` (an HDF5 path), no ``.``, space or control character. Names are
    case-sensitive, as every layout is.
    """
    if not isinstance(name, str) or not name.isidentifier():
        return "a name must be an identifier (letters, digits and _, not starting with a digit)"
    if name.startswith("_"):
        return "a name must not start with _ (netCDF and xarray keep such names)"
    normal = unicodedata.normalize("NFKC", name)
    if normal != name:
        return f"a name must be in Unicode's NFKC form: Python reads this one as {normal!r}"
    size = len(name.encode())
    if size > MAX_NAME_BYTES:
        return f"a name must be at most {MAX_NAME_BYTES} bytes long (netCDF's limit), got {size}"
    return None


def layout_holder(name: str) -> str | None:
    """What of the result file's layout ``name`` is (None if it is free for a result)."""
    if name in RESULT_FILE:
        return RESULT_FILE[name]
    if _COMPONENT_N.fullmatch(name):
        return f"the result file's dimension of the components of {name[10:]}-vectors"
    return None


class Holders:
    """The names of one scene's results, each with what holds it.

    :meth:`claim` takes a name (and, for a vector, its columns) for one holder, or refuses it
    with the field at fault and what holds it already.
    """

    def __init__(self) -> None:
        self._held: dict[str, str] = {}

    def claim(self, name: str, where: str, what: str, shape: tuple[int, ...] = ()) -> None:
        """Give ``name`` (an output or monitor whose value at one time has ``shape``) and its
        columns to ``what``; ``where`` is the field blamed for a collision."""
        if problem := name_problem(name):
            raise SceneError(where, f"{name!r}: {problem}")
        taken = [name, *columns(name, shape)] if shape else [name]
        for label in taken:
            holder = layout_holder(label) or self._held.get(label)
            if holder is not None:
                mine = "" if label == name else f" (its column {label} in to_pandas())"
                raise SceneError(where, f"{name!r}{mine} is already {holder}; name it otherwise")
        self._held[name] = what
        for label in taken[1:]:
            self._held[label] = f"a column of {what} in to_pandas()"


def check_scene(
    monitors: Iterable[str], events: Iterable[str], family: str, family_events: Iterable[str]
) -> None:
    """Refuse a user monitor or event whose name no layout can hold or that is taken, when the
    scene is validated (the names of the model come later: :func:`check_model`).

    Parameters
    ----------
    monitors, events
        The names of the scene's ``[monitors.NAME]`` and ``[events.NAME]`` tables.
    family, family_events
        The family's name and the events it offers (``Family.events``): a family picks its
        own event by name, so a user event of that name would be silently replaced.

    Raises
    ------
    SceneError
        ``monitors.NAME`` for a name that is not a name (:func:`name_problem`) or one of the
        layouts' own (:func:`layout_holder`); ``events.NAME`` for a name that is not a name
        or is one of the family's events.
    """
    for name in monitors:
        where = f"monitors.{name}"
        if problem := name_problem(name):
            raise SceneError(where, problem)
        if holder := layout_holder(name):
            raise SceneError(where, f"{name!r} is {holder}; name the monitor otherwise")
    own = tuple(family_events)
    for name in events:
        where = f"events.{name}"
        if problem := name_problem(name):
            raise SceneError(where, problem)
        if name in own:
            raise SceneError(
                where,
                f"{name!r} is one of the {family} family's own events ({', '.join(own)}); "
                "name the event otherwise",
            )


def check_model(model: Any, user_monitors: Iterable[str], where: str) -> None:
    """Refuse a model whose outputs and monitors would not each have a name of their own in
    every layout, before any work.

    Parameters
    ----------
    model
        The family's :class:`~.model.Model`, before the user's monitors are added.
    user_monitors
        The names of the scene's ``[monitors.NAME]`` (each a number at one time).
    where
        The field blamed for a collision among the family's own names (its key table).

    Raises
    ------
    SceneError
        ``monitors.NAME`` for a user monitor that takes an output's or monitor's name, or a
        column of a vector's (``momentum_space_x``); ``where`` for the family's own.
    """
    held = Holders()
    for name in model.outputs:
        held.claim(name, where, f"the built-in output {name}")
    for name, expr in model.monitors.items():
        shape = (len(expr),) if isinstance(expr, list) else ()
        held.claim(name, where, f"the built-in monitor {name}", shape)
    for name in user_monitors:
        held.claim(name, f"monitors.{name}", f"the user monitor {name}")
