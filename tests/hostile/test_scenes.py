"""Hostile scenes: every case is refused (exit 2, one ``error:`` line naming the field),
stopped cleanly with its results (exit 1 / 130) or run correctly (exit 0) — see conftest.py.

Most cases are generated from the bundled examples: each numeric leaf given a value of the
wrong type or a non-finite one, each table given an unknown or misspelt key or replaced by a
non-table. The rest are the classes of issue 15 §2, one case or more each.
"""

from __future__ import annotations

import re
import signal
import tomllib
from pathlib import Path
from typing import Any

import pytest
from conftest import Raw, toml
from helpers import with_value

from cayley_heyoka import load_result
from cayley_heyoka.core import scene as scene_module

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
NAMES = sorted(p.stem for p in EXAMPLES.glob("*.toml"))


def example(name: str) -> dict[str, Any]:
    """A bundled scene, floats kept as typed."""
    return tomllib.loads((EXAMPLES / f"{name}.toml").read_text(), parse_float=Raw)


def small(name: str) -> dict[str, Any]:
    """A bundled scene over a short span (so that accepted mutations run fast)."""
    data = example(name)
    data["output"]["times"] = {"start": Raw("0.0"), "stop": Raw("1.0"), "count": 3}
    return data


def _leaves(data: Any, path: tuple = ()) -> list[tuple]:
    """Paths of the numeric leaves (skipping output.times, generated separately)."""
    if isinstance(data, dict):
        return [p for k, v in data.items() for p in _leaves(v, (*path, k))]
    if isinstance(data, list):
        return [p for i, v in enumerate(data) for p in _leaves(v, (*path, i))]
    numeric = isinstance(data, Raw | int) and not isinstance(data, bool)
    return [path] if numeric and path[:2] != ("output", "times") else []


def _tables(data: Any, path: tuple = ()) -> list[tuple]:
    if not isinstance(data, dict):
        return []
    out = [path] if path else []
    return out + [p for k, v in data.items() for p in _tables(v, (*path, k))]


def _field(path: tuple) -> str:
    """The dotted field of a path, up to its first list index (errors name that far)."""
    parts = []
    for key in path:
        if isinstance(key, int):
            break
        parts.append(key)
    return ".".join(parts)


BAD_NUMBERS = [
    ("text", "abc"),
    ("bool", True),
    ("nan", Raw("nan")),
    ("inf", Raw("inf")),
    ("-inf", Raw("-inf")),
    ("table", {}),
    ("list", []),
    ("empty", ""),
    ("huge-exponent", Raw("1e999999999")),
    ("tiny-exponent", Raw("-1e-999999999")),
]


def _number_cases() -> list:
    cases = []
    for name in NAMES:
        for j, path in enumerate(_leaves(example(name))):
            for k in range(2):  # two bad values per leaf, rotating through the list
                label, value = BAD_NUMBERS[(2 * j + k + len(name)) % len(BAD_NUMBERS)]
                ident = f"{name}-{'.'.join(map(str, path))}-{label}"
                cases.append(pytest.param(name, path, value, id=ident))
    return cases


@pytest.mark.parametrize(("name", "path", "value"), _number_cases())
def test_numeric_leaf_of_wrong_type_or_not_finite(hostile, name, path, value):
    scene = hostile.scene(with_value(small(name), path, value))
    hostile.run(["run", str(scene), "--no-progress"], expect="refused", field=_field(path))


def _other_leaves(data: Any, path: tuple = ()) -> list[tuple]:
    """Paths of the text and boolean leaves."""
    if isinstance(data, dict):
        return [p for k, v in data.items() for p in _other_leaves(v, (*path, k))]
    if isinstance(data, list):
        return [p for i, v in enumerate(data) for p in _other_leaves(v, (*path, i))]
    text = isinstance(data, str) and not isinstance(data, Raw)
    return [path] if text or isinstance(data, bool) else []


def _other_cases() -> list:
    return [
        pytest.param(name, path, id=f"{name}-{'.'.join(map(str, path))}")
        for name in NAMES
        for path in _other_leaves(example(name))
    ]


