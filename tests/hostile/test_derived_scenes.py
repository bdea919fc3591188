"""Hostile paths into the one mechanism that makes a scene from another (``Scene.derive``,
``core/scene_dicts.py``): the paths a study sweeps and those a caller derives with. Every
refusal names the field or the parameter; nothing escapes as Python's own error, and the
scene derived from is never changed.
"""

from __future__ import annotations

import pytest
from test_more import _study
from test_scenes import small

from cayley_heyoka import Scene, SceneError

LONG_INDEX = "initial.rates[" + "9" * 5000 + "]"  # int() of it: Python's digit limit


@pytest.mark.covers("verb:sweep", "study-key:sweep.parameters")
@pytest.mark.parametrize(
    ("path", "words"),
    [
        (LONG_INDEX, "over 256"),
        ("initial.rates[" + "9" * 19 + "]", "dotted scene path"),
        ("initial." + "x" * 300, "over 256"),
        ("initial..rates", "dotted scene path"),
        ("", "dotted scene path"),
    ],
)
def test_a_swept_path_the_parser_refuses_refuses_the_study(hostile, path, words):
    study = _study(hostile, {"kind": "grid", "parameters": {path: [0.1, 0.2]}})
    hostile.run(["sweep", str(study)], expect="refused", field=words, seconds=10)


D: dict = {}
D["d"] = D  # a value that contains itself

CASES = [
    ({"": 1}, (), "changes", "dotted scene path"),
    ({5: 1}, (), "changes", "as text, got int"),
    ({LONG_INDEX: 1}, (), "changes", "over 256"),
    ({".".join(["a"] * 100_000): 1}, (), "changes", "over 256"),
    ({"initial.rates[7]": 1}, (), "initial.rates[7]", "out of range"),
    ({"initial.rates.x": 1}, (), "initial.rates", "is a list"),
    ({"title.x": 1}, (), "title", "must be a table"),
    ({"integrator.max_steps": D}, (), "integrator.max_steps", "must be an integer"),
    ({"integrator.tolerance": float("nan")}, (), "integrator.tolerance", "not finite"),
    ([("integrator.max_steps", 5)], (), "changes", "must be a table of paths"),
    ({}, "events", "drop", "must be a list of paths"),  # a tired user's drop="events"
    ({}, None, "drop", "must be a list of paths"),
    ({}, [5], "drop", "as text, got int"),
    ({}, ["initial.rates[0]"], "initial.rates[0]", "not a list entry"),
]


@pytest.mark.parametrize(("changes", "drop", "field", "words"), CASES)
def test_a_hostile_derivation_is_refused_by_name_and_leaves_its_scene_alone(
    changes, drop, field, words
):
    scene = Scene.from_dict(small("free_body"))
    before = scene.to_dict()
    with pytest.raises(SceneError, match=words) as caught:
        scene.derive(changes, drop=drop)
    assert caught.value.field == field
    assert scene.to_dict() == before
