"""Structure once, numbers many for the Hamiltonian family: a scene of a structure already built
(:func:`cayley_heyoka.core.structures.model_for`) takes that model with its own numbers, and
that model is the one a full build of the scene gives — in both formulations, for the
projectile, a user H or split, and the predominant mass."""

from __future__ import annotations

import copy

import numpy as np
import pytest
from helpers import (
    ANHARMONIC_SPLIT,
    assert_second_scene_filled,
    runs_shared_and_alone,
    with_value,
)

import cayley_heyoka as ch
from cayley_heyoka.core import structures
from cayley_heyoka.core.families import FAMILIES
from cayley_heyoka.core.model import Numbers
from cayley_heyoka.core.structures import model_for, structure_of

TIMES = {"start": "0", "stop": "2", "count": 3}
PROJECTILE = {
    "hamiltonian": {"model": "projectile", "g": "0.5", "mu": "1.3", "nu": "0.7"},
    "initial": {"eta": ["-1.1", "0.6", "0.25"], "varpi": ["-0.4", "1.9", "0.8"]},
    "output": {"times": TIMES, "principal_function": True},
}
ANHARMONIC = {
    "hamiltonian": copy.deepcopy(ANHARMONIC_SPLIT),
    "initial": {"eta": ["0.8"], "varpi": ["-0.3"]},
    "output": {"times": TIMES},
}
#: A user H with literals in its text, an event and a monitor of their own.
USER = {
    "hamiltonian": {"H": "(varpi1**2 + varpi2**2)/2 + 0.3*eta1**2 + 0.7*eta2**2 + 0.1*eta1*eta2"},
    "initial": {"eta": ["0.5", "-0.2"], "varpi": ["0.1", "0.4"]},
    "events": {"cross": {"expression": "eta1 - 0.125", "direction": "any"}},
    "monitors": {"twice": {"expression": "2.5*varpi1*varpi1", "conserved": False}},
    "output": {"times": TIMES, "events": ["cross"], "principal_function": True},
}
INNER = {
    "a": "1",
    "e": "0.05",
    "inclination": "0.05",
    "node": "0.3",
    "argument_of_pericentre": "1.1",
    "mean_anomaly": "0.4",
}
OUTER = {
    "a": "1.8",
    "e": "0.08",
    "inclination": "0.08",
    "node": "2",
    "argument_of_pericentre": "4",
    "mean_anomaly": "2.5",
}


def planets(formulation: str, bodies=None, **output) -> dict:
    """Two planets about a predominant mass (the bundled example's elements)."""
    if bodies is None:
        bodies = [{"mass": "0.001", "elements": INNER}, {"mass": "0.0003", "elements": OUTER}]
    return {
        "hamiltonian": {
            "model": "predominant_mass",
            "G": "1",
            "central_mass": "1",
            "formulation": formulation,
            "bodies": copy.deepcopy(bodies),
        },
        "output": {"times": TIMES, **output},
    }


CARTESIAN = [
    {"mass": "0.002", "position": ["1", "0", "0.1"], "velocity": ["0", "1", "0"]},
    {"mass": "0.001", "position": ["0", "-2", "0"], "velocity": ["0.7", "0", "0.05"]},
]
FIVE = [
    {"mass": f"0.000{k + 1}", "position": [str(1 + k), "0", "0"], "velocity": ["0", "1", "0"]}
    for k in range(5)
]


def _quad(doc: dict) -> dict:
    return {**copy.deepcopy(doc), "integrator": {"precision": "quad"}}