@pytest.mark.parametrize(("name", "path"), _other_cases())
def test_text_or_boolean_leaf_given_a_number(hostile, name, path):
    """A number where text or true/false belongs (a title, a precision, a formulation, an
    event name, an expression, a switch)."""
    data = small(name)
    value = 42
    if path[-1] == "formulation" and "orbit" in path:
        value = Raw("0.5")
    scene = hostile.scene(with_value(data, path, value))
    hostile.run(["run", str(scene), "--no-progress"], expect="refused", field=_field(path))


def _table_cases() -> list:
    cases = []
    for name in NAMES:
        for path in _tables(example(name)):
            ident = f"{name}-{'.'.join(map(str, path))}"
            cases.append(pytest.param(name, path, "unknown", id=f"{ident}-unknown"))
            cases.append(pytest.param(name, path, "not-a-table", id=f"{ident}-not-a-table"))
    return cases


@pytest.mark.parametrize(("name", "path", "how"), _table_cases())
def test_table_with_unknown_key_or_not_a_table(hostile, name, path, how):
    data = small(name)
    node = data
    for key in path:
        node = node[key]
    if how == "unknown":
        node["colour"] = "red"
        field = ".".join([*path, "colour"]) if path != ("output", "times") else "output.times"
    else:
        data = with_value(data, path, "a string")
        field = path[0]
    scene = hostile.scene(data)
    hostile.run(["run", str(scene), "--no-progress"], expect="refused", field=field)


@pytest.mark.parametrize("name", NAMES)
def test_misspelt_key_gets_a_suggestion(hostile, name):
    data = small(name)
    data["output"]["time"] = data["output"].pop("times")
    scene = hostile.scene(data)
    o = hostile.run(["run", str(scene), "--no-progress"], expect="refused", field="output.time")
    assert "did you mean 'times'" in o.error_line


@pytest.mark.parametrize("name", NAMES)
def test_examples_run_over_a_short_span(hostile, tmp_path, name):
    out = tmp_path / "r.h5"
    scene = hostile.scene(small(name))
    hostile.run(["run", str(scene), "--out", str(out), "--no-progress"], expect="done", out=out)


# ---------------------------------------------------------------------- output times
TIMES = [
    ("count-zero", {"start": 0, "stop": 1, "count": 0}, "output.times.count"),
    ("count-negative", {"start": 0, "stop": 1, "count": -5}, "output.times.count"),
    ("count-float", {"start": 0, "stop": 1, "count": Raw("2.5")}, "output.times.count"),
    ("count-1e12", {"start": 0, "stop": 1, "count": 10**12}, "output.times.count"),
    ("count-memory", {"start": 0, "stop": 1, "count": 9_000_000}, "output.times"),
    ("stop-before-start", {"start": 1, "stop": 0, "count": 3}, "output.times"),
    ("missing-stop", {"start": 0, "count": 3}, "output.times"),
    ("collapse-double", [Raw("0.1"), Raw("0.10000000000000000001")], "output.times"),
    (
        "collapse-grid",
        {"start": 1, "stop": Raw("1.000000000000000001"), "count": 5},
        "output.times",
    ),
    ("decreasing", [0, 2, 1], "output.times"),
    ("grid-overflow", {"start": Raw("-1e308"), "stop": Raw("1e308"), "count": 3}, "output.times"),
    ("repeated", [0, 1, 1], "output.times"),
    ("empty-list", [], "output.times"),
    ("nan-time", [0, Raw("nan")], "output.times[1]"),
    ("string-times", "soon", "output.times"),
]


@pytest.mark.covers(
    "key:output.times", "key:output.times.start", "key:output.times.stop", "key:output.times.count"
)
@pytest.mark.parametrize(("times", "field"), [pytest.param(t, f, id=i) for i, t, f in TIMES])
def test_output_times(hostile, times, field):
    data = small("free_body")
    data["output"]["times"] = times
    hostile.run(["run", str(hostile.scene(data)), "--no-progress"], expect="refused", field=field)


