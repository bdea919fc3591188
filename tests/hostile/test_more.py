"""More hostile input, found by fuzzing every verb after issue 15's suite: files that are not
regular files, sizes that only a bound keeps finite (study members, checkpoints, check
options, the step budget), outputs that overflow after the start, event expressions that
cannot cross zero, names given twice. Each case ends as conftest.py requires.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
from conftest import Raw
from test_scenes import small

import cayley_heyoka as ch
from cayley_heyoka import load_result
from cayley_heyoka.core.errors import IntegrationError, SceneError

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
VERBS = ["run", "check", "reference", "sweep", "info", "plot"]


def _argv(verb: str, path: Path, tmp_path: Path) -> list[str]:
    return {
        "run": ["run", str(path)],
        "check": ["check", str(path)],
        "reference": ["reference", str(path), "--digits", "5", "--out", str(tmp_path / "r.h5")],
        "sweep": ["sweep", str(path)],
        "info": ["info", str(path)],
        "plot": ["plot", str(path), "--kind", "drift", "--out", str(tmp_path / "p.png")],
    }[verb]


@pytest.mark.covers(
    "option:run scene",
    "option:check scene",
    "option:reference scene",
    "option:sweep study",
    "option:info result",
    "option:plot file",
)
@pytest.mark.parametrize("verb", VERBS)
@pytest.mark.parametrize("special", ["fifo", "/dev/null", "/dev/zero"])
def test_path_that_is_not_a_regular_file(hostile, tmp_path, verb, special):
    """Opening a FIFO waits for a writer (a hang), /dev/zero never ends: both are refused."""
    if special == "fifo":
        path = tmp_path / "fifo"
        os.mkfifo(path)
    else:
        path = Path(special)
        if not path.exists():
            pytest.skip(f"no {special} here")
    hostile.run(_argv(verb, path, tmp_path), expect="refused", field="not a regular file")


def _study(hostile, sweep: dict) -> Path:
    scene = hostile.scene(small("free_body"))
    return hostile.scene({"title": "s", "scene": str(scene), "sweep": sweep})


HUGE = {"start": 0, "stop": 1, "count": 10**12}
STUDIES = [
    (
        {"kind": "grid", "parameters": {"initial.rates[0]": HUGE}},
        "count: must be at most 1000000",
    ),
    (
        {"kind": "random", "count": 10**12, "seed": 1,
         "parameters": {"initial.rates[0]": {"normal": [0.1, 0.01]}}},
        "sweep.count: must be at most 1000000",
    ),
    (
        {"kind": "grid", "parameters": {
            "initial.rates[0]": {"start": Raw("0.1"), "stop": Raw("0.2"), "count": 1001},
            "body.inertia[0]": {"start": Raw("0.5"), "stop": Raw("0.9"), "count": 1000}}},
        "sweep.parameters: a grid of 1001000 members",
    ),
]  # fmt: skip


@pytest.mark.covers("verb:sweep", "study-key:sweep.count", "study-key:sweep.parameters")
@pytest.mark.parametrize(("sweep", "words"), STUDIES)
def test_study_with_too_many_members_is_refused_before_listing_them(hostile, sweep, words):
    hostile.run(["sweep", str(_study(hostile, sweep))], expect="refused", field=words, seconds=10)


@pytest.mark.covers("option:reference --checkpoints", "option:reference --tolerance")
@pytest.mark.parametrize(
    ("options", "words"),
    [
        (["--checkpoints", str(10**9)], "--checkpoints must be an integer"),
        (["--checkpoints", "0"], "--checkpoints must be an integer"),
        (["--tolerance", "junk"], "--tolerance must be a finite number: 'junk' is not a"),
        (["--tolerance", "1e-5000"], "--tolerance must be a finite number: '1e-5000' is beyond"),
    ],
)
def test_reference_option_out_of_bounds(hostile, tmp_path, options, words):
    scene = hostile.scene(small("projectile"))
    out = tmp_path / "r.h5"
    argv = ["reference", str(scene), "--digits", "10", "--out", str(out), *options]
    hostile.run(argv, expect="refused", field=words, seconds=10)
    assert not out.exists() and not (tmp_path / "r.h5.work").exists()


@pytest.mark.covers("option:check --set")
@pytest.mark.parametrize(
    ("setting", "words"),
    [
        (f"samples={10**6}", "--set samples: must be an integer in 1 … 10000"),
        (f"nodes={10**6}", "--set nodes: must be an integer in 1 … 400"),
        ("samples=-1", "--set samples: must be an integer in 1 … 10000"),
    ],
)
def test_check_option_out_of_bounds(hostile, setting, words):
    scene = EXAMPLES / "top_weakly_forced.toml"
    hostile.run(["check", str(scene), "--set", setting], expect="refused", field=words)


def _potential(V: str, precision: object = "double") -> dict:
    data = small("heavy_top")
    data["forces"] = {"potential": {"V": V}}
    data["integrator"]["precision"] = precision
    data["output"]["times"] = {"start": Raw("0.0"), "stop": Raw("2.0"), "count": 5}
    return data


OVERFLOWING_LATER = [
    ("1/(t - 1)", "double", 1.0),
    ("sqrt(1 - t)", "double", 1.5),
    ("exp(exp(exp(t)))", "double", 2.0),
    ("1/(t - 1)", "quad", 1.0),
    ("log(3/2 - t)", {"bits": 128}, 1.5),
]


@pytest.mark.covers("verb:run", "key:forces.potential.V")
@pytest.mark.parametrize(("V", "precision", "t_bad"), OVERFLOWING_LATER)
def test_output_that_overflows_after_the_start_stops_with_its_rows(
    hostile, tmp_path, V, precision, t_bad
):
    """A force function of t alone leaves the state finite, and the energy not."""
    out = tmp_path / "r.h5"
    scene = hostile.scene(_potential(V, precision))
    o = hostile.run(["run", str(scene), "--out", str(out)], expect="stopped", out=out)
    assert "the monitor energy became non-finite at t = " in o.error_line
    saved = load_result(out)
    assert not saved.success
    assert len(saved.t) and float(saved.t[-1]) < t_bad
    energy = np.asarray(saved.monitors["energy"], dtype=float)
    assert np.all(np.isfinite(energy))


def test_overflow_later_through_the_python_api():
    data = _potential("1/(t - 1)")
    with pytest.raises(IntegrationError, match="energy became non-finite") as info:
        ch.run(ch.Scene.from_dict(data))
    kept = info.value.result
    assert [float(t) for t in kept.t] == [0.0, 0.5]


def _with_event(name: str, expression: str) -> dict:
    data = small(name)
    data["events"] = {"e": {"expression": expression}}
    data["output"]["events"] = ["e"]
    return data


@pytest.mark.covers("key:events.*.expression")
@pytest.mark.parametrize("name", ["free_body", "orbit_j2_third_body", "projectile"])
@pytest.mark.parametrize("expression", ["0", "1/0", "pi", "2.5*3"])
def test_constant_user_event_is_refused(hostile, name, expression):
    """heyoka cannot build an event function that is a number or a parameter (a traceback)."""
    scene = hostile.scene(_with_event(name, expression))
    hostile.run(["run", str(scene)], expect="refused", field="events.e.expression: is constant")


@pytest.mark.covers("key:events.*.expression")
@pytest.mark.parametrize("expression", ["t - 0.5", "qw"])
def test_user_event_on_time_or_state_runs(hostile, expression):
    hostile.run(["run", str(hostile.scene(_with_event("free_body", expression)))], expect="done")


@pytest.mark.covers("key:output.events", "key:output.monitors")
@pytest.mark.parametrize(
    ("key", "names"),
    [("events", ["invariable_plane", "invariable_plane"]), ("monitors", ["energy", "energy"])],
)
def test_name_given_twice_is_refused(hostile, key, names):
    data = small("free_body")
    data["output"][key] = names
    hostile.run(["run", str(hostile.scene(data))], expect="refused", field=f"output.{key}")


@pytest.mark.covers("key:integrator.max_steps")
def test_step_budget_beyond_64_bits_is_refused(hostile):
    data = small("free_body")
    data["integrator"]["max_steps"] = 10**30
    hostile.run(["run", str(hostile.scene(data))], expect="refused", field="integrator.max_steps")


@pytest.mark.parametrize(
    "change",
    [
        ("output", "events", ["invariable_plane", "invariable_plane"]),
        ("integrator", "max_steps", 10**30),
        ("events", None, {"e": {"expression": "0"}}),
    ],
)
def test_python_api_raises_scene_error(change):
    data = small("free_body")
    table, key, value = change
    if key is None:
        data[table] = value
        data["output"]["events"] = ["e"]
    else:
        data[table][key] = value
    with pytest.raises(SceneError):
        ch.run(ch.Scene.from_dict(data))


@pytest.mark.parametrize("precision", ["double", "quad"])
def test_state_that_overflows_in_the_first_step_names_a_time(hostile, tmp_path, precision):
    """heyoka's own time is NaN after such a step: the stop names the last output time kept."""
    data = small("orbit_j2_third_body")
    data["orbit"]["mu"] = Raw("1e300")
    data["integrator"] = {"precision": precision}
    out = tmp_path / "r.h5"
    o = hostile.run(["run", str(hostile.scene(data)), "--out", str(out)], expect="stopped", out=out)
    assert "the state became non-finite after t = 0" in o.error_line
    assert "nan" not in o.error_line