#: (structure, the fields whose numbers the second scene changes and their new values)
CASES = {
    "projectile, canonical, S": (
        PROJECTILE,
        {
            ("hamiltonian", "g"): "9.80665",
            ("hamiltonian", "mu"): "0.05",
            ("initial", "eta"): ["1", "2", "0"],
            ("initial", "varpi"): ["10", "-3", "25"],
        },
    ),
    "projectile, elements, S, quad": (
        _quad(with_value(PROJECTILE, ("hamiltonian", "formulation"), "elements")),
        {
            ("hamiltonian", "g"): "2",
            ("hamiltonian", "nu"): "0.02",
            ("initial", "eta"): ["0", "0", "0"],
        },
    ),
    "user H, events and monitors": (
        USER,
        {("initial", "eta"): ["-0.4", "0.9"], ("output", "times"): ["0.5", "3"]},
    ),
    "user H, quad": (_quad(USER), {("initial", "varpi"): ["0", "0"]}),
    "user split, elements": (ANHARMONIC, {("initial", "varpi"): ["0.6"]}),
    "user split, canonical, quad": (
        _quad(with_value(ANHARMONIC, ("hamiltonian", "formulation"), "canonical")),
        {("initial", "eta"): ["-1.5"]},
    ),
    "predominant mass, canonical, S": (
        planets("canonical", principal_function=True),
        {
            ("hamiltonian", "G"): "1.5",
            ("hamiltonian", "central_mass"): "2",
            ("hamiltonian", "bodies", 0, "mass"): "0.004",
            ("hamiltonian", "bodies", 1, "elements", "e"): "0.3",
        },
    ),
    "predominant mass, elements, S": (
        planets("elements", principal_function=True),
        {
            ("hamiltonian", "bodies", 1, "mass"): "0.0001",
            ("hamiltonian", "bodies", 0, "elements", "inclination"): "1.2",
            # τ is absolute: the start time is one of the elements' numbers.
            ("output", "times"): {"start": "3.5", "stop": "5", "count": 2},
        },
    ),
    "predominant mass, elements, quad": (
        _quad(planets("elements")),
        {("hamiltonian", "bodies", 0, "elements", "a"): "0.7"},
    ),
    "predominant mass, one body, elements": (
        planets("elements", [{"mass": "0.001", "elements": INNER}]),
        {("hamiltonian", "bodies", 0, "elements", "mean_anomaly"): "-2"},
    ),
    "predominant mass, by positions, an event, one monitor": (
        {
            **planets("canonical", CARTESIAN, events=["near"], monitors=["energy"]),
            "events": {"near": {"expression": "x1 - 0.5", "direction": "down"}},
        },
        {
            ("hamiltonian", "bodies", 0, "velocity"): ["0.1", "0.9", "0"],
            ("hamiltonian", "bodies", 1, "position"): ["0", "-2.5", "0.3"],
        },
    ),
    "predominant mass, by positions, elements": (
        planets("elements", CARTESIAN),
        {("hamiltonian", "bodies", 1, "velocity"): ["0.6", "0", "0.1"]},
    ),
    "predominant mass, five bodies (compact)": (
        planets("canonical", FIVE),
        {("hamiltonian", "bodies", 4, "mass"): "0.01"},
    ),
}


@pytest.mark.parametrize("case", CASES)
def test_a_second_scene_of_a_structure_is_filled_with_its_own_numbers(case):
    assert_second_scene_filled(*CASES[case])


#: Scenes whose structures must differ from the case's first scene: what is not masked.
OTHERS = {
    "another literal in H": with_value(
        USER, ("hamiltonian", "H"), USER["hamiltonian"]["H"].replace("0.1*", "0.2*")
    ),
    "another degree of freedom": with_value(
        with_value(USER, ("initial", "eta"), ["0.5", "-0.2", "0"]),
        ("initial", "varpi"),
        ["0.1", "0.4", "0"],
    ),
    "another event literal": with_value(USER, ("events", "cross", "expression"), "eta1 - 0.25"),
    "another monitor literal": with_value(
        USER, ("monitors", "twice", "expression"), "2.25*varpi1*varpi1"
    ),
    "without S": with_value(USER, ("output", "principal_function"), False),
    "in quad": _quad(USER),
}


@pytest.mark.parametrize("other", OTHERS)
def test_what_the_build_compiles_names_another_structure(other):
    a, b = ch.Scene.from_dict(copy.deepcopy(USER)), ch.Scene.from_dict(OTHERS[other])
    assert structure_of(a) != structure_of(b)


def test_the_predominant_mass_keeps_its_shape_in_the_structure():
    base = planets("canonical", CARTESIAN)
    shapes = [
        planets("elements", CARTESIAN),
        planets("canonical", CARTESIAN[:1]),
        planets("canonical", [CARTESIAN[0], {"mass": "0.001", "elements": OUTER}]),
        planets("canonical", CARTESIAN, principal_function=True),
        _quad(base),
    ]
    keys = {structure_of(ch.Scene.from_dict(d)) for d in [base, *shapes]}
    assert len(keys) == 1 + len(shapes)