# ---------------------------------------------------------------------- integrator
INTEGRATOR = [
    ("tolerance-1e-310", {"tolerance": Raw("1e-310")}, "integrator.tolerance"),
    ("tolerance-1e-50", {"tolerance": Raw("1e-50")}, "integrator.tolerance"),
    ("tolerance-zero", {"tolerance": 0}, "integrator.tolerance"),
    ("tolerance-negative", {"tolerance": Raw("-1e-10")}, "integrator.tolerance"),
    ("tolerance-word", {"tolerance": "tight"}, "integrator.tolerance"),
    ("tolerance-one", {"tolerance": 1}, "integrator.tolerance"),
    ("max-step-1e-300", {"max_step": Raw("1e-300")}, "integrator.max_step"),
    ("max-step-zero", {"max_step": 0}, "integrator.max_step"),
    ("max-steps-zero", {"max_steps": 0}, "integrator.max_steps"),
    ("max-steps-float", {"max_steps": Raw("1e6")}, "integrator.max_steps"),
    ("max-steps-text", {"max_steps": "many"}, "integrator.max_steps"),
    ("precision-name", {"precision": "octuple"}, "integrator.precision"),
    ("precision-bits-small", {"precision": {"bits": 8}}, "integrator.precision"),
    ("precision-bits-huge", {"precision": {"bits": 1_000_000}}, "integrator.precision"),
    ("compact-mode", {"compact_mode": "sometimes"}, "integrator.compact_mode"),
    ("high-accuracy", {"high_accuracy": "yes"}, "integrator.high_accuracy"),
]


@pytest.mark.covers(
    "key:integrator.precision",
    "key:integrator.tolerance",
    "key:integrator.compact_mode",
    "key:integrator.max_step",
)
@pytest.mark.parametrize(("options", "field"), [pytest.param(o, f, id=i) for i, o, f in INTEGRATOR])
def test_integrator_options(hostile, options, field):
    data = small("free_body")
    data["integrator"] = {**data["integrator"], **options}
    hostile.run(["run", str(hostile.scene(data)), "--no-progress"], expect="refused", field=field)


def test_tolerance_at_epsilon_runs(hostile):
    data = small("free_body")
    data["integrator"]["tolerance"] = Raw("2.220446049250313e-16")
    hostile.run(["run", str(hostile.scene(data)), "--no-progress"], expect="done")


@pytest.mark.covers("key:output.times.stop")
@pytest.mark.parametrize("stop", ["1e300", "1e6"])
def test_a_span_far_beyond_the_step_budget_is_refused(hostile, stop):
    data = small("free_body")
    data["output"]["times"] = {"start": 0, "stop": Raw(stop), "count": 11}
    data["integrator"]["max_steps"] = 2000
    o = hostile.run(
        ["run", str(hostile.scene(data)), "--no-progress"], expect="refused", field="output.times"
    )
    assert "more than 10 times the step budget" in o.error_line


@pytest.mark.covers("key:integrator.max_steps", "option:run --out")
def test_step_budget_stops_a_run_and_keeps_its_results(hostile, tmp_path):
    data = small("free_body")
    data["output"]["times"] = {"start": 0, "stop": Raw("1500"), "count": 11}
    data["integrator"]["max_steps"] = 2000
    out = tmp_path / "r.h5"
    o = hostile.run(
        ["run", str(hostile.scene(data)), "--out", str(out), "--no-progress"],
        expect="stopped",
        out=out,
    )
    assert "integrator.max_steps = 2000" in o.error_line
    result = load_result(out)
    assert result.counters["steps"] == 2000 and not result.success and len(result.t) >= 1