@pytest.fixture
def projectile_result(hostile, tmp_path) -> Path:
    """The projectile at two output times: its energy drift is exactly 0 at the second."""
    out = tmp_path / "projectile.h5"
    hostile.run(["run", str(EXAMPLES / "projectile.toml"), "--out", str(out)], expect="done")
    return out


@pytest.mark.covers("verb:plot", "option:plot --kind")
@pytest.mark.parametrize(
    ("kind", "name", "words"),
    [
        ("drift", "p.png", "series: nothing to draw on log axes"),
        ("drift", "p.weird", "out: p.weird asks for format 'weird'"),
        ("orbit", "p.png", "kind 'orbit' is drawn for orbit results"),
    ],
)
def test_plot_that_cannot_be_drawn_is_refused(
    hostile, projectile_result, tmp_path, kind, name, words
):
    out = tmp_path / name
    argv = ["plot", str(projectile_result), "--kind", kind, "--out", str(out)]
    hostile.run(argv, expect="refused", field=words)
    assert not out.exists()


@pytest.mark.covers("verb:sweep", "option:sweep --out")
@pytest.mark.parametrize("formulation", ["quaternion", "rodrigues"])
def test_sweep_member_whose_output_overflows_later_fails(hostile, tmp_path, formulation):
    """Both sweep paths (heyoka's ensemble for the quaternion form, one run per member for
    Rodrigues' chart with its re-basings) stop a member as a lone run stops."""
    scene = {
        "body": {"inertia": [1.0, 1.5, 2.5]},
        "initial": {"rates": [0.3, 1.0, 0.5]},
        "attitude": {"formulation": formulation},
        "forces": {"potential": {"V": "1/(t - 1) + 0.3*R33"}},
        "output": {"times": {"start": 0.0, "stop": 2.0, "count": 5}},
    }
    study = hostile.scene(
        {"title": "s", "scene": scene,
         "sweep": {"kind": "grid", "parameters": {"initial.rates[0]": [0.1, 0.2]}}}
    )  # fmt: skip
    out = tmp_path / "s.h5"
    o = hostile.run(["sweep", str(study), "--out", str(out)], expect="stopped", out=out)
    assert "0 completed, 2 failed" in o.stdout
    assert o.stdout.count("the monitor energy became non-finite at t = 1.0") == 2


