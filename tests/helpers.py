"""Shared test helpers: scene dictionaries and the precisions under test."""

from __future__ import annotations

import copy

from cayley_heyoka import Precision

PRECISIONS = {
    "double": Precision("double"),
    "quad": Precision("quad"),
    "real256": Precision("real", 256),
}


def with_value(doc: dict, path: tuple, value) -> dict:
    """A deep copy of ``doc`` with the value at ``path`` (keys and list indices) replaced."""
    doc = copy.deepcopy(doc)
    node = doc
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    return doc


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


#: The free body as TOML (Rodrigues attitude, t = 0 … 1, 3 outputs).
SMALL_BODY = """
[body]
inertia = [1.0, 1.5, 2.5]
[initial]
rates = [0.125, 0.25, 1.0]
rodrigues = [0.1, 0.2, -0.3]
[output]
times = { start = 0.0, stop = 1.0, count = 3 }
"""

#: A non-compact quad body with the potential ``{V}``: a long V takes LLVM minutes to compile.
SLOW_COMPILE = """
[body]
inertia = [1.0, 1.5, 2.5]
[initial]
rates = [0.125, 0.25, 1.0]
[forces.potential]
V = "{V}"
[integrator]
precision = "quad"
compact_mode = false
[output]
times = [0, 1]
"""

#: The orbit of the event tests: a = 1, e = 0.1, i = ω = 0.3, starting at pericentre.
ORBIT_ELEMENTS = {
    "a": "1",
    "e": "0.1",
    "inclination": "0.3",
    "node": "0",
    "argument_of_pericentre": "0.3",
    "mean_anomaly": "0",
}