# ---------------------------------------------------------------------- model values
MODEL = [
    ("zero-rates-plane", "free_body", ("initial", "rates"), [0, 0, 0], "output.events", "L is 0"),
    (
        "rodrigues-1e300",
        "free_body",
        ("initial", "rodrigues"),
        [Raw("1e300"), 0, 0],
        "initial.rodrigues",
        "overflows",
    ),
    (
        "moments-overflow-energy",
        "free_body",
        ("body", "inertia"),
        [Raw("1e307"), Raw("1.5e307"), Raw("2.5e307")],
        "body.inertia",
        "overflow",
    ),
    ("moments-zero", "free_body", ("body", "inertia"), [0, 1, 1], "body.inertia", "> 0"),
    ("moments-triangle", "free_body", ("body", "inertia"), [1, 1, 3], "body.inertia", "triangle"),
    ("rates-short", "free_body", ("initial", "rates"), [1, 2], "initial.rates", "3 numbers"),
    (
        "chart-angle-1e-300",
        "heavy_top",
        ("attitude", "max_chart_angle"),
        Raw("1e-300"),
        "attitude.max_chart_angle",
        "[1,",
    ),
    ("chart-angle-180", "heavy_top", ("attitude", "max_chart_angle"), 180, "attitude", ""),
    ("formulation", "heavy_top", ("attitude", "formulation"), "euler", "attitude.formulation", ""),
    ("weight-nan", "heavy_top", ("forces", "heavy_top", "weight"), Raw("nan"), "forces", ""),
    ("up-not-unit", "heavy_top", ("forces", "heavy_top", "up"), [0, 0, 2], "forces", ""),
    ("mu-zero", "orbit_j2_third_body", ("orbit", "mu"), 0, "orbit.mu", ""),
    ("encke-hyperbola", "orbit_j2_third_body", ("orbit", "velocity"), [0, 3, 0], "orbit", "e ="),
    ("position-origin", "orbit_j2_third_body", ("orbit", "position"), [0, 0, 0], "orbit", ""),
    (
        "J2-string",
        "orbit_j2_third_body",
        ("perturbations", "zonal", "J2"),
        "big",
        "perturbations",
        "",
    ),
    (
        "H-divides-by-zero",
        "projectile",
        ("hamiltonian", "H"),
        "varpi1**2/2 + 1/0",
        "hamiltonian.H",
        "1 / 0 divides by zero",
    ),
    ("H-empty", "projectile", ("hamiltonian", "H"), "", "hamiltonian.H", ""),
    ("H-python", "projectile", ("hamiltonian", "H"), "__import__('os')", "hamiltonian.H", ""),
    ("H-lambda-call", "projectile", ("hamiltonian", "H"), "(lambda: 1)()", "hamiltonian.H", ""),
]


@pytest.mark.parametrize(
    ("name", "path", "value", "field", "words"),
    [pytest.param(*case[1:], id=case[0]) for case in MODEL],
)
def test_model_values(hostile, name, path, value, field, words):
    data = small(name)
    if name == "free_body" and path[-1] == "rates":
        data["output"]["events"] = ["invariable_plane"]
    if path[-1] == "velocity":
        data["orbit"]["formulation"] = "encke"
        del data["orbit"]["sigma0"]
    if name == "projectile":  # Hamilton's own function instead of the built-in model
        data["hamiltonian"] = {"H": "varpi1**2/2 + eta1**2/2"}
        data["initial"] = {"eta": [1], "varpi": [0]}
    o = hostile.run(
        ["run", str(hostile.scene(with_value(data, path, value))), "--no-progress"],
        expect="refused",
        field=field,
    )
    assert words in o.error_line


def test_encke_orbit_kicked_out_of_its_ellipse_stops_with_its_results(hostile, tmp_path):
    """A close third body makes the osculating orbit hyperbolic at t ≈ 18: exit 1, the rows
    before kept, the way on named."""
    data = {
        "orbit": {
            "mu": 1,
            "formulation": "encke",
            "position": [1, 0, 0],
            "velocity": [0, Raw("1.3"), Raw("0.01")],
        },
        "perturbations": {
            "third_body": {
                "gm": 3,
                "a": Raw("1.6"),
                "n": Raw("0.5"),
                "inclination": Raw("0.1"),
                "node": 0,
                "mean_longitude0": Raw("0.3"),
            }
        },
        "output": {"times": {"start": 0, "stop": 100, "count": 11}},
    }
    out = tmp_path / "r.h5"
    o = hostile.run(
        ["run", str(hostile.scene(data)), "--out", str(out), "--no-progress"],
        expect="stopped",
        out=out,
    )
    assert "not an ellipse" in o.error_line and "cartesian" in o.error_line
    assert 1 <= len(load_result(out).t) < 11


def test_zero_rates_without_events_run(hostile):
    data = small("free_body")
    data["initial"]["rates"] = [0, 0, 0]
    data["output"]["events"] = []
    hostile.run(["run", str(hostile.scene(data)), "--no-progress"], expect="done")