def test_an_elements_scene_starting_elsewhere_is_refused_by_its_numbers():
    structures.clear()
    model_for(ch.Scene.from_dict(copy.deepcopy(ANHARMONIC)))
    later = ch.Scene.from_dict(with_value(ANHARMONIC, ("output", "times"), ["1", "2"]))
    with pytest.raises(ch.SceneError, match="starts at t = 0") as info:
        model_for(later)
    assert info.value.field == "output.times"


def test_bodies_the_precision_cannot_tell_apart_are_refused_by_their_numbers():
    structures.clear()
    base = planets("canonical", CARTESIAN)
    model_for(ch.Scene.from_dict(copy.deepcopy(base)))
    close = with_value(
        base, ("hamiltonian", "bodies", 1, "position"), ["1.00000000000000001", "0", "0.1"]
    )
    with pytest.raises(ch.SceneError, match="rounding of their positions") as info:
        model_for(ch.Scene.from_dict(close))
    assert info.value.field == "hamiltonian.bodies[1]"
    # In quad the same bodies are apart.
    structures.clear()
    model_for(ch.Scene.from_dict(_quad(close)))


def test_a_build_whose_numbers_name_other_parameters_is_an_error(monkeypatch):
    import cayley_heyoka.hamilton.predominant_mass.model as pm

    honest = pm.numbers

    def extra(scene):
        given = honest(scene)
        return Numbers(given.initial_state, {**given.values, "predominant_mass.spare": "1"})

    monkeypatch.setattr(pm, "numbers", extra)
    with pytest.raises(RuntimeError, match="spare"):
        FAMILIES["hamiltonian"].build(ch.Scene.from_dict(planets("canonical")))


#: (base, the field each member changes, the members' values)
MEMBERS = {
    "projectile with an event": (
        {
            **with_value(PROJECTILE, ("output", "times"), {"start": "0", "stop": "6", "count": 4}),
            "events": {"top": {"expression": "varpi3", "direction": "down"}},
            "output": {
                "times": {"start": "0", "stop": "6", "count": 4},
                "events": ["top"],
                "principal_function": True,
            },
        },
        ("hamiltonian", "g"),
        ["0.5", "2", "9.80665"],
        ["eta3", "S"],
        "top",
    ),
    "user split, elements, an event": (
        {
            **ANHARMONIC,
            "events": {"turn": {"expression": "varpi1", "direction": "any"}},
            "output": {"times": {"start": "0", "stop": "12", "count": 5}, "events": ["turn"]},
        },
        ("initial", "eta"),
        [["0.8"], ["1.4"], ["-0.3"]],
        ["chi1", "eta1"],
        "turn",
    ),
    "predominant mass, elements, an event": (
        {
            **planets("elements", principal_function=True, events=["node"]),
            "events": {"node": {"expression": "z1", "direction": "up"}},
            "output": {
                "times": {"start": "0", "stop": "20", "count": 5},
                "principal_function": True,
                "events": ["node"],
            },
        },
        ("hamiltonian", "bodies", 0, "mass"),
        ["0.001", "0.003", "0.0002"],
        ["x1", "mu2", "S"],
        "node",
    ),
}


@pytest.mark.parametrize("case", MEMBERS)
def test_members_of_one_structure_run_as_their_own_scenes(case):
    base, path, values, names, event = MEMBERS[case]
    docs = [with_value(base, path, v) for v in values]
    shared, alone = runs_shared_and_alone(docs)
    for a, b in zip(shared, alone, strict=True):
        assert a.counters == b.counters
        for name in names:
            np.testing.assert_array_equal(a[name], b[name])
        for name in a.monitors:
            np.testing.assert_array_equal(a.monitors[name], b.monitors[name])
        assert len(a.events[event].time) > 0
        np.testing.assert_array_equal(a.events[event].time, b.events[event].time)
    # The members differ: each ran on its own numbers.
    assert not np.array_equal(shared[0][names[0]], shared[1][names[0]])
