"""A model family that lives outside cayley_heyoka, as a third party would write one: the
harmonic oscillator ẍ = −ω²x (``[oscillator]``), registered through the entry-point group
``cayley_heyoka.families`` in tests/test_family_plugin.py."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import heyoka as hy

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
