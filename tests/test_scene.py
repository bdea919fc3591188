"""Scene validation: every refused input names its field and the constraint."""

from __future__ import annotations

from pathlib import Path

import heyoka as hy
import numpy as np
import pytest
from helpers import free_body

from cayley_heyoka import Precision, Scene, SceneError, load_scene
from cayley_heyoka.core.expressions import parse_expression
from cayley_heyoka.core.model import ParTable
from cayley_heyoka.core.scene import DEFAULT_MAX_STEPS


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
    # A study given where a scene is expected: the verb that takes it.
    refuse({"scene": "s.toml", "sweep": {"kind": "grid"}}, "scene", "cayley-heyoka sweep")


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


@pytest.mark.parametrize(
    ("prec", "tol", "ok"),
    [
        ("double", "2.220446049250313e-16", True),  # epsilon's shortest text
        ("double", "1e-18", True),  # below epsilon: measured to pay for Encke's formulation
        ("double", "2.220446049250313e-22", True),  # the floor, 1e-6 epsilon
        ("double", "2.2e-22", False),
        ("double", "1e-310", False),
        ("quad", "1e-39", True),
        ("quad", "1e-41", False),
        ({"bits": 256}, "1e-82", True),
        ({"bits": 256}, "1e-84", False),
    ],
)
def test_tolerance_not_far_below_epsilon(prec, tol, ok):
    data = free_body(integrator={"precision": prec, "tolerance": tol})
    if ok:
        Scene.from_dict(data)
    else:
        refuse(data, "integrator.tolerance", "raise the precision")


@pytest.mark.parametrize(
    ("budget", "ok"),
    [(1, True), (10**12, True), (10**18, True), (0, False), (True, False), (10**18 + 1, False)],
)
def test_step_budget(budget, ok):
    data = free_body(integrator={"max_steps": budget})
    if ok:
        assert Scene.from_dict(data).integrator.max_steps == budget
    else:
        refuse(data, "integrator.max_steps", "integer in 1 … 10^18")


def test_step_budget_default():
    assert Scene.from_dict(free_body()).integrator.max_steps == DEFAULT_MAX_STEPS == 10**9


def test_output_times_distinct_only_once_rounded():
    """Refused when the scene is loaded, in its precision: the checked grid is the one every
    verb uses (Scene.time_grid)."""
    close = ["0.1", "0.10000000000000000001"]
    with pytest.raises(SceneError, match=r"output.times: .* in double: times \[0\] and \[1\]"):
        Scene.from_dict(free_body(output={"times": close}))
    quad = Scene.from_dict(free_body(output={"times": close}, integrator={"precision": "quad"}))
    assert len(quad.time_grid) == 2 and quad.time_grid[0] < quad.time_grid[1]
    with pytest.raises(SceneError, match="output.times"):
        quad.output.time_grid(Precision("double"))
    grid = free_body(output={"times": {"start": "1", "stop": "1.0000000000000000001", "count": 3}})
    with pytest.raises(SceneError, match="output.times"):
        Scene.from_dict(grid)


def test_too_many_output_times():
    refuse(
        free_body(output={"times": {"start": 0, "stop": 1, "count": 10**7 + 1}}),
        "output.times.count",
        "at most",
    )


@pytest.mark.parametrize(
    ("content", "words"),
    [
        (None, "no such file"),
        ("directory", "is a directory"),
        ("Poincaré".encode("latin-1"), "must be UTF-8"),
        (b"[body\n", "not valid TOML"),
        (("a = " + "[" * 3000 + "]" * 3000).encode(), "nested deeper than 16"),
        (("a = " + "[" * 20 + "]" * 20).encode(), "nested deeper than 16"),
    ],
)
def test_load_scene_refuses_what_is_not_a_scene_file(tmp_path, content, words):
    path = tmp_path / "scene.toml"
    if content == "directory":
        path.mkdir()
    elif content is not None:
        path.write_bytes(content)
    with pytest.raises(SceneError) as info:
        load_scene(path)
    assert info.value.field == "scene" and words in info.value.constraint


