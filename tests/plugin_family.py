"""A model family that lives outside cayley_heyoka, as a third party would write one: the
harmonic oscillator ẍ = −ω²x (``[oscillator]``), registered through the entry-point group
``cayley_heyoka.families`` in tests/test_family_plugin.py; and families a careless third party
would write (:data:`CLAIMS_BODY`, :data:`FAULTY`, …), for tests/hostile/test_names.py.

:func:`install` makes the registry find entry points as a new process with those packages
installed would.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from fractions import Fraction
from importlib import metadata
from typing import Any

import heyoka as hy

from cayley_heyoka.core import families
from cayley_heyoka.core.families import Family
from cayley_heyoka.core.model import Model, ParTable
from cayley_heyoka.core.precision import Number
from cayley_heyoka.core.scene import Scene, check_keys, number

KEYS = ("omega", "x0", "v0")


@dataclass(frozen=True)
class Oscillator:
    omega: Number
    x0: Number
    v0: Number

    @classmethod
    def parse(cls, tables: Mapping[str, Any]) -> Oscillator:
        table = tables.get("oscillator", {})
        check_keys(table, KEYS, "oscillator")
        return cls(*(number(table.get(k, 0), f"oscillator.{k}") for k in KEYS))


def build(scene: Scene) -> Model:
    o = scene.model
    prec = scene.integrator.precision
    pars = ParTable(prec)
    w = pars.add("omega", o.omega)
    x, v = hy.make_vars("x", "v")
    half = pars.constant(Fraction(1, 2))
    return Model(
        "oscillator",
        [(x, v), (v, -(w * w) * x)],
        [prec.number(o.x0), prec.number(o.v0)],
        pars,
        {"x": x, "v": v},
        {"energy": half * v * v + half * (w * w) * (x * x)},
        ("energy",),
    )


FAMILY = Family("oscillator", "oscillator", ("oscillator",), Oscillator.parse, build)


def install(monkeypatch: Any, *pairs: tuple[str, str], **points: str) -> None:
    """The registry as a new process finds it with the entry points ``(name, "module:attr")``
    and ``name = "module:attr"`` installed (none: no other package's family); restored after
    the test."""
    real = metadata.entry_points
    found = metadata.EntryPoints(
        metadata.EntryPoint(name, value, families.ENTRY_POINTS)
        for name, value in [*pairs, *points.items()]
    )

    def entry_points(**select: Any) -> Any:
        if select.get("group") == families.ENTRY_POINTS:
            return found
        return real(**select)

    monkeypatch.setattr(metadata, "entry_points", entry_points)
    monkeypatch.setattr(families.FAMILIES, "_entries", None)


def _raises(*args: Any) -> Any:
    raise ZeroDivisionError("division by zero")


#: A family that takes the rigid body's key table ``[body]`` for its own.
CLAIMS_BODY = replace(FAMILY, name="bodies", key_table="body", tables=("body",))
#: A family whose own table is fine but which also claims the generic ``[output]``.
CLAIMS_OUTPUT = replace(FAMILY, name="outputs", tables=("oscillator", "output"))
#: A family whose key table is the rotation family's ``[initial]`` (every rigid-body scene
#: has one).
CLAIMS_INITIAL = replace(FAMILY, name="initials", key_table="initial", tables=("initial",))
#: The oscillator again, as a second package would register it under the same name.
FAMILY_AGAIN = replace(FAMILY)
#: Two families of two packages with one key table, ``[oscillator]``.
TWIN_A = replace(FAMILY, name="twin_a")
TWIN_B = replace(FAMILY, name="twin_b")
#: A family whose parse raises what a bug raises (not a SceneError).
FAULTY_PARSE = replace(FAMILY, name="faulty", parse=_raises)
#: A family whose build raises what a bug raises.
FAULTY_BUILD = replace(FAMILY, name="faulty", build=_raises)
#: A family whose validate raises what a bug raises.
FAULTY_VALIDATE = replace(FAMILY, name="faulty", validate=_raises)
#: A family whose description of its variables raises (``info --variables``, saving).
FAULTY_VARIABLES = replace(FAMILY, name="faulty", variables=_raises)
#: A family whose consistency check raises (``cayley-heyoka check``).
FAULTY_CHECK = replace(FAMILY, name="faulty", consistency_check=_raises)
#: A family whose built-in output takes the result file's ``time``.
OUTPUT_TIME = replace(FAMILY, name="timed", build=lambda scene: _renamed(build(scene)))


def _renamed(model: Model) -> Model:
    model.outputs = {"time": model.outputs["x"], "v": model.outputs["v"]}
    return model