# ---------------------------------------------------------------------- expressions
def _potential(V: str) -> dict:
    data = small("free_body")
    data["forces"] = {"potential": {"V": V}}
    return data


EXPRESSIONS = [
    ("3000-terms", "+".join(["R33"] * 3000), "operators"),
    ("power-tower", "R33**" * 2500 + "R33", "operators"),
    ("nested-parens", "(" * 300 + "R33" + ")" * 300, "valid"),
    ("nested-calls", "sin(" * 150 + "R33" + ")" * 150, "deeper"),
    ("minus-signs", "-" * 500 + "R33", "deeper"),
    ("very-long", "R33 " + " " * 200_000, "characters"),
    ("unknown-name", "R33 + nothing", "unknown name"),
    ("unknown-function", "gamma(R33)", "unknown function"),
    ("attribute", "R33.real", "unsupported"),
    ("string-literal", "'abc'", "unsupported"),
    ("comparison", "R33 > 1", "unsupported"),
    ("keyword-argument", "sin(x=R33)", "unknown function"),
    ("unbalanced", "(R33", "valid"),
    ("newline", "R33\n+ 1\n)", "valid"),
]


@pytest.mark.covers("key:forces.potential.V")
@pytest.mark.parametrize(("V", "words"), [pytest.param(v, w, id=i) for i, v, w in EXPRESSIONS])
def test_expressions(hostile, V, words):
    scene = hostile.scene(_potential(V))
    o = hostile.run(["run", str(scene), "--no-progress"], expect="refused", field="forces")
    assert words in o.error_line


def test_large_expression_under_the_limits_runs(hostile):
    V = " + ".join(f"{k}e-4*R33*R13" for k in range(1, 600))  # 1197 operators
    hostile.run(["run", str(hostile.scene(_potential(V))), "--no-progress"], expect="done")


@pytest.mark.covers("key:events.*.expression")
def test_expression_over_the_limit_in_a_user_event(hostile):
    data = small("free_body")
    data["events"] = {"deep": {"expression": "+".join(["p"] * 2500)}}
    data["output"]["events"] = ["deep"]
    hostile.run(["run", str(hostile.scene(data)), "--no-progress"], expect="refused", field="deep")


# ---------------------------------------------------------------------- files
FILES = [
    ("latin-1", 'title = "Poincaré"\n'.encode("latin-1")),
    ("utf-16", 'title = "x"\n'.encode("utf-16")),
    ("binary", bytes(range(256)) * 4),
    ("nul-bytes", b'title = "a\x00b"\n'),
    ("empty", b""),
    ("not-toml", b"this is not toml\n"),
    ("deep-lists", ("a = " + "[" * 5000 + "]" * 5000 + "\n").encode()),
    ("deep-tables", ("a = " + "{b = " * 3000 + "1" + "}" * 3000 + "\n").encode()),
    ("deep-but-parsable", ("a = " + "[" * 40 + "]" * 40 + "\n").encode()),
    ("dotted-deep", ("a" + ".a" * 3000 + " = 1\n").encode()),
]


@pytest.mark.covers("option:run scene", "option:check scene", "option:reference scene")
@pytest.mark.parametrize("content", [pytest.param(c, id=i) for i, c in FILES])
@pytest.mark.parametrize("verb", ["run", "check", "reference"])
def test_scene_file_that_is_not_a_scene(hostile, tmp_path, content, verb):
    scene = hostile.scene(content)
    hostile.run(_argv(verb, scene, tmp_path), expect="refused", field=str(scene))


def _argv(verb: str, path: Path, tmp_path: Path) -> list[str]:
    if verb == "reference":
        return [verb, str(path), "--digits", "10", "--out", str(tmp_path / "ref.h5")]
    return [verb, str(path)]


@pytest.mark.covers(
    "option:run scene", "option:check scene", "option:reference scene", "option:sweep study"
)
@pytest.mark.parametrize("verb", ["run", "check", "reference", "sweep"])
@pytest.mark.parametrize("where", ["missing", "directory"])
def test_scene_path_missing_or_a_directory(hostile, tmp_path, verb, where):
    path = tmp_path / "nothing.toml" if where == "missing" else tmp_path
    argv = _argv(verb, path, tmp_path)
    words = "no such file" if where == "missing" else "is a directory"
    o = hostile.run(argv, expect="refused", field=str(path))
    assert words in o.error_line


