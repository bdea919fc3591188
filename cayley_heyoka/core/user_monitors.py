"""Monitors written in the scene: ``[monitors.NAME]`` tables.

A first integral the user knows — Kovalevskaya's K, a Jacobi constant, an energy written by hand
— is an expression of the model's outputs (the names ``cayley-heyoka info --variables`` lists),
of its named parameters (the moments ``A``, ``B``, ``C``, the orbit's ``mu``, …) and of ``t``::

    [monitors.K]                # Kovalevskaya's integral (A = B = 2C, Mg·x_G = C)
    expression = "(p*p - q*q - 2*(qx*qz - qw*qy))**2 + (2*p*q - 2*(qy*qz + qw*qx))**2"
    conserved = true            # the default: its drift is recorded and judged

It is evaluated on the output grid in the run's precision, exactly like the family's own
monitors (literals such as ``0.1`` are runtime parameters in that precision, integers exact),
appears in results, files and labelled views under its name and, when ``conserved``, in the
drifts that :meth:`Result.drift`, the regression helpers (:mod:`cayley_heyoka.testing`) and
sweeps record. The family builds its model without knowing of these; :func:`add_monitors`
adds them to the model it built.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import heyoka as hy

from .errors import SceneError
from .expressions import parse_expression
from .model import Model


def family_view(scene: Any) -> Any:
    """The scene as its family sees it: ``output.monitors`` without the user's monitors (the
    family offers its own; :func:`add_monitors` adds the others)."""
    wanted = scene.output.monitors
    if not scene.monitors or wanted is None:
        return scene
    own = tuple(m for m in wanted if m not in scene.monitors)
    return dataclasses.replace(scene, output=dataclasses.replace(scene.output, monitors=own))


def add_monitors(model: Model, scene: Any) -> Model:
    """``model`` with the scene's user monitors, parsed over its outputs and parameters (their
    names are checked first, with the model's: :func:`.names.check_model`)."""
    if not scene.monitors:
        return model
    wanted = scene.output.monitors
    symbols: dict[str, Any] = {
        name: hy.par[i] for i, name in enumerate(model.pars.names) if name.isidentifier()
    }
    symbols.update(model.outputs)
    for name, monitor in scene.monitors.items():
        where = f"monitors.{name}"
        if wanted is not None and name not in wanted:
            raise SceneError(where, "is defined but not listed in output.monitors")
        expr = parse_expression(monitor.expression, symbols, model.pars, f"{where}.expression")
        model.monitors[name] = expr
        if monitor.conserved:
            model.conserved = (*model.conserved, name)
    return model
