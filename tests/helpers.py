"""Shared test helpers: scene dictionaries and the precisions under test."""

from __future__ import annotations

import copy

from cayley_heyoka import Precision

PRECISIONS = {
    "double": Precision("double"),
    "quad": Precision("quad"),
    "real256": Precision("real", 256),
}


def free_body(**tables) -> dict:
    """A torque-free body near the major axis (Cayley 1843 reference case 1 inertia)."""
    scene = {
        "body": {"inertia": ["1", "1.5", "2.5"]},
        "initial": {"rates": ["0.125", "0.25", "1"], "rodrigues": ["0.1", "0.2", "-0.3"]},
        "output": {"times": {"start": "0", "stop": "10", "count": 11}},
    }
    for key, value in tables.items():
        if isinstance(value, dict) and isinstance(scene.get(key), dict):
            scene[key] = {**scene[key], **value}
        else:
            scene[key] = value
    return copy.deepcopy(scene)
