"""Structure once, numbers many (cayley_heyoka.core.structures): a scene of a structure already
built takes its model from that structure and its own numbers, and that model is the one a
full build of the scene gives — expressions, initial state and every parameter, exactly."""

from __future__ import annotations

import copy

import numpy as np
import pytest
from helpers import assert_second_scene_filled, runs_shared_and_alone, with_value, with_values

import cayley_heyoka as ch
from cayley_heyoka.core import structures
from cayley_heyoka.core.families import FAMILIES
from cayley_heyoka.core.model import Numbers
from cayley_heyoka.core.structures import model_for, structure_of

TIMES = {"start": "0", "stop": "2", "count": 3}
FREE = {
    "body": {"inertia": ["1", "1.5", "2.5"]},
    "initial": {"rates": ["0.3", "1", "0.5"], "quaternion": ["1", "0", "0", "0"]},
    "output": {"times": TIMES},
}
TOP = {"weight": "0.2", "center_of_mass": ["0", "0.1", "0.3"], "up": ["0", "0.6", "0.8"]}

#: (structure, the fields whose numbers the second scene changes and their new values)
CASES = {
    "quaternion": (
        {**FREE, "attitude": {"formulation": "quaternion"}},
        {("body", "inertia"): ["1.25", "1.75", "2"], ("initial", "rates"): ["-0.1", "0", "2"]},
    ),
    "quaternion, plane events": (
        {**FREE, "output": {"times": TIMES, "events": ["invariable_plane"]}},
        {("initial", "quaternion"): ["0.5", "0.5", "0.5", "-0.5"]},
    ),
    "rodrigues past the first chart, plane events": (
        {
            **FREE,
            "attitude": {"formulation": "rodrigues", "max_chart_angle": "120"},
            "output": {"times": TIMES, "events": ["invariable_plane"]},
        },
        # 170° from the identity: outside the first chart, so the base is the attitude.
        {("initial", "quaternion"): ["0.0871557427476582", "0.9961946980917455", "0", "0"]},
    ),
    "rodrigues, heavy top": (
        {**FREE, "attitude": {"formulation": "rodrigues"}, "forces": {"heavy_top": TOP}},
        {("forces", "heavy_top", "up"): ["1", "0", "0"], ("forces", "heavy_top", "weight"): "3"},
    ),
    "quaternion, gravity gradient and a potential": (
        {
            **FREE,
            "forces": {
                "gravity_gradient": {"gm": "1", "distance": "4", "direction": ["1", "0", "0"]},
                "potential": {"V": "0.01*R33 + 0.125*lambda*mu"},
            },
        },
        {("forces", "gravity_gradient", "direction"): ["0", "0.6", "-0.8"]},
    ),
    "rates only, Ψ": (
        {
            "body": FREE["body"],
            "initial": {"rates": ["0.3", "1", "0.5"]},
            "output": {"times": TIMES, "invariable_angle": True},
        },
        {("initial", "rates"): ["0.7", "-0.2", "0.1"]},
    ),
    "poisson with its azimuth": (
        {
            **FREE,
            "attitude": {"formulation": "poisson"},
            "forces": {"heavy_top": TOP},
            "output": {"times": TIMES, "azimuth": True},
        },
        {("forces", "heavy_top", "center_of_mass"): ["0.2", "0", "0.1"]},
    ),
    "user events and monitors, quad": (
        {
            **FREE,
            "events": {"spin": {"expression": "r - 0.45", "direction": "down"}},
            "monitors": {"spin2": {"expression": "r*r + 0.5", "conserved": False}},
            "output": {"times": TIMES, "events": ["spin"]},
            "integrator": {"precision": "quad"},
        },
        {("initial", "rates"): ["0.1", "0.2", "0.3"]},
    ),
}


@pytest.mark.parametrize("case", CASES)
def test_a_second_scene_of_a_structure_is_filled_with_its_own_numbers(case):
    assert_second_scene_filled(*CASES[case])


def test_numbers_compiled_in_name_another_structure():
    # A reduced body's forces' direction is compiled into its equations (its zero components
    # drop terms): another direction is another structure.
    base, _ = CASES["poisson with its azimuth"]
    other = with_value(base, ("forces", "heavy_top", "up"), ["0", "0", "1"])
    a, b = ch.Scene.from_dict(copy.deepcopy(base)), ch.Scene.from_dict(other)
    assert structure_of(a) != structure_of(b)
    assert model_for(a).code_key != model_for(b).code_key


def test_numbers_a_structure_refuses_are_refused_by_field():
    structures.clear()
    base, _ = CASES["quaternion, plane events"]
    model_for(ch.Scene.from_dict(copy.deepcopy(base)))
    rest = ch.Scene.from_dict(with_value(base, ("initial", "rates"), ["0", "0", "0"]))
    with pytest.raises(ch.SceneError, match="output.events.*angular momentum L is 0"):
        model_for(rest)


def test_a_family_whose_numbers_disagree_with_its_build_is_an_error(monkeypatch):
    structures.clear()
    base, changes = CASES["quaternion"]
    model_for(ch.Scene.from_dict(copy.deepcopy(base)))
    family = FAMILIES["rotation"]
    honest = family.numbers

    def off_by_one(scene):
        given = honest(scene)
        return Numbers(given.initial_state, {**given.values, "A": "7"})

    monkeypatch.setattr(type(family), "numbers", property(lambda self: off_by_one))
    with pytest.raises(RuntimeError, match="numbers disagree with its build.*'A'"):
        model_for(ch.Scene.from_dict(with_values(base, changes)))


def test_members_of_one_structure_run_as_their_own_scenes():
    # A chart re-based with its invariable-plane events: the handler recomputes the momentum
    # in the new base from the member's own numbers (its parameters), not the first member's.
    base, _ = CASES["rodrigues past the first chart, plane events"]
    base = with_value(base, ("output", "times"), {"start": "0", "stop": "20", "count": 5})
    docs = [
        with_value(base, ("initial", "rates"), rates)
        for rates in (["0.3", "1", "0.5"], ["-0.4", "0.2", "1.5"], ["1.1", "-0.3", "0.2"])
    ]
    shared, alone = runs_shared_and_alone(docs)
    for a, b in zip(shared, alone, strict=True):
        assert a.counters == b.counters and a.counters["rebasings"] > 0
        np.testing.assert_array_equal(a.variables["qw"], b.variables["qw"])
        crossings = a.events["invariable_plane"].time
        assert len(crossings) > 0
        np.testing.assert_array_equal(crossings, b.events["invariable_plane"].time)
