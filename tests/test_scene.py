"""Scene validation: every refused input names its field and the constraint."""

from __future__ import annotations

import pytest
from helpers import free_body

from cayley_heyoka import Scene, SceneError


def refuse(data, field, words):
    with pytest.raises(SceneError) as info:
        Scene.from_dict(data)
    assert info.value.field == field, str(info.value)
    assert words in str(info.value)


@pytest.mark.parametrize(
    "inertia, words",
    [
        ([0, 1, 1], "must be > 0"),
        ([-1, 2, 2], "must be > 0"),
        ([1, 1, 3], "triangle inequality A + B >= C"),
        ([3, 1, 1], "triangle inequality B + C >= A"),
        ([1, 3, 1], "triangle inequality C + A >= B"),
        (["nan", 1, 1], "finite"),
        (["inf", 1, 1], "finite"),
        ([1, 2], "list of 3 numbers"),
    ],
)
def test_bad_inertia(inertia, words):
    field = "body.inertia[0]" if words == "finite" else "body.inertia"
    refuse(free_body(body={"inertia": inertia}), field, words)


def test_flat_body_is_allowed():
    Scene.from_dict(free_body(body={"inertia": [1, 2, 3]}))


@pytest.mark.parametrize("tol", [0, -1e-10, "0"])
def test_tolerance_must_be_positive(tol):
    refuse(free_body(integrator={"tolerance": tol}), "integrator.tolerance", "must be > 0")


@pytest.mark.parametrize("step", [0, -1, "inf"])
def test_max_step_must_be_positive_and_finite(step):
    refuse(free_body(integrator={"max_step": step}), "integrator.max_step", "must be")


def test_unknown_keys_suggest_the_nearest():
    refuse(
        free_body(integrator={"tolerence": 1e-10}),
        "integrator.tolerence",
        "did you mean 'tolerance'",
    )
    refuse(
        free_body(body={"inertia": [1, 2, 2], "inerta": 1}), "body.inerta", "did you mean 'inertia'"
    )
    refuse({**free_body(), "outptu": {}}, "outptu", "did you mean 'output'")


def test_attitude_must_be_a_rotation():
    data = free_body(initial={"rates": [1, 0, 0], "quaternion": [1, 0.1, 0, 0]})
    del data["initial"]["rodrigues"]
    refuse(data, "initial.quaternion", "is not a rotation")
    data = free_body(initial={"rates": [1, 0, 0], "matrix": [[1, 0, 0], [0, 1, 0], [0, 0, -1]]})
    del data["initial"]["rodrigues"]
    refuse(data, "initial.matrix", "is not a rotation")  # a reflection
    data["initial"]["matrix"] = [[1, 0, 0], [0, 1, 0.001], [0, 0, 1]]
    refuse(data, "initial.matrix", "is not a rotation")


def test_output_times_must_increase():
    refuse(free_body(output={"times": [0, 1, 1]}), "output.times", "strictly increasing")
    refuse(free_body(output={"times": [0, 2, 1]}), "output.times", "strictly increasing")
    refuse(
        free_body(output={"times": {"start": 1, "stop": 0, "count": 3}}), "output.times", "greater"
    )
    refuse(
        free_body(output={"times": {"start": 0, "stop": 1, "count": 0}}),
        "output.times.count",
        ">= 1",
    )


def test_other_refusals():
    refuse(
        free_body(integrator={"precision": "single"}), "integrator.precision", "'double', 'quad'"
    )
    refuse(free_body(integrator={"precision": {"bits": 10}}), "integrator.precision.bits", ">= 64")
    refuse(free_body(attitude={"formulation": "euler"}), "attitude.formulation", "must be one of")
    refuse(free_body(attitude={"max_chart_angle": 180}), "attitude.max_chart_angle", "[1, 180)")
    refuse(
        free_body(
            forces={"heavy_top": {"weight": 1, "center_of_mass": [0, 0, 1], "up": [0, 0, 2]}}
        ),
        "forces.heavy_top.up",
        "unit vector",
    )
    refuse(free_body(forces={"magnetic": {}}), "forces.magnetic", "unknown key")
    refuse({"output": {"times": [0, 1]}}, "scene", "names no model family")


def test_expression_errors_name_the_field():
    from cayley_heyoka import run

    bad = free_body(forces={"potential": {"V": "lambda + foo"}})
    with pytest.raises(SceneError, match="forces.potential.V: unknown name 'foo'"):
        run(Scene.from_dict(bad))
    bad = free_body(forces={"potential": {"V": "__import__('os')"}})
    with pytest.raises(SceneError, match="unknown function '__import__'"):
        run(Scene.from_dict(bad))
    bad = free_body(output={"events": ["nope"]})
    with pytest.raises(SceneError, match="unknown event 'nope'"):
        run(Scene.from_dict(bad))


def test_decimal_text_is_kept_from_toml():
    scene = Scene.from_toml(
        """
        [body]
        inertia = [1.0, 1.5, 2.5]
        [initial]
        rates = [0.1, 0.2, 0.3]
        [output]
        times = { start = 0.0, stop = 1.0, count = 2 }
        """
    )
    assert scene.model.rates == ("0.1", "0.2", "0.3")
    assert scene.model.formulation == "none"