@pytest.mark.covers("option:sweep study", "study-key:scene")
@pytest.mark.parametrize("content", ["binary", "missing-scene", "deep"])
def test_study_that_cannot_be_read(hostile, tmp_path, content):
    study = tmp_path / "study.toml"
    if content == "binary":
        study.write_bytes(bytes(range(256)))
    elif content == "missing-scene":
        study.write_text(
            'scene = "nowhere.toml"\n[sweep]\nkind = "grid"\n'
            '[sweep.parameters]\n"initial.rates[0]" = [0.1, 0.2]\n'
        )
    else:
        study.write_text("a = " + "[" * 3000 + "]" * 3000 + "\n")
    hostile.run(["sweep", str(study), "--no-progress"], expect="refused", field=str(study))


def test_scene_larger_than_the_limit(hostile, monkeypatch):
    monkeypatch.setattr(scene_module, "MAX_SCENE_BYTES", 1000)
    scene = hostile.scene(toml(small("free_body")) + "# " + "x" * 2000 + "\n")
    o = hostile.run(["run", str(scene), "--no-progress"], expect="refused", field=str(scene))
    assert "more than 1000" in o.error_line


# ---------------------------------------------------------------------- signals
LONG = {
    "body": {"inertia": [1, Raw("1.5"), Raw("2.5")]},
    "initial": {"rates": [Raw("0.125"), Raw("0.25"), 1], "rodrigues": [Raw("0.1"), 0, 0]},
    "output": {"times": {"start": 0, "stop": Raw("1e6"), "count": 101}},
}


@pytest.mark.covers("verb:run", "option:run --progress", "signal:run")
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_signal_during_a_run_keeps_its_results(hostile, tmp_path, sig):
    """A run of ~30 s signalled once its progress bar shows 1 %: exit 130 within seconds,
    the result file written and marked interrupted."""
    out = tmp_path / "r.h5"
    o = hostile.process(
        ["run", str(hostile.scene(LONG)), "--out", str(out), "--progress"],
        send=sig,
        wait_for=re.compile(r"\b[1-9]\d*%"),
        expect="interrupted",
        out=out,
        seconds=60,
    )
    assert f"interrupted ({signal.Signals(sig).name})" in o.stderr
    result = load_result(out)
    assert result.status != 0 and "interrupted" in result.message and len(result.t) >= 1


# ---------------------------------------------------------------------- every verb
def _collapsing() -> dict:
    data = small("free_body")
    data["output"]["times"] = [Raw("0.1"), Raw("0.10000000000000000001"), 1]
    return data


def _infinite_energy() -> dict:
    return {
        "hamiltonian": {"H": "varpi1**2/2 + eta1**2/2 + 1/0"},
        "initial": {"eta": [1], "varpi": [0]},
        "output": {"times": [0, 1]},
    }


@pytest.mark.covers("verb:run", "verb:check", "verb:reference")
@pytest.mark.parametrize("verb", ["run", "check", "reference"])
@pytest.mark.parametrize(
    ("build", "field"),
    [(_collapsing, "output.times"), (_infinite_energy, "hamiltonian.H")],
    ids=["times-collapse", "energy-infinite"],
)
def test_refusals_found_when_the_model_is_built_reach_every_verb(
    hostile, tmp_path, verb, build, field
):
    scene = hostile.scene(build())
    o = hostile.run(_argv(verb, scene, tmp_path), expect="refused", field=field)
    assert str(scene) in o.error_line


def test_study_whose_scene_times_collapse(hostile, tmp_path):
    (tmp_path / "collapse.toml").write_text(toml(_collapsing()))
    study = hostile.scene(
        'scene = "collapse.toml"\n[sweep]\nkind = "grid"\n'
        '[sweep.parameters]\n"initial.rates[0]" = [0.1, 0.2]\n'
    )
    hostile.run(["sweep", str(study), "--no-progress"], expect="refused", field="output.times")
