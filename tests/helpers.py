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


def with_values(doc: dict, changes: dict) -> dict:
    """A deep copy of ``doc`` with each ``path: value`` of ``changes`` set (:func:`with_value`)."""
    for path, value in changes.items():
        doc = with_value(doc, path, value)
    return doc


def assert_same_model(filled, built) -> None:
    """``filled`` (a structure with a scene's numbers, cayley_heyoka.core.structures) is the
    model ``built`` in full from that scene: code, parameters (values and their types), initial
    state, and what the engine reads beside them."""
    assert filled.code_key == built.code_key
    assert filled.pars.names == built.pars.names
    for name, a, b in zip(built.pars.names, built.pars.values, filled.pars.values, strict=True):
        assert type(a) is type(b) and (a == b or (a != a and b != b)), name
    assert len(filled.initial_state) == len(built.initial_state)
    for a, b in zip(built.initial_state, filled.initial_state, strict=True):
        assert type(a) is type(b) and a == b
    assert filled.compact == built.compact and filled.conserved == built.conserved
    assert filled.variant == built.variant and filled.initial_fields == built.initial_fields
    assert [t.counter for t in filled.terminal] == [t.counter for t in built.terminal]


#: An anharmonic oscillator H = H₁ + H₂ in Hamilton's varying elements of the harmonic H₁
#: (its flow given), the ``[hamiltonian]`` table.
ANHARMONIC_SPLIT = {
    "H1": "(varpi1**2 + eta1**2)/2",
    "H2": "0.05*eta1**4",
    "formulation": "elements",
    "flow": {"eta1": "chi1*cos(t) + lambda1*sin(t)", "varpi1": "lambda1*cos(t) - chi1*sin(t)"},
}


def assert_second_scene_filled(base: dict, changes: dict) -> None:
    """A second scene of ``base``'s structure (``base`` with ``changes``, numbers only) takes the
    first scene's structure, filled with its own numbers: the model its family builds in full,
    the same expressions; and the numbers did change."""
    from cayley_heyoka import Scene
    from cayley_heyoka.core import structures
    from cayley_heyoka.core.families import FAMILIES

    structures.clear()
    first = Scene.from_dict(copy.deepcopy(base))
    second = Scene.from_dict(with_values(base, changes))
    assert structures.structure_of(first) == structures.structure_of(second) is not None
    built_first = structures.model_for(first)
    filled = structures.model_for(second)  # checked against its full build by model_for, once
    built = FAMILIES[second.family].build(second)
    assert_same_model(filled, built)
    third = structures.model_for(second)  # now filled without a full build
    assert_same_model(third, filled)
    assert third.system is built_first.system  # the expressions are shared, not rebuilt
    # A filled model that kept the first scene's numbers would pass the above only if the
    # changes changed nothing.
    assert list(built.initial_state) != list(built_first.initial_state) or (
        built.pars.values != built_first.pars.values
    )


def runs_shared_and_alone(docs: list[dict]) -> tuple[list, list]:
    """The scenes ``docs`` run one after the other through their shared structure
    (cayley_heyoka.core.structures), and each alone (the structures forgotten before each)."""
    from cayley_heyoka import Scene, run
    from cayley_heyoka.core import structures

    structures.clear()
    shared = [run(Scene.from_dict(copy.deepcopy(d))) for d in docs]
    alone = []
    for d in docs:
        structures.clear()
        alone.append(run(Scene.from_dict(copy.deepcopy(d))))
    return shared, alone


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