def test_load_scene_reads_an_example():
    scene = load_scene(Path(__file__).resolve().parent.parent / "examples" / "free_body.toml")
    assert scene.family == "rotation"


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("+".join(["p"] * 2002), "more than 2000"),
        ("-" * 101 + "p", "deeper than 100"),
        ("sin(" * 101 + "p" + ")" * 101, "deeper than 100"),
        ("p**" * 101 + "p", "deeper than 100"),
        ("p" + " " * 100_000, "longer than 100000"),
    ],
    ids=["operators", "signs", "calls", "powers", "characters"],
)
def test_expression_limits(text, words):
    with pytest.raises(SceneError, match=words):
        parse_expression(text, {"p": hy.make_vars("p")}, ParTable(), "forces.potential.V")


def test_long_sums_are_folded_as_python_would():
    """1000 terms (1999 operators): built without recursion, the same expression as folding
    left to right."""
    p, q = hy.make_vars("p", "q")
    text = " + ".join(f"{k}*p - q/{k}" for k in range(1, 501))
    built = parse_expression(text, {"p": p, "q": q}, ParTable(), "V")
    expected = 1.0 * p - q / 1.0
    for k in range(2, 501):
        expected = expected + float(k) * p - q / float(k)
    values = np.array([[0.3], [-1.7]])
    both = hy.cfunc([built, expected], [p, q])(values)
    assert both[0, 0] == both[1, 0]


@pytest.mark.parametrize(
    "start, stop, count", [("0", "10", 1001), ("-3.7", "0.1", 77), ("1e-5", "2e10", 4096)]
)
def test_a_double_grid_is_built_as_each_time_alone_would_be(start, stop, count):
    """The double grid is computed by numpy at once; each time is the one the scene's rule
    gives alone, start + (stop − start)·k/(count − 1) rounded operation by operation."""
    scene = Scene.from_dict(
        free_body(output={"times": {"start": start, "stop": stop, "count": count}})
    )
    p = Precision("double")
    a, b, n = p.number(start), p.number(stop), p.number(count - 1)
    alone = [a + (b - a) * p.number(k) / n for k in range(count)]
    assert scene.output.time_grid(p).tolist() == alone


# ---------------------------------------------------------------------- derived scenes
def test_a_derived_scene_sets_and_drops_fields_and_leaves_its_source_alone():
    data = free_body(
        events={"p_zero": {"expression": "p"}},
        output={"times": {"start": "0", "stop": "3", "count": 4}},
    )
    scene = Scene.from_dict(data)
    derived = scene.derive(
        {"integrator.max_steps": 1000, "output.times": ["0", "1.5"]}, drop=("events", "nowhere.x")
    )
    assert derived.integrator.max_steps == 1000
    assert [float(t) for t in derived.time_grid] == [0.0, 1.5]
    assert not derived.events and "events" not in derived.to_dict()
    assert scene.events and len(scene.time_grid) == 4  # the source scene is as it was
    assert scene.to_dict() == Scene.from_dict(data).to_dict()


def test_a_derived_scene_is_validated_as_one_written_so():
    scene = Scene.from_dict(free_body())
    with pytest.raises(SceneError, match="integrator.tolerance"):
        scene.derive({"integrator.tolerance": "-1"})
    with pytest.raises(SceneError, match="integrator.colour: unknown key"):
        scene.derive({"integrator.colour": "blue"})


def test_a_path_through_a_value_is_refused_by_name():
    scene = Scene.from_dict(free_body()).derive({"integrator.max_steps": 5})
    with pytest.raises(SceneError, match=r"integrator.max_steps: must be a table to set"):
        scene.derive({"integrator.max_steps.deeper": 1})


@pytest.mark.parametrize(
    ("path", "field", "words"),
    [
        ("initial.rates[7]", "initial.rates[7]", "out of range"),
        ("initial.rates.x", "initial.rates", "is a list"),
        ("initial.rates[0][1]", "initial.rates[0]", "must be a table"),
        ("title.x", "title", "must be a table"),
        ("initial..rates", "initial..rates", "dotted scene path"),
    ],
)
def test_a_derived_path_that_does_not_fit_the_scene_is_refused_by_name(path, field, words):
    scene = Scene.from_dict(free_body(title="t"))
    with pytest.raises(SceneError, match=words) as caught:
        scene.derive({path: "1"})
    assert caught.value.field == field


def test_a_derived_index_sets_one_entry_and_leaves_the_source_scene_alone():
    scene = Scene.from_dict(free_body())
    rates = list(scene.to_dict()["initial"]["rates"])
    derived = scene.derive({"initial.rates[1]": "0.125"})
    assert derived.to_dict()["initial"]["rates"] == [rates[0], "0.125", rates[2]]
    assert scene.to_dict()["initial"]["rates"] == rates
