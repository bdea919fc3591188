"""What every Hamiltonian model offers beside its equations: the monitors asked for, the
principal function's switch and the user's events (the projectile's model and the
predominant-mass system's share them)."""

from __future__ import annotations

from ..core.errors import SceneError
from ..core.expressions import parse_expression
from ..core.model import EventSpec, ParTable
from ..core.scene import Scene


def select_monitors(scene: Scene, monitors: dict, conserved: tuple) -> tuple[dict, tuple]:
    """The monitors the scene's ``output.monitors`` asks for (all when it names none)."""
    wanted = scene.output.monitors
    if wanted is None:
        return monitors, conserved
    unknown = [m for m in wanted if m not in monitors]
    if unknown:
        raise SceneError(
            "output.monitors",
            f"{unknown[0]!r} is not available here; available: {list(monitors)}",
        )
    chosen = {k: v for k, v in monitors.items() if k in wanted}
    return chosen, tuple(k for k in conserved if k in wanted)


def wants_principal_function(scene: Scene) -> bool:
    """Whether the scene asks for Hamilton's principal function S as an output."""
    value = scene.output.options.get("principal_function", False)
    if not isinstance(value, bool):
        raise SceneError("output.principal_function", f"must be true or false, got {value!r}")
    return value


def user_events(scene: Scene, outputs: dict, pars: ParTable) -> list[EventSpec]:
    """The scene's events, as expressions of the outputs, each listed in ``output.events``."""
    events = []
    for name in scene.output.events:
        if name not in scene.events:
            known = list(scene.events)
            raise SceneError("output.events", f"unknown event {name!r}; known: {known}")
        ev = scene.events[name]
        expr = parse_expression(ev.expression, outputs, pars, f"events.{name}.expression")
        events.append(EventSpec(name, name, expr, ev.direction))
    for name in scene.events:
        if name not in scene.output.events:
            raise SceneError(f"events.{name}", "is defined but not listed in output.events")
    return events