@pytest.mark.parametrize("precision", ["quad", {"bits": 128}])
def test_value_beyond_double_range_is_summarised_not_as_inf(hostile, precision):
    """exp(exp(exp(2))) = 5.831e+702 is finite in quad and MPFR: a correct run, shown as such
    (the energy at t = 2 is that and a kinetic energy of order 1)."""
    data = _potential("exp(exp(exp(t))) + 0.3*R33", precision)
    o = hostile.run(["run", str(hostile.scene(data))], expect="done")
    (line,) = [ln for ln in o.stdout.splitlines() if ln.strip().startswith("energy")]
    assert line.split() == ["energy", "largest", "|value|", "5.831e+702"], line


@pytest.mark.covers("class:11", "option:sweep --workers", "option:sweep --chunk", "study-key:run")
@pytest.mark.parametrize("option", ["--workers", "--chunk"])
def test_a_sweep_names_its_overriding_option_or_its_study_field(hostile, option):
    """A bad count given on the command line names the option; one in the study's ``[run]``
    table names that field (it was ``run (with the command-line options).workers``)."""
    key = option[2:]
    hostile.scene(
        {
            "body": {"inertia": ["1", "1.5", "2.5"]},
            "initial": {"rates": ["0.3", "1", "0.5"]},
            "output": {"times": [0, 1]},
        },
        name="body.toml",
    )
    study = {
        "scene": "body.toml",
        "sweep": {"kind": "grid", "parameters": {"initial.rates[0]": ["0.3", "0.4"]}},
    }
    path = hostile.scene(study, name="study.toml")
    o = hostile.run(["sweep", str(path), option, "0"], expect="refused", field=f"{option}:")
    assert "command-line options" not in o.error_line
    bad = hostile.scene({**study, "run": {key: 0}}, name="bad.toml")
    hostile.run(["sweep", str(bad)], expect="refused", field=f"run.{key}:")
    # The study file itself is invalid: an option does not make it valid.
    hostile.run(["sweep", str(bad), option, "2"], expect="refused", field=f"run.{key}:")
